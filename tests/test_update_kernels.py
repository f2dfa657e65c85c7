"""The compiled kernels of the speed work against the numpy code they replaced, bit for bit.

Each kernel was written to reproduce a few lines of array code to the last bit, so that the
tracks did not change; the references below are those lines (the old bodies of
`GaussianMixturePMB`'s methods, `Tracker.tracks`, `BoxMeasurement`, `lbp_sparse` and
`ObjectWiseExpectedValue`), kept here and run on small random inputs from seeded generators,
empty ones included.
"""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.association.lbp import _marginals
from occtrack.filters.gmpmb.children import (
    _child_parents,
    _children,
    _inherit,
    _kept_children,
    _trim,
)
from occtrack.filters.gmpmb.labels import (
    _cap_in_place,
    _confirm_in_place,
    _count_in_place,
    _keep_labels,
    _open_slots,
    _rank_bernoullis,
    _split_ranked,
)
from occtrack.filters.gmpmb.pool import (
    _append_births,
    _cell_keys,
    _learnt_sizes,
    _merge_packed,
    _packed_order,
    _pool_cells,
    _prior_sizes,
    _sort_pool,
)
from occtrack.filters.gmpmb.prediction import (
    _predict_in_place,
    _predict_pool,
    _relax_in_place,
    _survive_in_place,
)
from occtrack.filters.gmpmb.weights import (
    _all_pairs,
    _association_weights,
    _clipped,
    _miss_terms,
    _new_weights,
    _object_misses,
    _object_rows,
    _occludable,
    _strong_edges,
)
from occtrack.models.box import (
    _beyond_scores,
    _box_clutter,
    _censored,
    _edges,
    _edges_of_boxes,
    _measured_edges,
)
from occtrack.occlusion.box_objectwise import _occluder_boxes
from occtrack.spatial import _sweep
from occtrack.tracker.camera import _first_best
from occtrack.tracker.tracker import OCCLUDED_ABOVE, _report_rows, _reported

EDGE_FLOOR = 1e-9
# (seed, components n, detections M): empty pools and frames, single ones, small crowds
CASES = [(0, 0, 0), (1, 0, 4), (2, 5, 0), (3, 1, 1), (4, 6, 3), (5, 12, 5), (6, 25, 8)]
SLOTS = 6


def equal(actual, expected) -> None:
    """Every array of `actual` equals the one of `expected`: same kind of dtype, same shape,
    same values and signs of zero (NaN where the other has NaN)."""
    for a, e in zip(actual, expected, strict=True):
        a, e = np.asarray(a), np.asarray(e)
        assert a.dtype.kind == e.dtype.kind, (a.dtype, e.dtype)
        np.testing.assert_array_equal(a, e, strict=False)
        assert a.shape == e.shape
        if a.dtype.kind == "f":  # (-0.0 == 0.0 above)
            np.testing.assert_array_equal(np.signbit(a), np.signbit(e))


def bincount(x, weights, minlength):
    """np.bincount with weights, as floats (numpy gives integers when `x` is empty)."""
    return np.bincount(x, weights=weights, minlength=minlength).astype(float)


def labels(rng, n, L=SLOTS):
    """Labels -1 (the Poisson part) to L - 1, repeats included."""
    return rng.integers(-1, L, n).astype(np.int64)


def states(rng, n):
    """Box states (n, 2, 3) (centre, velocity, half-size per axis) around a 640 x 480 image,
    and covariances (n, 2, 3, 3)."""
    mean = np.empty((n, 2, 3))
    mean[:, 0, 0] = rng.uniform(-40.0, 680.0, n)
    mean[:, 1, 0] = rng.uniform(-40.0, 520.0, n)
    mean[:, :, 1] = rng.normal(0.0, 20.0, (n, 2))
    mean[:, :, 2] = rng.uniform(0.3, 90.0, (n, 2))
    root = rng.normal(0.0, 3.0, (n, 2, 3, 3))
    cov = root @ root.transpose(0, 1, 3, 2) + 0.5 * np.eye(3)
    return mean, cov


def masses(rng, n):
    """Masses in (0, 1]: an object of several components can sum above 1."""
    return rng.uniform(0.05, 1.0, n)


# -- gmpmb: the update's per-component terms ---------------------------------------------------


def occludable_reference(label, mass, occ_all, used, hits, confirm_hits, stationary):
    L = len(used)
    confirmed = used & (hits >= confirm_hits)
    established = np.where(label >= 0, confirmed[np.maximum(label, 0)], False)
    occ = np.where(established, occ_all, 0.0)
    r_slot = bincount(label[label >= 0], mass[label >= 0], minlength=L)
    within = np.where(label >= 0, mass / np.maximum(r_slot[label], 1e-300), mass)
    o_seen = np.where(established, occ, stationary)
    return established, occ, o_seen, r_slot, within


@pytest.mark.parametrize("seed,n,M", CASES)
def test_occludable(seed, n, M):
    """_occludable gives the old established mask, o, o_seen, r per slot and w_k / r."""
    rng = np.random.default_rng(seed)
    pool = (labels(rng, n), masses(rng, n), rng.uniform(0, 1, n))
    slots = (rng.random(SLOTS) < 0.7, rng.integers(0, 4, SLOTS))
    for confirm_hits in (1, 2, 3):
        args = (*pool, *slots, confirm_hits, 0.3)
        equal(_occludable(*args), occludable_reference(*args))


@pytest.mark.parametrize("seed,n,M", CASES)
def test_miss_terms(seed, n, M):
    """_miss_terms gives the old clipped v, q and P_D, miss of the occlusion line."""
    rng = np.random.default_rng(seed)
    det, occ = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    visible, hidden = rng.uniform(-0.5, 1.5, n), rng.uniform(-0.5, 1.5, n)
    v, q = np.clip(visible, 0.0, 1.0), np.clip(hidden, 0.0, 1.0)
    pd = det * (1.0 - occ + occ * v)
    miss = 1.0 - pd + det * occ * v * q
    equal(_miss_terms(det, occ, visible, hidden), (v, q, pd, miss))


@pytest.mark.parametrize("seed,n,M", CASES)
@pytest.mark.parametrize("presorted", [False, True, "births"])
def test_sort_pool(seed, n, M, presorted):
    """_sort_pool reorders the seven pool arrays in place as the old stable argsort did,
    also when only the births appended at the end (label -1) are out of place."""
    rng = np.random.default_rng(seed)
    label = labels(rng, n)
    if presorted:
        label.sort()
    if presorted == "births":
        label[len(label) - len(label) // 4:] = -1
    mean, cov = states(rng, n)
    pool = [masses(rng, n), mean, cov, rng.uniform(0, 1, n), rng.uniform(0, 1, n),
            rng.uniform(0, 2, n), label]
    order = np.argsort(label, kind="stable")
    expected = [arr[order] for arr in pool]
    _sort_pool(*pool)
    equal(pool, expected)


def slot_arrays(rng, L=SLOTS):
    """Slot bookkeeping: detection, age, hits, coast, used."""
    return (rng.integers(-1, 4, L), rng.integers(0, 6, L), rng.integers(0, 6, L),
            rng.uniform(0, 1, L), rng.random(L) < 0.7)


@pytest.mark.parametrize("seed,n,M", CASES)
def test_count_in_place(seed, n, M):
    """_count_in_place updates detection, age, hits and coast as _count_detections did."""
    rng = np.random.default_rng(seed)
    detection, age, hits, coast, used = slot_arrays(rng)
    slots = np.flatnonzero(used)
    A = len(slots)
    E = n if A and M else 0
    row, col = rng.integers(0, max(A, 1), E), rng.integers(0, max(M, 1), E)
    p_hit = rng.uniform(0.0, 0.5, E)
    p_hit[rng.random(E) < 0.2] = 0.5
    for a in np.unique(row):  # at most one p_hit above 1/2 per object
        if rng.random() < 0.7:
            p_hit[rng.choice(np.flatnonzero(row == a))] = rng.uniform(0.5, 1.0)
    dt = 0.04
    expected = [detection.copy(), age.copy(), hits.copy(), coast.copy()]
    e_det, e_age, e_hits, e_coast = expected
    e_det[:] = -1
    took = p_hit > 0.5
    e_det[slots[row[took]]] = col[took]
    hit = e_det >= 0
    e_age[used] += 1
    e_hits[hit] += 1
    e_coast[used & ~hit] += dt
    e_coast[hit] = 0.0
    _count_in_place(detection, age, hits, coast, used, slots, row, col, p_hit, dt)
    equal([detection, age, hits, coast], expected)


@pytest.mark.parametrize("seed,n,M", CASES)
def test_confirm_in_place(seed, n, M):
    """_confirm_in_place frees the doomed slots and keeps the components _confirm_or_delete
    kept."""
    rng = np.random.default_rng(seed)
    _, age, hits, _, used = slot_arrays(rng)
    label = labels(rng, n)
    window, needed = 4, 3
    left = np.maximum(window - age, 0)
    doomed = used & (hits + left < needed)
    e_used = used.copy()
    if doomed.any():
        e_used[doomed] = False
        e_keep = ~((label >= 0) & doomed[np.maximum(label, 0)])
    else:
        e_keep = np.ones(n, dtype=bool)
    keep = _confirm_in_place(used, age, hits, label, window, needed)
    equal([keep, used], [e_keep, e_used])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_cap_in_place(seed, n, M):
    """_cap_in_place scales an object's masses by 1 / r when r > 1, as _cap_existence did."""
    rng = np.random.default_rng(seed)
    label = labels(rng, n, 3)
    mass = masses(rng, n)
    lab = label >= 0
    r = bincount(label[lab], mass[lab], minlength=SLOTS)
    expected = mass.copy()
    over = r > 1.0
    if over.any():
        scale = np.where(over, 1.0 / np.maximum(r, 1e-300), 1.0)
        expected[lab] *= scale[label[lab]]
    _cap_in_place(mass, label, SLOTS)
    equal([mass], [expected])


# -- gmpmb: labels --------------------------------------------------------------------------


def newborns(rng, label, M):
    """The detection each Poisson component's hit child was born from (-1: none)."""
    out = np.where(label < 0, rng.integers(-1, max(M, 1), len(label)), -1)
    return out if M else np.full(len(label), -1)


@pytest.mark.parametrize("seed,n,M", CASES + [(7, 120, 40)])
def test_rank_bernoullis(seed, n, M):
    """_rank_bernoullis gives the old slots, measurements, existences and stable ranking
    (ties in r among more Bernoullis than an insertion sort handles)."""
    rng = np.random.default_rng(seed)
    label = np.where(rng.random(n) < 0.5, -1, labels(rng, n))
    mass = rng.integers(1, 9, n) / 8.0  # (ties in r, for the stable order)
    newborn = newborns(rng, label, M)
    used = rng.random(SLOTS) < 0.7
    min_existence = 0.25
    lab, born = label >= 0, newborn >= 0
    r_old = bincount(label[lab], mass[lab], minlength=SLOTS)
    r_new = bincount(newborn[born], mass[born], minlength=M)
    old = np.flatnonzero(used)
    new = np.flatnonzero(r_new > 0)
    r_all = np.concatenate([r_old[old], r_new[new]])
    eligible = r_all >= min_existence
    ranked = np.argsort(-r_all, kind="stable")
    ranked = ranked[eligible[ranked]]
    equal(_rank_bernoullis(label, mass, newborn, used, M, min_existence),
          (old, new, r_all, ranked))


@pytest.mark.parametrize("seed,n,M", CASES + [(7, 120, 40)])
@pytest.mark.parametrize("limit", [0, 1, 3])
def test_keep_labels(seed, n, M, limit):
    """_keep_labels keeps the strongest Bernoullis (at most `limit`), frees the other used
    slots, unlabels their components and lists the cut existences, as the old numpy lines of
    `_assign_labels` did around _rank_bernoullis and _split_ranked."""
    rng = np.random.default_rng(seed)
    label = np.where(rng.random(n) < 0.5, -1, labels(rng, n))
    mass = rng.integers(1, 9, n) / 8.0
    newborn = newborns(rng, label, M)
    used = rng.random(SLOTS) < 0.7
    old, new, r_all, ranked = _rank_bernoullis(label, mass, newborn, used.copy(), M, 0.25)
    held, lost = len(ranked), np.zeros(0)
    if limit and held > limit:
        lost, ranked = r_all[ranked[limit:]], ranked[:limit]
    keep_old, keep_new = _split_ranked(ranked, len(old))
    expected_used = used.copy()
    expected_used[old[~keep_old]] = False
    gone = np.zeros(SLOTS, dtype=bool)
    gone[old[~keep_old]] = True
    expected = np.where((label >= 0) & gone[np.maximum(label, 0)], -1, label)
    out = _keep_labels(label, mass, newborn, used, M, 0.25, limit)
    equal(out[:3], (expected, new[keep_new], lost))
    assert out[3] == held
    equal(used, expected_used)


@pytest.mark.parametrize("seed", range(6))
def test_split_ranked(seed):
    """_split_ranked splits a ranking into kept old Bernoullis and sorted new ones."""
    rng = np.random.default_rng(seed)
    n_old, n_new = rng.integers(0, 5, 2)
    ranked = rng.permutation(n_old + n_new)[:rng.integers(0, n_old + n_new + 1)]
    keep_old = np.zeros(n_old, dtype=bool)
    keep_old[ranked[ranked < n_old]] = True
    keep_new = ranked[ranked >= n_old] - n_old
    keep_new.sort()
    equal(_split_ranked(ranked.astype(np.int64), int(n_old)), (keep_old, keep_new))


@pytest.mark.parametrize("seed,n,M", CASES)
@pytest.mark.parametrize("with_classes", [False, True])
def test_open_slots(seed, n, M, with_classes):
    """_open_slots gives the kept newborns the first free slots and their labels, as
    _assign_labels did."""
    rng = np.random.default_rng(seed)
    L = SLOTS + M
    label = np.where(rng.random(n) < 0.5, -1, labels(rng, n))
    newborn = newborns(rng, label, M)
    present = np.unique(newborn[newborn >= 0])
    meas = present[rng.random(len(present)) < 0.7]
    used = np.zeros(L, dtype=bool)
    used[:SLOTS] = rng.random(SLOTS) < 0.6
    slot_arrays_ = [rng.integers(0, 50, L), rng.integers(0, 6, L), rng.integers(0, 6, L),
                    rng.uniform(0, 1, L), rng.integers(-1, 4, L), rng.integers(0, 3, L)]
    classes = rng.integers(0, 4, M) if with_classes else np.zeros(0, dtype=np.int64)
    serial0 = 17

    e_used = used.copy()
    serial, age, hits, coast, detection, cls = (a.copy() for a in slot_arrays_)
    free = np.flatnonzero(~e_used)[:len(meas)]
    e_used[free] = True
    slot_of_meas = np.full(M, -1, dtype=np.int64)
    slot_of_meas[meas] = free
    e_label = np.where(newborn >= 0, slot_of_meas[np.maximum(newborn, 0)], label) if M else label
    serial[free] = serial0 + np.arange(len(free))
    age[free] = 1
    hits[free] = 1
    coast[free] = 0.0
    detection[free] = meas
    cls[free] = classes[meas] if with_classes else 0

    out = _open_slots(label, newborn, meas, M, serial0, used, *slot_arrays_, classes)
    equal([out, used, *slot_arrays_], [e_label, e_used, serial, age, hits, coast, detection,
                                       cls])


# -- gmpmb: pairs, objects and association weights -------------------------------------------


@pytest.mark.parametrize("seed,n,M", CASES)
def test_all_pairs(seed, n, M):
    """_all_pairs lists every (component, detection) pair and candidate edge as the old
    repeat / tile / divmod did."""
    rng = np.random.default_rng(seed)
    A = int(rng.integers(0, 4))
    rows = rng.integers(0, A + 1, n)
    pk, pj = np.repeat(np.arange(n), M), np.tile(np.arange(M), n)
    cand_row, cand_col = np.divmod(np.arange(A * M), max(M, 1))
    cand_of_pair = rows[pk] * M + pj
    got_k, got_j, (got_row, got_col, got_cand) = _all_pairs(n, M, rows, A)
    equal([got_k, got_j, got_row, got_col, got_cand], [pk, pj, cand_row, cand_col,
                                                       cand_of_pair])


def object_rows_reference(label, used):
    L = len(used)
    slots = np.flatnonzero(used)
    A = len(slots)
    row_of_slot = np.full(L, A, dtype=np.int64)
    row_of_slot[slots] = np.arange(A)
    return slots, np.where(label >= 0, row_of_slot[np.maximum(label, 0)], A)


@pytest.mark.parametrize("seed,n,M", CASES)
def test_object_rows(seed, n, M):
    """_object_rows gives the old used slots and each component's object row."""
    rng = np.random.default_rng(seed)
    label, used = labels(rng, n), rng.random(SLOTS) < 0.7
    equal(_object_rows(label, used), object_rows_reference(label, used))


def update_terms(rng, n, M):
    """Per-component terms of an update: (rows, A, mass, miss, det, occ, v, q, slots)."""
    label, used = labels(rng, n), rng.random(SLOTS) < 0.7
    slots, rows = object_rows_reference(label, used)
    det, occ = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    v, q = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    occ[rng.random(n) < 0.3] = 0.0
    pd = det * (1.0 - occ + occ * v)
    miss = 1.0 - pd + det * occ * v * q
    return rows, len(slots), masses(rng, n), miss, det, occ, v, q, slots


def object_misses_reference(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden):
    hidden = det * occ * (1.0 - v + v * q)
    r_obj = bincount(rows, mass, minlength=A + 1)
    miss_mass = bincount(rows, mass * miss, minlength=A + 1)
    hidden_mass = bincount(rows, mass * hidden, minlength=A + 1)
    slot_hidden[:] = 0.0
    slot_hidden[slots] = hidden_mass[:A] / np.maximum(miss_mass[:A], 1e-300)
    return np.maximum(1.0 - r_obj[:A] + miss_mass[:A], 1e-300)


def detections(rng, M):
    """Detections (M, 2, 2) (left, right; top, bottom), some under a pixel wide."""
    low = rng.uniform(-10.0, 600.0, (M, 2))
    size = rng.uniform(0.0, 120.0, (M, 2))
    size[rng.random((M, 2)) < 0.2] = rng.uniform(0.0, 0.9)
    return np.stack([low, low + size], axis=-1)


def new_weights_reference(z, score_term, seen_hidden, poisson_hit, rate, area, occludability):
    size = np.maximum((z[:, :, 1] - z[:, :, 0]).prod(axis=1), 1.0)
    clutter = rate / (area * size) * score_term * (1.0 - occludability * seen_hidden)
    return clutter + poisson_hit


def strong_edges_reference(row, col, L_edge, miss_obj, w_new, floor):
    strong = (L_edge >= floor * miss_obj[row] * w_new[col]) if floor else (
        np.ones(len(L_edge), dtype=bool))
    return strong, row[strong], col[strong], L_edge[strong]


def association_inputs(rng, n, M):
    rows, A, mass, miss, det, occ, v, q, slots = update_terms(rng, n, M)
    z = detections(rng, M)
    scores = rng.uniform(0.0, 1.0, M)
    score_term = np.clip(scores, 0.1, 1.0) ** -1.5
    seen_hidden = np.where(rng.random(M) < 0.5, rng.uniform(0, 1, M), 0.0)
    poisson_hit = np.where(rng.random(M) < 0.5, rng.uniform(0, 1e-5, M), 0.0)
    E = int(rng.integers(0, A * M + 1))
    e_row, e_col = rng.integers(0, max(A, 1), E), rng.integers(0, max(M, 1), E)
    return (rows, A, mass, miss, det, occ, v, q, slots, z, score_term, seen_hidden,
            poisson_hit, e_row, e_col)


def edge_weights(rng, e_row, e_col, miss_obj, w_new, floor):
    """L_ij around floor miss_i w_new_j, some exactly on it."""
    L_edge = floor * miss_obj[e_row] * w_new[e_col] * rng.uniform(0.3, 3.0, len(e_row))
    on = rng.random(len(e_row)) < 0.2
    L_edge[on] = (floor * miss_obj[e_row] * w_new[e_col])[on]
    return L_edge


@pytest.mark.parametrize("seed,n,M", CASES)
def test_object_misses(seed, n, M):
    """_object_misses gives the old miss_i and writes the old slot_hidden."""
    rng = np.random.default_rng(seed)
    rows, A, mass, miss, det, occ, v, q, slots = update_terms(rng, n, M)
    slot_hidden, expected_hidden = rng.uniform(0, 1, SLOTS), np.empty(SLOTS)
    expected = object_misses_reference(rows, A, mass, miss, det, occ, v, q, slots,
                                       expected_hidden)
    got = _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden)
    equal([got, slot_hidden], [expected, expected_hidden])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_new_weights(seed, n, M):
    """_new_weights gives the old L_0j = clutter + Poisson hit weights."""
    rng = np.random.default_rng(seed)
    z, score_term, seen_hidden, poisson_hit = association_inputs(rng, n, M)[9:13]
    rate, area, o = 4.0, 640.0 * 480.0, 0.3
    got = _new_weights(_box_clutter(z, score_term, rate, area), seen_hidden, poisson_hit, o)
    expected = new_weights_reference(z, score_term, seen_hidden, poisson_hit, rate, area, o)
    equal([got], [expected])


@pytest.mark.parametrize("seed,n,M", CASES)
@pytest.mark.parametrize("floor", [EDGE_FLOOR, 0.0])
def test_strong_edges(seed, n, M, floor):
    """_strong_edges keeps the old gated edges (floor 0: all of them)."""
    rng = np.random.default_rng(seed)
    A = int(rng.integers(0, 4))
    E = int(rng.integers(0, A * M + 1))
    row, col = rng.integers(0, max(A, 1), E), rng.integers(0, max(M, 1), E)
    miss_obj, w_new = rng.uniform(0.01, 1, A), rng.uniform(1e-8, 1e-4, M)
    L_edge = edge_weights(rng, row, col, miss_obj, w_new, floor or EDGE_FLOOR)
    args = (row, col, L_edge, miss_obj, w_new, floor)
    equal(_strong_edges(*args), strong_edges_reference(*args))


@pytest.mark.parametrize("seed,n,M", CASES)
@pytest.mark.parametrize("floor", [EDGE_FLOOR, 0.0])
def test_association_weights(seed, n, M, floor):
    """_association_weights gives the old miss_i, L_0j, slot_hidden and strong edges."""
    rng = np.random.default_rng(seed)
    (rows, A, mass, miss, det, occ, v, q, slots, z, score_term, seen_hidden, poisson_hit,
     e_row, e_col) = association_inputs(rng, n, M)
    rate, area, o = 4.0, 640.0 * 480.0, 0.3
    hidden = np.empty(SLOTS)
    miss_obj = object_misses_reference(rows, A, mass, miss, det, occ, v, q, slots, hidden)
    w_new = new_weights_reference(z, score_term, seen_hidden, poisson_hit, rate, area, o)
    L_edge = edge_weights(rng, e_row, e_col, miss_obj, w_new, floor or EDGE_FLOOR)
    expected = (miss_obj, w_new,
                *strong_edges_reference(e_row, e_col, L_edge, miss_obj, w_new, floor), hidden)
    slot_hidden = rng.uniform(0, 1, SLOTS)
    got = _association_weights(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden,
                               _box_clutter(z, score_term, rate, area), seen_hidden,
                               poisson_hit, o, e_row, e_col, L_edge, floor)
    equal([*got, slot_hidden], expected)


# -- gmpmb: children ------------------------------------------------------------------------


@pytest.mark.parametrize("seed,n,M", CASES)
def test_children(seed, n, M):
    """_children gives the old miss and hit children's masses."""
    rng = np.random.default_rng(seed)
    A = int(rng.integers(0, 4))
    rows = rng.integers(0, A + 1, n)
    mass, miss = masses(rng, n), rng.uniform(0, 1, n)
    P = n * M
    pj, hit = np.tile(np.arange(M), n), rng.uniform(0, 1e-3, P)
    E = int(rng.integers(0, A * M + 1))
    edge_of_pair = np.where((rows.repeat(M) < A) & (rng.random(P) < 0.7),
                            rng.integers(0, max(E, 1), P), -1) if E else np.full(P, -1)
    strong = rng.random(E) < 0.7
    L_edge = rng.uniform(1e-6, 1e-3, E)
    p_hit = rng.uniform(0, 1, int(strong.sum()))
    p_new, w_new = rng.uniform(0, 1, M), rng.uniform(1e-6, 1e-3, M)
    p_miss, miss_obj = rng.uniform(0, 1, A), rng.uniform(0.01, 1, A)

    mine = edge_of_pair >= 0
    hit_factor = (p_new / w_new)[pj]
    edge_factor = np.zeros(E)
    edge_factor[strong] = p_hit / L_edge[strong]
    hit_factor[mine] = edge_factor[edge_of_pair[mine]]
    miss_factor = np.append(p_miss / miss_obj, 1.0)
    expected = np.concatenate([mass * miss * miss_factor[rows], hit * hit_factor])
    got = _children(mass, miss, rows, hit, pj, edge_of_pair, strong, p_hit, L_edge, p_new,
                    w_new, p_miss, miss_obj)
    equal([got], [expected])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_child_parents(seed, n, M):
    """_child_parents gives the kept children's parents, detections and masses in the old
    order (by parent, a miss child before its hit children)."""
    rng = np.random.default_rng(seed)
    P = n * M
    pk, pj = np.repeat(np.arange(n), M), np.tile(np.arange(M), n)
    keep = np.flatnonzero(rng.random(n + P) < 0.6)
    children = rng.uniform(0, 1, n + P)
    missed = keep < n
    pair = np.where(missed, 0, keep - n)
    parent = np.where(missed, keep, pk[pair] if len(pk) else 0)
    j = np.where(missed, -1, pj[pair] if len(pj) else 0)
    order = np.argsort(parent * (M + 1) + j + 1, kind="stable")
    e_keep, parent, j = keep[order], parent[order], j[order]
    equal(_child_parents(keep, n, pk, pj, M, children),
          (e_keep, parent, j, children[e_keep]))


@pytest.mark.parametrize("seed,n,M", CASES + [(7, 40, 6)])
@pytest.mark.parametrize("cap", [0, 1, 2])
@pytest.mark.parametrize("given", [False, True])
def test_kept_children(seed, n, M, cap, given):
    """_kept_children selects (the given indices, else those above prune_mass), orders by
    _child_parents and trims to cap per object as the old lines of `_update` did."""
    rng = np.random.default_rng(seed)
    P = n * M
    pk, pj = np.repeat(np.arange(n), M), np.tile(np.arange(M), n)
    children = rng.uniform(0, 1, n + P)
    label = labels(rng, n)
    selected = np.flatnonzero(rng.random(n + P) < 0.6) if given else None
    keep = selected if given else np.flatnonzero(children > 0.3)
    keep, parent, j, mass = _child_parents(keep, n, pk, pj, M, children)
    if cap:
        trim = _trim(mass, label[parent], j, cap, SLOTS)
        keep, parent, j, mass = keep[trim], parent[trim], j[trim], mass[trim]
    equal(_kept_children(children, selected, 0.3, n, pk, pj, M, label, cap, SLOTS),
          (keep, parent, j, mass))


@pytest.mark.parametrize("seed,n,M", CASES)
def test_inherit(seed, n, M):
    """_inherit copies the parents' means, covariances and labels and finds the hit and
    newborn children as the old lines did."""
    rng = np.random.default_rng(seed)
    mean, cov = states(rng, n)
    label = labels(rng, n)
    K = 2 * n
    parent = rng.integers(0, max(n, 1), K) if n else np.zeros(0, dtype=np.int64)
    j = rng.integers(-1, M, K) if M else np.full(K, -1)
    new_label = label[parent]
    expected = (mean[parent], cov[parent], new_label, np.flatnonzero(j >= 0),
                np.where((j >= 0) & (new_label < 0), j, -1))
    equal(_inherit(mean, cov, label, parent, j), expected)


# -- gmpmb: clipping, sizes, births, prediction, merging ------------------------------------


@pytest.mark.parametrize("seed,n,M", CASES)
def test_clipped(seed, n, M):
    """_clipped equals np.clip, bounds and values outside them included."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 2.0, n)
    x[rng.random(n) < 0.2] = 1.0
    x[rng.random(n) < 0.2] = -0.0
    x[rng.random(n) < 0.1] = np.nan
    x[rng.random(n) < 0.1] = -np.inf
    for low, high in ((0.0, 1.0), (0.25, 0.5), (-3.0, 3.0)):
        equal([_clipped(x, low, high)], [np.clip(x, low, high)])


@pytest.mark.parametrize("seed", range(6))
def test_learnt_sizes(seed):
    """_learnt_sizes gives the old mean half-size and its floored standard deviation."""
    rng = np.random.default_rng(seed)
    count = rng.integers(2, 40, 2).astype(float)
    half = [rng.uniform(2.0, 90.0, int(c)) for c in count]
    if seed % 2:
        half[0][:] = half[0][0]  # (variance below 1: floored)
    total = np.array([h.sum() for h in half])
    squares = np.array([(h * h).sum() for h in half])
    expected = (total / count,
                np.sqrt(np.maximum(squares / count - (total / count) ** 2, 1.0)))
    equal(_learnt_sizes(count, total, squares), expected)


@pytest.mark.parametrize("seen", [0, 1, 2, 9])
@pytest.mark.parametrize("mean_set", [None, (12.0, 34.0)])
@pytest.mark.parametrize("std_set", [None, (1.5, 0.5)])
def test_prior_sizes(seen, mean_set, std_set):
    """_prior_sizes gives the old `_size_prior`: the settings, else the detections' sizes
    once two were seen, else 30 x 90 px and a third of it; the std floored at 1 px."""
    rng = np.random.default_rng(seen)
    half = rng.uniform(0.5, 60.0, (seen, 2))
    stats = np.array([np.full(2, float(seen)), half.sum(axis=0), (half * half).sum(axis=0)])
    learnt = _learnt_sizes(stats[0], stats[1], stats[2]) if seen >= 2 else None
    mean = (np.asarray(mean_set) if mean_set is not None else
            learnt[0] if learnt else np.array([30.0, 90.0]))
    std = (np.asarray(std_set) if std_set is not None else
           learnt[1] if learnt else mean / 3.0)
    settings = [np.zeros(0) if x is None else np.asarray(x) for x in (mean_set, std_set)]
    equal(_prior_sizes(stats, *settings), (mean, np.maximum(std, 1.0)))


@pytest.mark.parametrize("seed,n,M", CASES)
def test_append_births(seed, n, M):
    """_append_births appends the births of positive mass as the old lines did."""
    rng = np.random.default_rng(seed)
    B = M
    mass = np.where(rng.random(B) < 0.3, 0.0, rng.uniform(0, 1e-3, B))
    means, covs = states(rng, B)
    cap = n + B + 3
    pool_mean, pool_cov = states(rng, cap)
    pool = [rng.uniform(0, 1, cap), pool_mean, pool_cov, rng.uniform(0, 1, cap),
            rng.uniform(0, 1, cap), labels(rng, cap), rng.uniform(0, 1, cap)]
    det, occ = 0.7, 0.2
    e_mass, e_mean, e_cov, e_det, e_occ, e_label, e_coast = (a.copy() for a in pool)
    keep = mass > 0
    b = int(keep.sum())
    s = slice(n, n + b)
    e_mass[s], e_mean[s], e_cov[s] = mass[keep], means[keep], covs[keep]
    e_det[s] = det
    e_occ[s] = occ
    e_label[s] = -1
    e_coast[s] = 0.0
    got = _append_births(n, mass, means, covs, det, occ, *pool)
    assert got == n + b
    equal(pool, [e_mass, e_mean, e_cov, e_det, e_occ, e_label, e_coast])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_predict_pool(seed, n, M):
    """_predict_pool equals _predict_in_place, _relax_in_place (d, o) and _survive_in_place
    in turn."""
    rng = np.random.default_rng(seed)
    mean, cov = states(rng, n)
    pool = [masses(rng, n), mean, cov, rng.uniform(0, 1, n), rng.uniform(0, 1, n),
            rng.uniform(0, 0.2, n)]
    F, F_coast = np.eye(3) + rng.normal(0, 0.1, (3, 3)), np.eye(3) + rng.normal(0, 0.1, (3, 3))
    Q, Q_coast = np.diag(rng.uniform(0, 1e-3, 3)), np.diag(rng.uniform(0, 1e-3, 3))
    image_size = np.array([640.0, 480.0])
    after = 0.1
    mass, mean, cov, det, occ, coast = (a.copy() for a in pool)
    _predict_in_place(mean, cov, coast > after, F, Q, F_coast, Q_coast)
    _relax_in_place(det, 0.9, 0.8)
    _relax_in_place(occ, 0.4, 0.6)
    _survive_in_place(mass, mean, image_size, 0.99, 0.5)
    _predict_pool(*pool, after, F, Q, F_coast, Q_coast, 0.9, 0.8, 0.4, 0.6, image_size,
                  0.99, 0.5)
    equal(pool, [mass, mean, cov, det, occ, coast])


def merge_reference(mass, mean, cov, det, occ, coast, label, cell):
    """The old `GaussianMixturePMB._merge` after its n < 2 test: (fits, the pool merged)."""
    key = _cell_keys(mean, label, cell)
    fits, order, start = _packed_order(key)
    if not fits:
        order = np.lexsort(key.T[::-1])
        key = key[order]
        start = np.ones(len(order), dtype=bool)
        start[1:] = (key[1:] != key[:-1]).any(axis=1)
    if start.all():
        return fits, (mass, mean, cov, det, occ, coast, label)
    return fits, _pool_cells(order, start, mass, mean, cov, det, occ, coast, label)


@pytest.mark.parametrize("seed,n,M", [case for case in CASES if case[1] >= 2])
@pytest.mark.parametrize("spread", ["shared", "apart", "too wide"])
def test_merge_packed(seed, n, M, spread):
    """_merge_packed gives the old cell keys and merged pool; when the packed keys do not
    fit it hands the keys and the pool as given to the lexsort path, which merges as the old
    code did."""
    rng = np.random.default_rng(seed)
    label = np.sort(labels(rng, n, 3))
    mean, cov = states(rng, n)
    if spread == "shared":  # a few distinct states, so that cells hold several components
        mean = mean[rng.integers(0, 3, n)] + rng.uniform(0, 1e-3, (n, 2, 3))
    elif spread == "too wide":
        mean[:, :, :2] *= 1e6
    pool = (masses(rng, n), mean, cov, rng.uniform(0, 1, n), rng.uniform(0, 1, n),
            rng.uniform(0, 1, n))
    cell = np.array([0.5, 0.5, 0.5] * 2)
    mass, _, cov, det, occ, coast = pool
    fits, key, merged = _merge_packed(mean, label, cell, mass, cov, det, occ, coast)
    e_fits, expected = merge_reference(*pool, label, cell)
    assert fits == e_fits == (spread != "too wide")
    np.testing.assert_array_equal(key, _cell_keys(mean, label, cell))
    if spread == "shared":
        assert len(expected[0]) < n
    if not fits:
        equal(merged, (*pool, label))
        order = np.lexsort(key.T[::-1])
        key = key[order]
        start = np.ones(len(order), dtype=bool)
        start[1:] = (key[1:] != key[:-1]).any(axis=1)
        if not start.all():
            merged = _pool_cells(order, start, *pool, label)
    equal(merged, expected)


# -- tracker --------------------------------------------------------------------------------


def tracks_reference(r, means, centre_std, used, took, coast, serial, reported_serial,
                     report_id, next_id, min_existence, coast_time, max_centre_std, boxes_in,
                     hidden, classes, observed):
    """The old body of `Tracker.tracks` after `object_moments`: (ids, boxes, existence,
    velocities, detection index, class, occluded, next id); report_id and reported_serial
    in place. A detection's unmeasured edge (`observed` False: on the border) gives way to
    the state's when that lies farther out."""
    height = np.maximum(2.0 * means[:, 1, 2], 1.0)
    trusted = (took >= 0) | ((coast <= coast_time + 1e-9)
                             & (centre_std.max(axis=1) < max_centre_std * height))
    shown = np.flatnonzero(used & (r > min_existence) & trusted)
    fresh = shown[reported_serial[shown] != serial[shown]]
    fresh = fresh[np.lexsort((means[fresh, 1, 0], means[fresh, 0, 0]))]
    report_id[fresh] = next_id + np.arange(len(fresh))
    reported_serial[fresh] = serial[fresh]
    next_id += len(fresh)
    ids = report_id[shown]
    order = np.argsort(ids)
    shown = shown[order]
    c, s = means[shown][..., 0], means[shown][..., 2]
    boxes = np.concatenate([c - s, 2.0 * s], axis=-1)
    index = took[shown]
    detected = index >= 0
    state_lo = boxes[detected, :2]
    state_hi = state_lo + boxes[detected, 2:]
    lo, size = boxes_in[index[detected], :2], boxes_in[index[detected], 2:]
    seen = observed[index[detected]]
    out = ~seen[..., 0] & (state_lo < lo)
    lo, size = np.where(out, state_lo, lo), np.where(out, size + (lo - state_lo), size)
    out = ~seen[..., 1] & (state_hi > lo + size)
    size = np.where(out, state_hi - lo, size)
    boxes[detected] = np.concatenate([lo, size], axis=-1)
    occluded = ~detected & (hidden[shown] > OCCLUDED_ABOVE)
    return (ids[order], boxes, r[shown], means[shown, :, 1].copy(), index,
            classes[shown].copy(), occluded, next_id)


@pytest.mark.parametrize("seed,n,M", CASES)
def test_reported(seed, n, M):
    """_reported and _report_rows give the old tracks, new ids in image order, ties in x
    broken by y and then by slot."""
    rng = np.random.default_rng(seed)
    L = n  # (slots)
    r = rng.uniform(0, 1, L)
    means, _ = states(rng, L)
    means[:, :, 0] = np.round(means[:, :, 0] / 200.0) * 200.0  # (ties in image order)
    means[rng.random(L) < 0.2, 1, 2] = 0.2  # (height floored at 1)
    centre_std = rng.uniform(0, 20, (L, 2))
    used = rng.random(L) < 0.8
    took = rng.integers(-1, M, L) if M else np.full(L, -1)
    coast = np.where(rng.random(L) < 0.5, rng.uniform(0, 2, L), 1.0)
    serial = rng.integers(0, 3, L)
    reported_serial = np.where(rng.random(L) < 0.5, serial, serial + 1)
    next_id = 40
    report_id = rng.permutation(next_id)[:L].astype(np.int64)
    boxes_in = rng.uniform(0, 300, (M, 4))
    hidden = rng.uniform(0, 1, L)
    hidden[rng.random(L) < 0.2] = OCCLUDED_ABOVE
    classes = rng.integers(0, 3, L)
    rules = (0.3, 1.0, 0.4)
    observed = rng.random((M, 2, 2)) < 0.7  # (a share of the edges on the border)

    e_serial, e_id = reported_serial.copy(), report_id.copy()
    expected = tracks_reference(r, means, centre_std, used, took, coast, serial, e_serial,
                                e_id, next_id, *rules, boxes_in, hidden, classes, observed)
    shown, got_next = _reported(r, means, centre_std, used, took, coast, serial,
                                reported_serial, report_id, next_id, *rules)
    rows = _report_rows(shown, r, means, took, boxes_in, hidden, classes, OCCLUDED_ABOVE,
                        observed)
    assert got_next == expected[-1]
    equal([report_id[shown], *rows, reported_serial, report_id],
          [*expected[:-1], e_serial, e_id])


# -- box model, belief propagation, object-wise occlusion ------------------------------------


@pytest.mark.parametrize("seed,n,M", CASES)
def test_edges(seed, n, M):
    """_edges equals H m with H = [[1, 0, -1], [1, 0, 1]], and _edges_of_boxes the old
    (left, top, width, height) to edges conversion."""
    rng = np.random.default_rng(seed)
    means, _ = states(rng, n)
    H = np.array([[1.0, 0.0, -1.0], [1.0, 0.0, 1.0]])
    equal([_edges(means)], [means @ H.T])
    boxes = rng.uniform(-20.0, 600.0, (M, 4))
    low = boxes[:, :2]
    equal([_edges_of_boxes(boxes)], [np.stack([low, low + boxes[:, 2:]], axis=-1)])


@pytest.mark.parametrize("seed,n,M", CASES)
@pytest.mark.parametrize("extrapolated", [True, False])
def test_measured_edges(seed, n, M, extrapolated):
    """_measured_edges equals numpy's rule, edges exactly on either side of the margin
    included: an edge within the margin of the border is censored; one beyond it by more
    than the margin is measured when `extrapolated`, censored otherwise."""
    rng = np.random.default_rng(seed)
    margin, image_size = 2.0, np.array([640.0, 480.0])
    z = detections(rng, M)
    z[rng.random((M, 2)) < 0.3, 0] = margin
    z[rng.random((M, 2)) < 0.2, 0] = -margin
    z[rng.random((M, 2)) < 0.2, 0] = -50.0
    on_high = rng.random((M, 2)) < 0.3
    z[on_high, 1] = np.broadcast_to(image_size - margin, (M, 2))[on_high]
    beyond_high = rng.random((M, 2)) < 0.2
    z[beyond_high, 1] = np.broadcast_to(image_size + margin, (M, 2))[beyond_high]
    z[rng.random((M, 2)) < 0.2, 1] = 700.0
    low_ok = (z[..., 0] > margin) | (extrapolated & (z[..., 0] < -margin))
    high_ok = (z[..., 1] < image_size - margin) | (extrapolated & (z[..., 1] > image_size + margin))
    expected = np.stack([low_ok, high_ok], axis=-1)
    W, H = image_size
    equal([_measured_edges(z, margin, W, H, extrapolated)], [expected])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_beyond_scores(seed, n, M):
    """_censored lists the edges some detection has on the border, and _beyond_scores equals
    the old standard scores of the border in loglik_pairs on those edges."""
    rng = np.random.default_rng(seed)
    means, covs = states(rng, n)
    zhat = _edges(means)
    root = rng.normal(0.0, 4.0, (n, 2, 2, 2))
    S = root @ root.transpose(0, 1, 3, 2) + np.eye(2)
    margin, image_size = 2.0, np.array([640.0, 480.0])
    sd = np.sqrt(np.stack([S[..., 0, 0], S[..., 1, 1]], axis=-1))
    border = np.stack([np.full(2, margin), image_size - margin], axis=-1)
    scores = np.array([1.0, -1.0]) * (border - zhat) / sd
    observed = rng.random((M, 2, 2)) < 0.8
    censored = ~observed.all(axis=0)
    W, H = image_size
    equal([_censored(observed)], [censored])
    equal([_beyond_scores(zhat, S, margin, W - margin, H - margin, observed)],
          [scores[:, censored]])


@pytest.mark.parametrize("seed,n,M", CASES)
def test_marginals(seed, n, M):
    """_marginals gives the old p_hit, p_miss and p_new from the converged messages."""
    rng = np.random.default_rng(seed)
    A = n  # (objects)
    E = int(rng.integers(0, A * M + 1))
    rows, cols = rng.integers(0, max(A, 1), E), rng.integers(0, max(M, 1), E)
    ratio, grouped = rng.uniform(0, 5, E), rng.uniform(0, 2, E)
    order = rng.permutation(E)
    w_new = rng.uniform(1e-6, 1, M)
    nu = np.empty(E)
    nu[order] = grouped
    s = ratio * nu
    total = bincount(rows, s, minlength=A)
    p_hit = s / (1.0 + total[rows])
    p_miss = 1.0 / (1.0 + total)
    mu = ratio / (1.0 + total[rows] - s)
    p_new = w_new / (w_new + bincount(cols, mu, minlength=M))
    equal(_marginals(rows, cols, ratio, grouped, order, w_new, A), (p_hit, p_miss, p_new))


def mean_boxes_reference(boxes, weights, owner, n_objects):
    """The old `_mean_boxes` of box_objectwise."""
    mine = owner >= 0
    flat = boxes[mine].reshape(-1, 4)
    w = weights[mine]
    total = bincount(owner[mine], w, minlength=n_objects)
    sums = np.stack([bincount(owner[mine], w * flat[:, c], minlength=n_objects)
                     for c in range(4)], axis=1)
    return (sums / np.maximum(total, 1e-300)[:, None]).reshape(n_objects, 2, 2)


@pytest.mark.parametrize("seed,n,M", CASES)
def test_occluder_boxes(seed, n, M):
    """_occluder_boxes gives the old occluders' mean boxes and each component's place among
    them, an occluder with no component and objects that are no occluder included."""
    rng = np.random.default_rng(seed)
    n_objects = SLOTS
    means, _ = states(rng, n)
    boxes = _edges(means)
    owner = labels(rng, n, n_objects)
    weights = rng.uniform(0, 1, n)
    occluders = np.flatnonzero(rng.random(n_objects) < 0.6)
    mean_boxes = mean_boxes_reference(boxes, weights, owner, n_objects)[occluders]
    position = np.full(n_objects + 1, -1)
    position[occluders] = np.arange(len(occluders))
    own = position[owner]
    equal(_occluder_boxes(boxes, weights, owner, occluders), (mean_boxes, own))


@pytest.mark.parametrize("seed, n, M", CASES)
def test_sweep(seed, n, M):
    """_sweep gives the candidate pairs of `overlapping_pairs` that overlap, in the order of
    the old array lines (i ascending, then the sweep order)."""
    rng = np.random.default_rng(seed)
    N, K = n + 3, M + 4
    a = np.sort(rng.uniform(0, 100, (N, 2, 2)), axis=-1)
    b = np.sort(rng.uniform(0, 100, (K, 2, 2)), axis=-1)
    order = np.argsort(b[:, 0, 0], kind="stable")
    low, s_x1, s_y0, s_y1 = b[order, 0, 0], b[order, 0, 1], b[order, 1, 0], b[order, 1, 1]
    widest = float((b[:, 0, 1] - b[:, 0, 0]).max())
    start = np.searchsorted(low, a[:, 0, 0] - widest, side="left")
    stop = np.searchsorted(low, a[:, 0, 1], side="left")
    counts = np.maximum(stop - start, 0)
    total = int(counts.sum())
    i = np.repeat(np.arange(N), counts)
    k = np.arange(total) + np.repeat(start - (np.cumsum(counts) - counts), counts)
    ok = (a[i, 0, 0] < s_x1[k]) & (a[i, 1, 0] < s_y1[k]) & (s_y0[k] < a[i, 1, 1])
    expected = (i[ok], order[k[ok]])
    assert total > 0 and 0 < ok.sum() < total
    equal(_sweep(a[:, 0, 0].copy(), a[:, 1, 0].copy(), a[:, 1, 1].copy(), s_x1, s_y0, s_y1,
                 order, start, stop), expected)


@pytest.mark.parametrize("seed, n, M", CASES)
def test_first_best(seed, n, M):
    """_first_best gives, per group, the largest value and among ties the smallest other, as
    the old lexsort lines did; groups without a pair get (0, 0)."""
    rng = np.random.default_rng(seed)
    size, pairs = n + 2, 3 * M
    group = rng.integers(0, size, pairs)
    value = rng.choice([0.2, 0.5, 0.8], pairs) if seed % 2 else rng.uniform(0, 1, pairs)
    other = rng.integers(0, 9, pairs)
    best_value, best_index = np.zeros(size), np.zeros(size, dtype=np.int64)
    if pairs:
        order = np.lexsort((other, -value, group))
        first = np.ones(len(order), dtype=bool)
        first[1:] = group[order[1:]] != group[order[:-1]]
        winners = order[first]
        best_value[group[winners]] = value[winners]
        best_index[group[winners]] = other[winners]
    equal(_first_best(group, value, other, size), (best_value, best_index))
