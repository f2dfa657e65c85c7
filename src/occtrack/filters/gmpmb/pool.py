"""The filter's component pool, compiled (`occtrack.jit`): its order by label, the merging of
one object's components that share a cell, and the births it takes in, with their size
prior learnt from the detections. Loops over a few hundred components, too small for
numpy's per-call overhead to pay off; `GaussianMixturePMB` calls them."""

from __future__ import annotations

import math

import numpy as np

from occtrack.jit import njit
from occtrack.models.box import MIN_HEIGHT


@njit
def _sort_pool(mass, mean, cov, det, occ, coast, label):
    """Stable sort of the pool's arrays (views of its first n entries) by label, in place.
    The usual pool is sorted but for the births appended at its end (label -1): then the
    stable sort is a rotation that moves them in front of the labelled components."""
    n = len(label)
    t = n
    while t > 0 and label[t - 1] == -1:
        t -= 1
    p = 0
    while p < t and label[p] == -1:
        p += 1
    for k in range(p + 1, t):
        if label[k] < label[k - 1]:
            break
    else:
        if p < t < n:
            for a in (mass, det, occ, coast):
                _rotate(a, p, t)
            _rotate(mean, p, t)
            _rotate(cov, p, t)
            _rotate(label, p, t)
        return
    order = np.argsort(label, kind="mergesort")
    for i in range(len(order)):
        if order[i] != i:
            break
    else:
        return
    mass[:] = mass[order]
    mean[:] = mean[order]
    cov[:] = cov[order]
    det[:] = det[order]
    occ[:] = occ[order]
    coast[:] = coast[order]
    label[:] = label[order]


@njit
def _rotate(a, p, t):
    """a[p:] becomes a[t:] followed by a[p:t]."""
    tail = a[p:].copy()
    a[p:p + len(a) - t] = tail[t - p:]
    a[p + len(a) - t:] = tail[:t - p]


@njit
def _merge_packed(mean, label, cell, mass, cov, det, occ, coast):
    """(fits, cell keys, the pool merged): `_cell_keys`, then `_packed_order` and
    `_pool_cells` when the packed keys fit (else the pool comes back as given, for the
    lexsort path), and the pool as given when no two components share a cell."""
    key = _cell_keys(mean, label, cell)
    fits, order, start = _packed_order(key)
    if fits:
        for i in range(len(start)):
            if not start[i]:
                return True, key, _pool_cells(order, start, mass, mean, cov, det, occ, coast,
                                              label)
    return fits, key, (mass, mean, cov, det, occ, coast, label)


@njit
def _cell_keys(mean, label, cell):
    """Per component (label, octave, the six cell indices): octave = round(log2 h) of its box
    height h, cell index = floor(state / (cell width 2^octave))."""
    n = len(mean)
    key = np.empty((n, 8), dtype=np.int64)
    for k in range(n):
        octave = np.round(np.log2(max(2.0 * mean[k, 1, 2], MIN_HEIGHT)))
        scale = np.exp2(octave)
        key[k, 0], key[k, 1] = label[k], np.int64(octave)
        for axis in range(2):
            for r in range(3):
                key[k, 2 + 3 * axis + r] = np.int64(
                    math.floor(mean[k, axis, r] / (cell[3 * axis + r] * scale)))
    return key


@njit
def _packed_order(key):
    """(fits, order, start): the rows of `key` sorted (stable) by packing each into one
    integer of mixed radix, and where a new key starts; fits is False when the packed
    integers would not fit in 62 bits."""
    n, width = key.shape
    low, span = key[0].copy(), np.ones(width, dtype=np.int64)
    high = key[0].copy()
    for k in range(n):
        for c in range(width):
            low[c] = min(low[c], key[k, c])
            high[c] = max(high[c], key[k, c])
    bits = 0.0
    for c in range(width):
        span[c] = high[c] - low[c] + 1
        bits += math.log2(float(span[c]))
    if not bits < 62:
        return False, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.bool_)
    packed = np.zeros(n, dtype=np.int64)
    for k in range(n):
        for c in range(width):
            packed[k] = packed[k] * span[c] + (key[k, c] - low[c])
    order = np.argsort(packed, kind="mergesort")
    start = np.ones(n, dtype=np.bool_)
    for i in range(1, n):
        start[i] = packed[order[i]] != packed[order[i - 1]]
    return True, order, start


@njit
def _pool_cells(order, start, mass, mean, cov, det, occ, coast, label):
    """Moment matching of the runs of `order` that `start` opens (one run a cell): mass
    W = sum w_k, mean mu = sum s_k m_k and covariance sum s_k (P_k + (m_k - mu)(m_k - mu)')
    with shares s_k = w_k / W; d, o and the coasting time are share-weighted means. A
    component alone in its cell comes out unchanged."""
    G = 0
    for i in range(len(start)):
        G += start[i]
    B, d = mean.shape[1], mean.shape[2]
    out_mass, out_mean, out_cov = np.zeros(G), np.zeros((G, B, d)), np.zeros((G, B, d, d))
    out_det, out_occ, out_coast = np.zeros(G), np.zeros(G), np.zeros(G)
    out_label = np.empty(G, dtype=label.dtype)
    first = np.empty(G + 1, dtype=np.int64)
    g = -1
    for i in range(len(order)):
        if start[i]:
            g += 1
            first[g] = i
        out_mass[g] += mass[order[i]]
    first[G] = len(order)
    for g in range(G):
        total = out_mass[g]
        out_label[g] = label[order[first[g]]]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    out_mean[g, b, r] += share * mean[k, b, r]
            out_det[g] += share * det[k]
            out_occ[g] += share * occ[k]
            out_coast[g] += share * coast[k]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    dev_r = mean[k, b, r] - out_mean[g, b, r]
                    for c in range(d):
                        dev_c = mean[k, b, c] - out_mean[g, b, c]
                        out_cov[g, b, r, c] += share * (cov[k, b, r, c] + dev_r * dev_c)
    return out_mass, out_mean, out_cov, out_det, out_occ, out_coast, out_label


@njit
def _learnt_sizes(count, total, squares):
    """Mean half-size of the detections counted and its standard deviation (at least 1 px)."""
    mean = total / count
    return mean, np.sqrt(np.maximum(squares / count - mean ** 2, 1.0))


@njit
def _prior_sizes(stats, setting_mean, setting_std):
    """`GaussianMixturePMB._size_prior` from the running count, sum and sum of squares
    `stats` (3, 2) and the configured mean and std (empty: not set)."""
    learnt = stats[0, 0] >= 2
    learnt_mean, learnt_std = np.zeros(2), np.zeros(2)
    if learnt:
        learnt_mean, learnt_std = _learnt_sizes(stats[0], stats[1], stats[2])
    if len(setting_mean):
        mean = setting_mean.copy()
    else:
        mean = learnt_mean if learnt else np.array([30.0, 90.0])
    if len(setting_std):
        std = setting_std.copy()
    else:
        std = learnt_std if learnt else mean / 3.0
    return mean, np.maximum(std, 1.0)


@njit
def _count_sizes(z, observed, stats):
    """Add the half-sizes of the detections with every edge measured to the running count,
    sum and sum of squares `stats` (3, 2)."""
    for j in range(len(z)):
        full = True
        for axis in range(2):
            full = full and observed[j, axis, 0] and observed[j, axis, 1]
        if full:
            for axis in range(2):
                half = 0.5 * (z[j, axis, 1] - z[j, axis, 0])
                stats[0, axis] += 1.0
                stats[1, axis] += half
                stats[2, axis] += half * half


@njit
def _append_births(n, mass, means, covs, det, occ, pool_mass, pool_mean, pool_cov, pool_det,
                   pool_occ, pool_label, pool_coast):
    """Append the birth components of positive mass to the pool after its first n (the
    Poisson part: label -1, never missed, d and o the births'); returns the new n."""
    for b in range(len(mass)):
        if mass[b] > 0:
            pool_mass[n], pool_mean[n], pool_cov[n] = mass[b], means[b], covs[b]
            pool_det[n], pool_occ[n], pool_label[n], pool_coast[n] = det, occ, -1, 0.0
            n += 1
    return n
