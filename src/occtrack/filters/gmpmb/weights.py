"""The update's weights, compiled (`occtrack.jit`): each component's miss term under
occlusion, the (component, detection) pairs and their hit weights l_kj, and the
association's weights miss_i, L_ij and L_0j that loopy BP takes (the formulas are
`occtrack.filters.gmpmb`'s docstring). Loops over components and pairs, too small for
numpy's per-call overhead to pay off; `GaussianMixturePMB._update` calls them."""

from __future__ import annotations

import math

import numpy as np

from occtrack.filters.gmpmb.labels import _label_sums
from occtrack.jit import njit

LOG_FLOOR = -300.0


@njit
def _occludable(label, mass, occ_all, used, hits, confirm_hits, stationary):
    """(established, o, o_seen, r per slot, w_k / r of its object) of each component:
    occlusion is for the components of confirmed objects (`GaussianMixturePMB.confirmed`: used
    slots with `confirm_hits` hits; o = 0 for the others; o_seen, the
    o that weighs a detection's source, is the `stationary` occludability for them); the
    Poisson part's components keep w_k."""
    n = len(label)
    r = _label_sums(label, mass, len(used))
    established = np.zeros(n, dtype=np.bool_)
    occ, o_seen, within = np.zeros(n), np.full(n, stationary), np.empty(n)
    for k in range(n):
        i = label[k]
        if i >= 0:
            established[k] = used[i] and hits[i] >= confirm_hits
            if established[k]:
                occ[k] = occ_all[k]
                o_seen[k] = occ_all[k]
            within[k] = mass[k] / max(r[i], 1e-300)
        else:
            within[k] = mass[k]
    return established, occ, o_seen, r, within


@njit
def _miss_terms(det, occ, visible, hidden):
    """(v, q, P_D, miss) per component, v and q clipped to [0, 1]: P_D = d (1 - o + o v) and
    miss = 1 - P_D + d o v q (the occlusion line of `occtrack.filters.gmpmb`'s docstring)."""
    n = len(det)
    v, q, pd, miss = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        v[k] = min(max(visible[k], 0.0), 1.0)
        q[k] = min(max(hidden[k], 0.0), 1.0)
        pd[k] = det[k] * (1.0 - occ[k] + occ[k] * v[k])
        miss[k] = 1.0 - pd[k] + det[k] * occ[k] * v[k] * q[k]
    return v, q, pd, miss


@njit
def _clipped(x, low, high):
    """np.clip(x, low, high) as a new array (numpy's clip costs more than the loop here)."""
    out = np.empty_like(x)
    for i in range(len(x)):
        out[i] = min(max(x[i], low), high)
    return out


@njit
def _object_rows(label, used):
    """(the used slots, each component's object row): rows 0..A-1 are the used slots in
    order, row A the Poisson part."""
    slots = np.flatnonzero(used)
    A = len(slots)
    row_of_slot = np.full(len(used), A, dtype=np.int64)
    for a in range(A):
        row_of_slot[slots[a]] = a
    rows = np.empty(len(label), dtype=np.int64)
    for k in range(len(label)):
        rows[k] = row_of_slot[label[k]] if label[k] >= 0 else A
    return slots, rows


@njit
def _all_pairs(n, M, rows, A):
    """Every (component, detection) pair, component-major (pk, pj), and every (object row,
    detection) pair of the A object rows as a candidate edge: (row, column, candidate of each
    pair; the Poisson part's pairs point past the A M candidates, where nothing reads)."""
    pk, pj = np.empty(n * M, np.int64), np.empty(n * M, np.int64)
    cand_of_pair = np.empty(n * M, np.int64)
    for k in range(n):
        for j in range(M):
            pk[k * M + j] = k
            pj[k * M + j] = j
            cand_of_pair[k * M + j] = rows[k] * M + j
    cand_row, cand_col = np.empty(A * M, np.int64), np.empty(A * M, np.int64)
    for i in range(A):
        for j in range(M):
            cand_row[i * M + j] = i
            cand_col[i * M + j] = j
    return pk, pj, (cand_row, cand_col, cand_of_pair)


@njit
def _hit_edges(pk, pj, log_hit, cand_of_pair, cand_row, cand_col, rows, A, M, mass, det,
               o_seen, v, seen_hidden, pd, use_seen, label, slot_class, classes):
    """The hit weights l_kj = w_k d_k (1 - o_k + o_k v_k (1 - h_j)) p(z_j | x_k) of the pairs
    that are possible (l_kj > e^LOG_FLOOR: below, a pair is impossible, and cutting there
    keeps slow subnormal numbers out; and an object never takes a detection of another
    class, `classes` empty: one class), summed into the association's weights: L_0j of the
    Poisson part, and L_ij on the candidate edges (object row, detection) that any pair
    reaches. Returns the kept pairs (pk, pj, l, edge of each pair, -1 for the Poisson part's),
    L_0j and the edges (row, column, L_ij)."""
    P = len(pk)
    keep = np.zeros(P, dtype=np.bool_)
    hit = np.empty(P)
    floor = math.exp(LOG_FLOOR)
    for e in range(P):
        k, j = pk[e], pj[e]
        if use_seen:
            o = o_seen[k]
            weight = mass[k] * det[k] * (1.0 - o + o * v[k] * (1.0 - seen_hidden[j]))
        else:
            weight = mass[k] * pd[k]
        value = math.exp(log_hit[e]) * max(weight, 1e-300)
        if value > floor and (len(classes) == 0 or label[k] < 0
                              or slot_class[label[k]] == classes[j]):
            keep[e] = True
            hit[e] = value
    poisson_hit = np.zeros(M)
    L_cand = np.zeros(len(cand_row))
    for e in range(P):
        if keep[e]:
            if rows[pk[e]] < A:
                L_cand[cand_of_pair[e]] += hit[e]
            else:
                poisson_hit[pj[e]] += hit[e]
    edge_of_cand = np.full(len(cand_row), -1, dtype=np.int64)
    E = 0
    for i in range(len(cand_row)):
        if L_cand[i] > 0:
            edge_of_cand[i] = E
            E += 1
    e_row, e_col, L_edge = (np.empty(E, dtype=np.int64), np.empty(E, dtype=np.int64),
                            np.empty(E))
    for i in range(len(cand_row)):
        if edge_of_cand[i] >= 0:
            e_row[edge_of_cand[i]] = cand_row[i]
            e_col[edge_of_cand[i]] = cand_col[i]
            L_edge[edge_of_cand[i]] = L_cand[i]
    K = 0
    for e in range(P):
        K += keep[e]
    out_k, out_j = np.empty(K, dtype=np.int64), np.empty(K, dtype=np.int64)
    out_hit, out_edge = np.empty(K), np.empty(K, dtype=np.int64)
    i = 0
    for e in range(P):
        if keep[e]:
            out_k[i], out_j[i], out_hit[i] = pk[e], pj[e], hit[e]
            out_edge[i] = edge_of_cand[cand_of_pair[e]] if rows[pk[e]] < A else -1
            i += 1
    return out_k, out_j, out_hit, out_edge, poisson_hit, e_row, e_col, L_edge


@njit
def _association_weights(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden, clutter,
                         seen_hidden, poisson_hit, occludability, e_row, e_col, L_edge, floor):
    """`_object_misses`, `_new_weights` and `_strong_edges` in one call: (miss_i, L_0j, and
    the strong edges: mask, rows, columns, L_ij). `clutter` is kappa p_F(z_j) of each
    measurement, from the measurement model (`BoxMeasurement.clutter_density`
    for boxes)."""
    miss_obj = _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden)
    w_new = _new_weights(clutter, seen_hidden, poisson_hit, occludability)
    strong, s_row, s_col, s_L = _strong_edges(e_row, e_col, L_edge, miss_obj, w_new, floor)
    return miss_obj, w_new, strong, s_row, s_col, s_L


@njit
def _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden):
    """miss_i = 1 - r_i + sum_{k in i} w_k miss_k of each object row (floored at 1e-300),
    and, in place, each slot's probability that occlusion caused a miss:
    sum w_k d_k o_k (1 - v_k + v_k q_k) / sum w_k miss_k."""
    r, miss_mass, hidden_mass = np.zeros(A + 1), np.zeros(A + 1), np.zeros(A + 1)
    for k in range(len(rows)):
        r[rows[k]] += mass[k]
        miss_mass[rows[k]] += mass[k] * miss[k]
        hidden_mass[rows[k]] += mass[k] * (det[k] * occ[k] * (1.0 - v[k] + v[k] * q[k]))
    slot_hidden[:] = 0.0
    miss_obj = np.empty(A)
    for a in range(A):
        slot_hidden[slots[a]] = hidden_mass[a] / max(miss_mass[a], 1e-300)
        miss_obj[a] = max(1.0 - r[a] + miss_mass[a], 1e-300)
    return miss_obj


@njit
def _new_weights(clutter, seen_hidden, poisson_hit, occludability):
    """L_0j = kappa p_F(z_j) (1 - o h_j) + the Poisson part's hit weights, kappa p_F(z_j)
    given as `clutter` (the measurement model's clutter density)."""
    w_new = np.empty(len(clutter))
    for j in range(len(clutter)):
        w_new[j] = clutter[j] * (1.0 - occludability * seen_hidden[j]) + poisson_hit[j]
    return w_new


@njit
def _strong_edges(row, col, L_edge, miss_obj, w_new, floor):
    """The edges with L_ij >= floor miss_i w_new_j (floor 0: every edge): (mask, their rows,
    columns and L_ij)."""
    strong = np.empty(len(L_edge), dtype=np.bool_)
    count = 0
    for e in range(len(L_edge)):
        strong[e] = floor == 0.0 or L_edge[e] >= floor * miss_obj[row[e]] * w_new[col[e]]
        count += strong[e]
    s_row, s_col, s_L = np.empty(count, np.int64), np.empty(count, np.int64), np.empty(count)
    i = 0
    for e in range(len(L_edge)):
        if strong[e]:
            s_row[i], s_col[i], s_L[i] = row[e], col[e], L_edge[e]
            i += 1
    return strong, s_row, s_col, s_L
