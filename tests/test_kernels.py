"""The filter's compiled loops (Cython, `filters/gmpmb/_gmpmb.pyx`) against plain numpy.

Each kernel of `occtrack.filters.gmpmb` replaced array code; these tests hold it to what that
code computed, on random input that takes every branch (mixed labels, coasting and not,
components inside and outside the image, borders, ties). Mutation testing cannot plant faults
in compiled functions (mutmut skips decorated functions), so these comparisons are what
notices a fault there. The box model's kernels are compared with `occtrack.densities.gaussian`
in tests/test_scaling.py (`test_pair_likelihoods_and_box_update_equal_the_general_forms`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import occtrack.tracker  # noqa: F401  (the import order gmpmb needs)
from occtrack.filters.gmpmb.children import _child_features, _trim
from occtrack.filters.gmpmb.labels import _object_moments
from occtrack.filters.gmpmb.pool import _cell_keys, _count_sizes, _packed_order, _pool_cells
from occtrack.filters.gmpmb.prediction import (
    _move_in_place,
    _predict_in_place,
    _relax_in_place,
    _survive_in_place,
)
from occtrack.filters.gmpmb.weights import LOG_FLOOR, _hit_edges, _object_misses
from occtrack.models.box import MIN_HEIGHT, heights
from occtrack.models.motion import ConstantVelocity


def components(rng, n):
    """n random box components: means (n, 2, 3), covariances (n, 2, 3, 3)."""
    mean = np.stack([rng.uniform([-50, -40, 0.5], [1970, 40, 80], (n, 3)),
                     rng.uniform([-50, -40, 0.5], [1130, 40, 150], (n, 3))], axis=1)
    root = rng.normal(size=(n, 2, 3, 3))
    return mean, root @ np.swapaxes(root, -1, -2) * 10 + np.eye(3)


@pytest.mark.parametrize("seed", range(3))
def test_pool_cells_is_moment_matching_of_each_run(seed):
    rng = np.random.default_rng(seed)
    n = 40
    mean, cov = components(rng, n)
    mass, det, occ, coast = rng.uniform(0.01, 1, (4, n))
    label = rng.integers(-1, 5, n)
    order = rng.permutation(n)
    start = rng.random(n) < 0.3
    start[0] = True
    got = _pool_cells(order, start, mass, mean, cov, det, occ, coast, label)
    runs = np.split(order, np.flatnonzero(start)[1:])
    assert len(got[0]) == len(runs)
    for g, run in enumerate(runs):
        s = mass[run] / mass[run].sum()
        mu = np.einsum("k,kbd->bd", s, mean[run])
        dev = mean[run] - mu
        P = np.einsum("k,kbij->bij", s, cov[run] + dev[..., :, None] * dev[..., None, :])
        assert got[0][g] == pytest.approx(mass[run].sum(), rel=1e-14)
        np.testing.assert_allclose(got[1][g], mu, rtol=1e-12)
        np.testing.assert_allclose(got[2][g], P, rtol=1e-10)
        for out, values in zip(got[3:6], (det, occ, coast), strict=True):
            assert out[g] == pytest.approx(s @ values[run], rel=1e-12)
        assert got[6][g] == label[run[0]]


def test_predict_in_place_is_each_components_motion_model_in_box_heights():
    rng = np.random.default_rng(1)
    mean, cov = components(rng, 30)
    mean[0, 1, 2] = 0.5  # a degenerate box: the unit is MIN_HEIGHT
    coasting = rng.random(30) < 0.5
    plain = ConstantVelocity(0.1, 2.0, 5.0, 0.5)
    coast = ConstantVelocity(0.1, 2.0, 5.0, 0.5, velocity_time=0.3)
    expected = [np.empty_like(mean), np.empty_like(cov)]
    for model, rows in ((plain, ~coasting), (coast, coasting)):
        m, P = model.predict(mean[rows], cov[rows], heights(mean[rows]))
        expected[0][rows], expected[1][rows] = m, P
    _predict_in_place(mean, cov, coasting, plain.F, plain.Q, coast.F, coast.Q)
    np.testing.assert_allclose(mean, expected[0], rtol=1e-13, atol=1e-9)
    np.testing.assert_allclose(cov, expected[1], rtol=1e-12, atol=1e-9)
    assert heights(expected[0][:1]) == MIN_HEIGHT


def test_object_moments_are_each_slots_mixture_moments():
    rng = np.random.default_rng(2)
    mean, cov = components(rng, 30)
    mass = rng.uniform(0.01, 0.3, 30)
    label = rng.integers(-1, 4, 30)
    label[label == 2] = -1  # slot 2 empty; slot 4 unused
    r, means, sd = _object_moments(label, mass, mean, cov, 5)
    for i in range(5):
        mine = label == i
        r_i = mass[mine].sum()
        assert r[i] == pytest.approx(r_i, rel=1e-14)
        if not mine.any():
            assert not means[i].any() and not sd[i].any()
            continue
        s = mass[mine] / r_i
        mu = np.einsum("k,kbd->bd", s, mean[mine])
        var = s @ (cov[mine][:, :, 0, 0] + (mean[mine][:, :, 0] - mu[:, 0]) ** 2)
        np.testing.assert_allclose(means[i], mu, rtol=1e-12)
        np.testing.assert_allclose(sd[i], np.sqrt(var), rtol=1e-12)


def test_object_misses_are_bincounts():
    """miss_i = 1 - r_i + sum w miss (floored at 1e-300) per object row, and each used slot's
    share of its miss mass that occlusion explains, sum w d o (1 - v + v q) / sum w miss."""
    rng = np.random.default_rng(3)
    A, n = 6, 50
    rows = rng.integers(0, A + 1, n)  # row A: the Poisson part
    mass, miss, det, occ, v, q = rng.random((6, n))
    slots = np.array([0, 2, 3, 5, 7, 8])  # the used slots, one per object row
    slot_hidden = np.full(10, 0.5)
    miss_obj = _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden)
    r = np.bincount(rows, mass, minlength=A + 1)[:A]
    miss_mass = np.bincount(rows, mass * miss, minlength=A + 1)[:A]
    hidden = np.bincount(rows, mass * (det * occ * (1 - v + v * q)), minlength=A + 1)[:A]
    np.testing.assert_allclose(miss_obj, np.maximum(1 - r + miss_mass, 1e-300), rtol=1e-13)
    expected = np.zeros(10)
    expected[slots] = hidden / miss_mass
    np.testing.assert_allclose(slot_hidden, expected, rtol=1e-13)


def test_child_features_are_bayes_for_the_miss_and_the_hit_children():
    rng = np.random.default_rng(4)
    K, M, C = 12, 5, 40
    det, occ_all, v, q, coast = rng.random((5, K))
    established = rng.random(K) < 0.6
    occ = np.where(established, occ_all, 0.0)
    miss = 1 - det * (1 - occ + occ * v) + det * occ * v * q
    seen_hidden = rng.random(M)
    parent, j = rng.integers(0, K, C), rng.integers(-1, M, C)
    d, o, x = _child_features(parent, j, det, occ, occ_all, established, v, q, miss,
                              seen_hidden, coast, 0.04)
    dk, ok, vk, hid = det[parent], occ[parent], v[parent], 1 - v[parent] + v[parent] * q[parent]
    escaped = vk * (1 - seen_hidden[np.maximum(j, 0)])
    hit = j >= 0
    expected_o = np.where(hit, ok * escaped / (1 - ok + ok * escaped),
                          ok * (1 - dk + dk * hid) / miss[parent])
    expected_o = np.where(established[parent], expected_o, occ_all[parent])
    np.testing.assert_allclose(d, np.where(hit, 1.0, dk * ok * hid / miss[parent]), rtol=1e-12)
    np.testing.assert_allclose(o, expected_o, rtol=1e-12)
    np.testing.assert_allclose(x, np.where(hit, 0.0, coast[parent] + 0.04), rtol=1e-14)
    assert hit.any() and (~hit).any() and established.any() and (~established).any()


@pytest.mark.parametrize("use_seen", [False, True])
@pytest.mark.parametrize("with_classes", [False, True])
def test_hit_edges_keep_the_possible_pairs_and_sum_them_per_edge(use_seen, with_classes):
    rng = np.random.default_rng(5)
    K, M, A = 20, 6, 3
    label = np.sort(rng.integers(-1, A, K))
    rows = np.where(label >= 0, label, A)
    pk, pj = np.repeat(np.arange(K), M), np.tile(np.arange(M), K)
    cand_row, cand_col = np.divmod(np.arange(A * M), M)
    cand_of_pair = rows[pk] * M + pj
    log_hit = rng.uniform(-320, 0, K * M)
    mass, det, o_seen, v, pd = rng.random((5, K))
    seen_hidden = rng.random(M)
    slot_class = rng.integers(0, 2, A)
    classes = rng.integers(0, 2, M) if with_classes else np.zeros(0, dtype=np.int64)
    got = _hit_edges(pk, pj, log_hit, cand_of_pair, cand_row, cand_col, rows, A, M, mass,
                     det, o_seen, v, seen_hidden, pd, use_seen, label, slot_class, classes)
    out_k, out_j, out_hit, out_edge, poisson_hit, e_row, e_col, L_edge = got

    o = o_seen[pk]
    weight = (mass[pk] * det[pk] * (1 - o + o * v[pk] * (1 - seen_hidden[pj])) if use_seen
              else mass[pk] * pd[pk])
    value = np.exp(log_hit) * np.maximum(weight, 1e-300)
    keep = value > math.exp(LOG_FLOOR)
    if with_classes:
        keep &= (label[pk] < 0) | (slot_class[np.maximum(label[pk], 0)] == classes[pj])
    assert 0 < keep.sum() < len(keep)
    np.testing.assert_array_equal(out_k, pk[keep])
    np.testing.assert_array_equal(out_j, pj[keep])
    np.testing.assert_allclose(out_hit, value[keep], rtol=1e-13)
    poisson = keep & (rows[pk] == A)
    np.testing.assert_allclose(poisson_hit, np.bincount(pj[poisson], value[poisson],
                                                        minlength=M), rtol=1e-12)
    L_cand = np.bincount(cand_of_pair[keep & ~poisson], value[keep & ~poisson],
                         minlength=A * M)
    edges = np.flatnonzero(L_cand > 0)
    np.testing.assert_array_equal(e_row, cand_row[edges])
    np.testing.assert_array_equal(e_col, cand_col[edges])
    np.testing.assert_allclose(L_edge, L_cand[edges], rtol=1e-12)
    edge_of_cand = np.full(A * M + M, -1)  # (the Poisson part's pairs point past the edges)
    edge_of_cand[edges] = np.arange(len(edges))
    np.testing.assert_array_equal(
        out_edge, np.where(rows[out_k] < A, edge_of_cand[cand_of_pair[keep]], -1))


def test_relax_survive_and_move_in_place_equal_their_array_forms():
    rng = np.random.default_rng(6)
    p = rng.random(20)
    expected = 0.8 + 0.3 * (p - 0.8)
    _relax_in_place(p, 0.8, 0.3)
    np.testing.assert_allclose(p, expected, rtol=1e-15)

    mean, cov = components(rng, 40)
    mean[:4, :, 0] = [[0.0, 1080.0], [1920.0, 0.0], [-1e-9, 10.0], [10.0, 1080.1]]
    mean[4:6, :, 2] = [[1.0, 1.0], [0.999, 10.0]]
    mass = rng.random(40)
    size = np.array([1920.0, 1080.0])
    inside = ((mean[..., 0] >= 0) & (mean[..., 0] <= size) & (mean[..., 2] >= 1.0)).all(axis=1)
    expected = mass * np.where(inside, 0.97, 0.2)
    _survive_in_place(mass, mean, size, 0.97, 0.2)
    np.testing.assert_allclose(mass, expected, rtol=1e-15)
    assert inside.any() and (~inside).any() and inside[:2].all() and not inside[2:4].any()

    scale, shift = np.array([1.1, 0.9]), np.array([-7.0, 12.5])
    variance = np.array([4.0, 0.25])  # the shift's: it widens the centres only
    expected_mean = mean * scale[:, None]
    expected_mean[..., 0] += shift
    expected_cov = cov * scale[:, None, None] ** 2
    expected_cov[:, :, 0, 0] += variance
    _move_in_place(mean, cov, scale, shift, variance)
    np.testing.assert_allclose(mean, expected_mean, rtol=1e-14)
    np.testing.assert_allclose(cov, expected_cov, rtol=1e-14)


def test_count_sizes_adds_the_half_sizes_of_fully_measured_boxes():
    rng = np.random.default_rng(7)
    low = rng.uniform(0, 1000, (30, 2))
    z = np.stack([low, low + rng.uniform(1, 200, (30, 2))], axis=-1)
    observed = rng.random((30, 2, 2)) < 0.85
    stats = np.ones((3, 2))
    _count_sizes(z, observed, stats)
    full = observed.all(axis=(1, 2))
    half = 0.5 * (z[full, :, 1] - z[full, :, 0])
    np.testing.assert_allclose(stats, 1 + np.stack([np.full(2, full.sum()), half.sum(axis=0),
                                                    (half**2).sum(axis=0)]), rtol=1e-13)
    assert 0 < full.sum() < 30


def test_cell_keys_and_their_packed_order_equal_lexsort():
    rng = np.random.default_rng(8)
    mean, _ = components(rng, 60)
    mean[:20] = mean[20:40] + rng.uniform(-0.5, 0.5, (20, 2, 3))  # many shared cells
    label = rng.integers(-1, 4, 60)
    label[:20] = label[20:40]
    cell = np.array([0.5, 2.0, 0.25] * 2)
    key = _cell_keys(mean, label, cell)
    octave = np.round(np.log2(np.maximum(2 * mean[:, 1, 2], MIN_HEIGHT)))
    expected = np.concatenate([label[:, None], octave[:, None],
                               np.floor(mean.reshape(60, 6) / (cell * 2.0**octave[:, None]))],
                              axis=1)
    np.testing.assert_array_equal(key, expected.astype(np.int64))

    fits, order, start = _packed_order(key)
    reference = np.lexsort(key.T[::-1])
    ordered = key[reference]
    assert fits
    np.testing.assert_array_equal(order, reference)
    np.testing.assert_array_equal(start[1:], (ordered[1:] != ordered[:-1]).any(axis=1))
    assert start[0] and 1 < start.sum() < 60

    wide = key.copy()
    wide[0, 2:] = 2**40  # eight keys spanning 2^40 do not pack into 62 bits
    fits, order, start = _packed_order(wide)
    assert not fits and len(order) == 0 and len(start) == 0


@pytest.mark.parametrize("cap", [1, 2, 3])
def test_trim_keeps_each_objects_heaviest_and_rescales(cap):
    rng = np.random.default_rng(9)
    n, L = 50, 4
    mass = np.round(rng.random(n), 1) + 0.05  # ties: the earlier child wins
    label = rng.integers(-1, L, n)
    measurement = np.where(label < 0, rng.integers(-1, 3, n), rng.integers(-1, 3, n))
    key = np.where(label >= 0, label, np.where(measurement >= 0, L + measurement, -1))
    expected_keep = np.ones(n, dtype=bool)
    expected_mass = mass.copy()
    for k in np.unique(key[key >= 0]):
        members = np.flatnonzero(key == k)
        if len(members) <= cap:
            continue
        ranked = members[np.argsort(-mass[members], kind="stable")]
        expected_keep[ranked[cap:]] = False
        expected_mass[members] *= mass[members].sum() / mass[ranked[:cap]].sum()
    got_mass = mass.copy()
    keep = _trim(got_mass, label, measurement, cap, L)
    np.testing.assert_array_equal(keep, expected_keep)
    np.testing.assert_allclose(got_mass, expected_mass, rtol=1e-14)
    assert (~keep).any() and keep[key < 0].all()
    untouched = mass.copy()
    assert _trim(untouched, label, measurement, n, L).all()
    np.testing.assert_array_equal(untouched, mass)
