"""The update's children, compiled (`occtrack.jit`): their masses from loopy BP's marginals,
which are kept (pruning, at most `max_components_per_object` per object), and what each
inherits from its parent (state, label, d, o, coasting time). Loops over components and
pairs, too small for numpy's per-call overhead to pay off; `GaussianMixturePMB._update`
calls them."""

from __future__ import annotations

import numpy as np

from occtrack.jit import njit


@njit
def _children(mass, miss, rows, hit, pj, edge_of_pair, strong, p_hit, L_edge, p_new, w_new,
              p_miss, miss_obj):
    """The children's masses: the miss child of each component, w_k miss_k p_miss_i / miss_i
    (the Poisson part's: w_k miss_k), then the hit child of each pair, l_kj p_hit_ij / L_ij
    (Poisson: l_kj p_new_j / L_0j). p_hit is given on the `strong` edges, in order."""
    n, P, A = len(mass), len(hit), len(miss_obj)
    edge_factor = np.zeros(len(L_edge))
    s = 0
    for e in range(len(L_edge)):
        if strong[e]:
            edge_factor[e] = p_hit[s] / L_edge[e]
            s += 1
    out = np.empty(n + P)
    for k in range(n):
        factor = p_miss[rows[k]] / miss_obj[rows[k]] if rows[k] < A else 1.0
        out[k] = mass[k] * miss[k] * factor
    for p in range(P):
        e = edge_of_pair[p]
        out[n + p] = hit[p] * (edge_factor[e] if e >= 0 else p_new[pj[p]] / w_new[pj[p]])
    return out


@njit
def _child_parents(keep, n, pk, pj, M, children):
    """(kept children, their parent component, their detection (-1: miss), their mass) in
    the order of the parents, a miss child before its hit children."""
    K = len(keep)
    parent, j, key = np.empty(K, np.int64), np.empty(K, np.int64), np.empty(K, np.int64)
    for c in range(K):
        if keep[c] < n:
            parent[c], j[c] = keep[c], -1
        else:
            parent[c], j[c] = pk[keep[c] - n], pj[keep[c] - n]
        key[c] = parent[c] * (M + 1) + j[c] + 1
    order = np.argsort(key, kind="mergesort")
    keep, parent, j = keep[order], parent[order], j[order]
    return keep, parent, j, children[keep]


@njit
def _kept_children(children, selected, prune_mass, n, pk, pj, M, label, cap, L):
    """The children kept, as `_child_parents` gives them: those `selected` (None: those
    heavier than prune_mass), then, when cap > 0, at most cap per object (`_trim`, masses
    rescaled)."""
    keep = np.flatnonzero(children > prune_mass) if selected is None else selected
    keep, parent, j, mass = _child_parents(keep, n, pk, pj, M, children)
    if cap:
        trim = _trim(mass, label[parent], j, cap, L)
        if not trim.all():
            keep, parent, j, mass = keep[trim], parent[trim], j[trim], mass[trim]
    return keep, parent, j, mass


@njit
def _trim(mass, label, measurement, cap, L):
    """Which children to keep when each Bernoulli keeps at most `cap` (its heaviest): the
    mask, the kept ones' masses scaled in place so that its existence is unchanged (only its
    density loses the tail). An object is a label (< L), or, born this step, the Poisson
    part's hit children of one measurement, keyed L + j; the Poisson part's miss children
    (key -1) are an intensity and are not trimmed."""
    n = len(mass)
    key = np.empty(n, dtype=np.int64)
    top = -1
    for c in range(n):
        key[c] = label[c] if label[c] >= 0 else (L + measurement[c] if measurement[c] >= 0
                                                 else -1)
        top = max(top, key[c])
    keep = np.ones(n, dtype=np.bool_)
    counts = np.zeros(top + 2, dtype=np.int64)
    over = False
    for c in range(n):
        if key[c] >= 0:
            counts[key[c]] += 1
            over = over or counts[key[c]] > cap
    if not over:
        return keep
    order = np.argsort(key, kind="mergesort")
    first = 0
    while first < n:
        last = first
        while last < n and key[order[last]] == key[order[first]]:
            last += 1
        if key[order[first]] >= 0 and last - first > cap:
            members = order[first:last]
            ranked = members[np.argsort(-mass[members], kind="mergesort")]
            total, kept_total = 0.0, 0.0
            for rank in range(len(ranked)):
                total += mass[ranked[rank]]
                if rank < cap:
                    kept_total += mass[ranked[rank]]
                else:
                    keep[ranked[rank]] = False
            scale = total / max(kept_total, 1e-300)
            for c in members:
                mass[c] *= scale
        first = last
    return keep


@njit
def _inherit(mean, cov, label, parent, j):
    """Each child's copy of its parent's mean, covariance and label, the hit children (j >= 0)
    and the detection each child of the Poisson part was born from (-1 for the others)."""
    K = len(parent)
    new_mean, new_cov = mean[parent], cov[parent]
    new_label = np.empty(K, dtype=label.dtype)
    newborn = np.full(K, -1, dtype=np.int64)
    hits = 0
    for c in range(K):
        new_label[c] = label[parent[c]]
        if j[c] >= 0:
            hits += 1
            if new_label[c] < 0:
                newborn[c] = j[c]
    h = np.empty(hits, dtype=np.int64)
    hits = 0
    for c in range(K):
        if j[c] >= 0:
            h[hits] = c
            hits += 1
    return new_mean, new_cov, new_label, h, newborn


@njit
def _child_features(parent, j, det, occ, occ_all, established, v, q, miss, seen_hidden, coast,
                    dt):
    """d, o and the coasting time of each child (of component parent[c], by detection j[c],
    -1 for the miss child), by Bayes. Missed: P(D=1 | miss) = d o (1 - v + v q) / miss and
    P(O=1 | miss) = o (1 - d + d (1 - v + v q)) / miss. Hit by z_j: D = 1 and
    P(O=1 | hit) = o v (1 - h_j) / (1 - o + o v (1 - h_j)). `occ` is 0 for the components of
    objects not confirmed, whose o (`occ_all`) is carried unchanged."""
    C = len(parent)
    new_det, new_occ, new_coast = np.empty(C), np.empty(C), np.empty(C)
    for c in range(C):
        k = parent[c]
        d, o, vv, mm = det[k], occ[k], v[k], max(miss[k], 1e-300)
        hidden_if_occludable = 1.0 - vv + vv * q[k]
        if j[c] >= 0:
            new_det[c] = 1.0
            escaped = vv * (1.0 - seen_hidden[j[c]])
            seen_o = o * escaped / max(1.0 - o + o * escaped, 1e-300)
            new_occ[c] = seen_o if established[k] else occ_all[k]
            new_coast[c] = 0.0
        else:
            new_det[c] = d * o * hidden_if_occludable / mm
            missed_o = o * (1.0 - d + d * hidden_if_occludable) / mm
            new_occ[c] = missed_o if established[k] else occ_all[k]
            new_coast[c] = coast[k] + dt
    return new_det, new_occ, new_coast


def _miss_branch_moments(mean, cov, parent, j, det, occ, v, q, miss, centre, variance):
    """In place, the miss children (j < 0) of component parent[c]: their density
    p(x) (1 - d + d o v q(x)) / miss moment-matched, given the moments (`centre`, per-axis
    `variance`) of p(x) q(x) / q of each parent. The hidden share s = d o v q / miss moves the
    centre there and the rest of the state with it (its regression on the centre, per axis,
    gain g = P[:, 0] / P[0, 0]): m' = m + s g (c_h - m_0), P' = P + s (v_h - P_00 +
    (1 - s) (c_h - m_0)^2) g g'. Numpy: only the lidar scan tracker's occlusion gives
    these moments."""
    rows = np.flatnonzero(j < 0)
    if len(rows) == 0:
        return
    p = parent[rows]
    share = np.clip(det[p] * occ[p] * v[p] * q[p] / np.maximum(miss[p], 1e-300), 0.0, 1.0)
    for axis in range(mean.shape[1]):
        P = cov[rows, axis]
        P00 = P[:, 0, 0]
        gain = P[:, :, 0] / np.maximum(P00, 1e-300)[:, None]
        dm = centre[p, axis] - mean[rows, axis, 0]
        dv = variance[p, axis] - P00
        mean[rows, axis] += (share * dm)[:, None] * gain
        cov[rows, axis] += (share * (dv + (1.0 - share) * dm * dm))[:, None, None] * (
            gain[:, :, None] * gain[:, None, :])
