"""Compiled loops (numba) of the highway's object-wise occlusion handlers
(`occtrack.occlusion.highway`): one pass over the particles each, no temporaries. Imported
only when a handler runs, so that listing the handlers loads no compiler.

Particles arrive flat: angles a_l <= a_r (ends over lane distance), lane, owner track (-1:
the undetected intensity) and weight; the particles of one track are contiguous.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.jit import njit


@njit
def track_extents(owner, lane, weights, a_left, a_right, n):
    """Lane and expected extent (angles) of each of the n tracks."""
    total = np.zeros(n)
    sum_l = np.zeros(n)
    sum_r = np.zeros(n)
    track_lane = np.zeros(n, np.int64)
    for p in range(len(owner)):
        i = owner[p]
        if i < 0:
            continue
        w = weights[p]
        total[i] += w
        sum_l[i] += w * a_left[p]
        sum_r[i] += w * a_right[p]
        track_lane[i] = lane[p]
    tiny = np.finfo(np.float64).tiny
    for i in range(n):
        t = max(total[i], tiny)
        sum_l[i] /= t
        sum_r[i] /= t
    return track_lane, sum_l, sum_r


@njit
def expval_visibility(owner, lane, a_left, a_right, existence, occ_lane, occ_l, occ_r, beta,
                      min_visible):
    """v = max(prod_i (1 - r_i (1 - e^(-beta cover_l)) (1 - e^(-beta cover_r))), v_min) over
    the tracks i of nearer lanes whose expected extent covers both ends' sides. Each run of
    particles sharing owner and lane is tested against an occluder by its hull first."""
    k = len(owner)
    log_open = np.zeros(k)
    start = 0
    while start < k:
        end = start + 1
        while end < k and owner[end] == owner[start] and lane[end] == lane[start]:
            end += 1
        run_lane = lane[start]
        max_l = -np.inf
        min_r = np.inf
        for p in range(start, end):
            max_l = max(max_l, a_left[p])
            min_r = min(min_r, a_right[p])
        for i in range(len(occ_lane)):
            if occ_lane[i] >= run_lane or occ_l[i] >= max_l or occ_r[i] <= min_r:
                continue
            for p in range(start, end):
                cover_l = a_left[p] - occ_l[i]
                cover_r = occ_r[i] - a_right[p]
                if cover_l > 0 and cover_r > 0:
                    hidden = existence[i] * -math.expm1(-beta * cover_l) * -math.expm1(
                        -beta * cover_r)
                    log_open[p] += math.log1p(-min(hidden, 1.0 - 1e-12))
        start = end
    visible = np.empty(k)
    for p in range(k):
        visible[p] = max(math.exp(log_open[p]), min_visible)
    return visible


@njit
def grid_visibility(owner, lane, weights, a_left, a_right, existence, n, n_lanes, c0, step,
                    top, cells):
    """The visibility grid: a cell seen from lane k is open with probability prod_i (1 - r_i
    P(track i covers it)) over the tracks of lanes nearer than k; a particle is as visible as
    the most open cell whose centre it covers (the cell nearest its middle if it covers
    none), 1 outside the grid."""
    k = len(owner)
    first = np.empty(k, np.int64)
    last = np.empty(k, np.int64)
    for p in range(k):
        first[p] = max(math.ceil((a_left[p] - c0) / step), 0)
        last[p] = min(math.floor((a_right[p] - c0) / step), cells - 1)
    diff = np.zeros((n, cells + 1))
    total = np.zeros(n)
    track_lane = np.zeros(n, np.int64)
    for p in range(k):
        i = owner[p]
        if i < 0:
            continue
        total[i] += weights[p]
        track_lane[i] = lane[p]
        if first[p] <= last[p]:
            diff[i, first[p]] += weights[p]
            diff[i, last[p] + 1] -= weights[p]
    log_open = np.zeros((n_lanes, cells))
    tiny = np.finfo(np.float64).tiny
    for i in range(n):
        t = max(total[i], tiny)
        covered = 0.0
        for c in range(cells):
            covered += diff[i, c]
            p_cover = min(max(covered / t, 0.0), 1.0)
            log_open[track_lane[i], c] += math.log1p(-min(existence[i] * p_cover, 1.0 - 1e-12))
    # open probability seen from lane k: occluders in lanes 0 .. k-1 only
    open_ = np.ones((n_lanes, cells))
    for c in range(cells):
        behind = 0.0
        for j in range(n_lanes):
            open_[j, c] = math.exp(behind)
            behind += log_open[j, c]
    visible = np.ones(k)
    for p in range(k):
        if a_right[p] < c0 or a_left[p] > top:
            continue
        f, g = first[p], last[p]
        if f > g:
            f = min(max(math.floor((0.5 * (a_left[p] + a_right[p]) - c0) / step + 0.5), 0),
                    cells - 1)
            g = f
        best = 0.0
        row = lane[p]
        for c in range(f, g + 1):
            best = max(best, open_[row, c])
        visible[p] = best
    return visible
