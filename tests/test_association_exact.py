"""Association marginals pinned to hand-computed numbers: the dense and the sparse loopy BP,
the exact enumeration they are checked against, and the clusters of the sparse form."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.association import exact_marginals, lbp_marginals, lbp_sparse
from occtrack.association import lbp as lbp_module


def one_pair(w_hit=0.6, w_miss=0.5, w_new=0.25):
    return np.array([[w_hit]]), np.array([w_miss]), np.array([w_new])


def test_one_object_one_measurement_by_hand():
    """Two associations: a hit (weight w_hit) or a miss and a new measurement (w_miss w_new),
    so p_hit = 0.6 / (0.6 + 0.125). BP is exact on it: nu is 1 / w_new after one iteration
    and unchanged after the second, where it stops."""
    p = 0.6 / (0.6 + 0.5 * 0.25)
    for marg in (exact_marginals(*one_pair()), lbp_marginals(*one_pair())):
        np.testing.assert_allclose(marg.p_hit, [[p]], rtol=1e-13)
        np.testing.assert_allclose(marg.p_miss, [1 - p], rtol=1e-13)
        np.testing.assert_allclose(marg.p_new, [1 - p], rtol=1e-13)
    assert exact_marginals(*one_pair()).iterations == 0
    assert lbp_marginals(*one_pair()).iterations == 2
    assert lbp_marginals(*one_pair(w_new=1.0)).iterations == 1  # nu = 1 from the start
    sparse = lbp_sparse([0], [0], [0.6], [0.5], [0.25])
    np.testing.assert_allclose(sparse.p_hit, [p], rtol=1e-13)
    assert (sparse.iterations, sparse.clusters) == (2, 1)


def test_tol_zero_runs_to_max_iter_even_at_a_fixed_point():
    """The messages stop changing at the second iteration; a change of 0 is not below a
    tolerance of 0, so BP runs all max_iter iterations (by default 1000)."""
    assert lbp_marginals(*one_pair(), tol=0.0, max_iter=50).iterations == 50
    assert lbp_marginals(*one_pair(), tol=0.0).iterations == 1000
    assert lbp_sparse([0], [0], [0.6], [0.5], [0.25], tol=0.0, max_iter=50).iterations == 50
    assert lbp_sparse([0], [0], [0.6], [0.5], [0.25], tol=0.0).iterations == 1000


def two_by_two():
    w_hit = np.array([[0.8, 0.3], [0.2, 0.7]])
    return w_hit, np.array([0.4, 0.6]), np.array([0.5, 0.9])


def test_exact_two_by_two_by_hand():
    """All seven associations of two objects and two measurements, summed by hand."""
    w_hit, w_miss, w_new = two_by_two()
    terms = {  # (object 0's measurement, object 1's): weight; -1: missed
        (-1, -1): 0.4 * 0.6 * 0.5 * 0.9, (0, -1): 0.8 * 0.6 * 0.9, (1, -1): 0.3 * 0.6 * 0.5,
        (-1, 0): 0.4 * 0.2 * 0.9, (-1, 1): 0.4 * 0.7 * 0.5, (0, 1): 0.8 * 0.7,
        (1, 0): 0.3 * 0.2}
    total = sum(terms.values())
    p_hit = np.zeros((2, 2))
    p_miss = np.zeros(2)
    for (a, b), w in terms.items():
        for i, j in enumerate((a, b)):
            if j < 0:
                p_miss[i] += w / total
            else:
                p_hit[i, j] += w / total
    marg = exact_marginals(w_hit, w_miss, w_new)
    np.testing.assert_allclose(marg.p_hit, p_hit, rtol=1e-13)
    np.testing.assert_allclose(marg.p_miss, p_miss, rtol=1e-13)
    np.testing.assert_allclose(marg.p_new, 1 - p_hit.sum(axis=0), rtol=1e-13)
    assert marg.iterations == 0
    # integer weights are numbers like any other: (6 x 2^40)^2 is beyond int64
    big = 6 * 2**40
    marg = exact_marginals(np.array([[big * big, 0], [0, 0]]), [big, big], [big, big])
    np.testing.assert_allclose(marg.p_hit[0, 0], 0.5, rtol=1e-13)


def test_weights_are_unnormalised_up_to_the_float_range():
    """Scaling every association weight by the same factor changes no marginal, even near
    the largest float (1e307 here)."""
    w_hit, w_miss, w_new = two_by_two()
    small = exact_marginals(w_hit, w_miss, w_new)
    one = exact_marginals([[1e308]], [1e307], [1.0])
    np.testing.assert_allclose(one.p_hit, [[1 / 1.1]], rtol=1e-13)
    for scale in (1e-300, 1e300):
        # every association has two factors here, so scale each by sqrt(scale)
        c = np.sqrt(scale)
        big = exact_marginals(w_hit * c, w_miss * c, w_new)
        np.testing.assert_allclose(big.p_hit, small.p_hit, rtol=1e-12)


@pytest.mark.parametrize("n,m", [(0, 0), (0, 3), (2, 0)])
def test_empty_problems(n, m):
    marg = lbp_marginals(np.zeros((n, m)), np.full(n, 0.5), np.full(m, 0.5))
    assert marg.p_hit.shape == (n, m) and marg.iterations == 0
    np.testing.assert_array_equal(marg.p_miss, np.ones(n))
    np.testing.assert_array_equal(marg.p_new, np.ones(m))
    sparse = lbp_sparse(np.zeros(0, int), np.zeros(0, int), np.zeros(0), np.full(n, 0.5),
                        np.full(m, 0.5))
    assert sparse.p_hit.shape == (0,) and (sparse.iterations, sparse.clusters) == (0, 0)
    np.testing.assert_array_equal(sparse.p_miss, np.ones(n))
    np.testing.assert_array_equal(sparse.p_new, np.ones(m))


def test_sparse_pairs_with_no_weight_left_still_give_ones():
    """Objects and measurements in no pair: missed (p_miss 1) and new (p_new 1)."""
    marg = lbp_sparse([1], [2], [0.6], [0.5, 0.5, 0.5], [0.25, 0.25, 0.25, 0.25])
    p = 0.6 / (0.6 + 0.5 * 0.25)
    np.testing.assert_allclose(marg.p_miss, [1, 1 - p, 1], rtol=1e-13)
    np.testing.assert_allclose(marg.p_new, [1, 1, 1 - p, 1], rtol=1e-13)


def test_zero_miss_and_new_weights_are_constraints_not_divided_by():
    """A sure detection (w_miss 0) and a measurement that cannot be clutter (w_new 0), each
    with two pairs to choose from: BP gives finite marginals, the dense and sparse forms agree
    with the enumeration of the zeros themselves, and an impossible event has probability at
    most ZERO_FLOOR (test_association_zeros.py: the forced pairs)."""
    w_hit = np.array([[0.5, 0.5], [0.0, 0.2]])
    w_miss, w_new = np.array([0.0, 0.3]), np.array([0.4, 0.0])
    dense = lbp_marginals(w_hit, w_miss, w_new, tol=1e-13)
    i, j = np.nonzero(w_hit)
    sparse = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=1e-13)
    exact = exact_marginals(w_hit, w_miss, w_new)
    assert exact.p_miss[0] == 0.0 and exact.p_new[1] == 0.0
    for marg, hit in ((dense, dense.p_hit[i, j]), (sparse, sparse.p_hit)):
        assert np.isfinite(hit).all()
        np.testing.assert_allclose(hit, exact.p_hit[i, j], atol=1e-9)
        np.testing.assert_allclose(marg.p_miss, exact.p_miss, atol=1e-9)
        np.testing.assert_allclose(marg.p_new, exact.p_new, atol=1e-9)
        assert marg.p_miss[0] <= lbp_module.ZERO_FLOOR and marg.p_new[1] <= 1e-9


def blocks(rng, count, size):
    """`count` fully connected size x size problems side by side (no pair between them)."""
    n = m = count * size
    w_hit = np.zeros((n, m))
    for b in range(count):
        s = slice(b * size, (b + 1) * size)
        w_hit[s, s] = rng.uniform(0.05, 0.9, (size, size))
    return w_hit, rng.uniform(0.1, 1.0, n), rng.uniform(0.01, 1.0, m)


@pytest.mark.parametrize("count,size", [(3, 3), (21, 4), (2, 12)])  # 27, 336, 288 pairs
def test_sparse_matches_the_dense_form_cluster_by_cluster(count, size):
    """Each cluster of the sparse form iterates exactly as the dense form on that cluster
    alone (same iterations, same marginals up to rounding); the whole run takes as many
    iterations as the slowest cluster. Below CLUSTER_MIN_PAIRS pairs it is one problem and
    runs as the dense form on all of it."""
    rng = np.random.default_rng(count)
    w_hit, w_miss, w_new = blocks(rng, count, size)
    # one more object and one more measurement in no pair: missed and new for sure
    w_hit = np.pad(w_hit, ((0, 1), (0, 1)))
    w_miss, w_new = np.append(w_miss, 0.5), np.append(w_new, 0.5)
    i, j = np.nonzero(w_hit)
    tol = 1e-6
    sparse = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=tol)
    clustered = len(i) >= lbp_module.CLUSTER_MIN_PAIRS
    assert clustered == (count != 3)
    if not clustered:
        dense = lbp_marginals(w_hit, w_miss, w_new, tol=tol)
        assert sparse.clusters == 1 and sparse.iterations == dense.iterations
        np.testing.assert_allclose(sparse.p_hit, dense.p_hit[i, j], rtol=1e-12)
        np.testing.assert_allclose(sparse.p_miss, dense.p_miss, rtol=1e-12)
        np.testing.assert_allclose(sparse.p_new, dense.p_new, rtol=1e-12)
        return
    assert sparse.clusters == count + 2  # the lone object and measurement count as clusters
    assert (sparse.p_miss[-1], sparse.p_new[-1]) == (1.0, 1.0)
    iterations = []
    for b in range(count):
        s = slice(b * size, (b + 1) * size)
        dense = lbp_marginals(w_hit[s, s], w_miss[s], w_new[s], tol=tol)
        iterations.append(dense.iterations)
        mine = (i >= b * size) & (i < (b + 1) * size)
        np.testing.assert_allclose(sparse.p_hit[mine], dense.p_hit.ravel(), rtol=1e-12)
        np.testing.assert_allclose(sparse.p_miss[s], dense.p_miss, rtol=1e-12)
        np.testing.assert_allclose(sparse.p_new[s], dense.p_new, rtol=1e-12)
    assert iterations[0] != iterations[-1] and sparse.iterations == max(iterations)
    # defaults: tol 1e-7, max_iter 1000
    default = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new)
    explicit = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=1e-7, max_iter=1000)
    assert default.iterations == explicit.iterations > sparse.iterations
    np.testing.assert_array_equal(default.p_hit, explicit.p_hit)
    capped = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=0.0, max_iter=9)
    assert capped.iterations == 9


def test_dense_defaults_and_relative_change():
    """The stopping rule is the largest change of nu relative to its new value: measurement
    weights far from 1 make nu far from 1, which a change not divided by nu would miss."""
    rng = np.random.default_rng(3)
    w_hit, w_miss, w_new = blocks(rng, 1, 4)
    i, j = np.nonzero(w_hit)
    for scale in (1e-3, 1.0, 1e3):
        dense = lbp_marginals(w_hit * scale, w_miss, w_new * scale)
        explicit = lbp_marginals(w_hit * scale, w_miss, w_new * scale, tol=1e-7, max_iter=1000)
        sparse = lbp_sparse(i, j, w_hit[i, j] * scale, w_miss, w_new * scale)
        assert dense.iterations == explicit.iterations == sparse.iterations > 2
        coarse = lbp_marginals(w_hit * scale, w_miss, w_new * scale, tol=1e-3)
        assert coarse.iterations < dense.iterations


def test_clusters_are_connected_components_of_the_pairs():
    """Objects 0, 1 share measurement 0; object 2 takes measurement 1; object 3 and
    measurement 2 are in no pair and make a cluster each (8 nodes in 4 clusters)."""
    rows, cols = np.array([0, 1, 2, 1]), np.array([0, 0, 1, 3])
    count, cluster = lbp_module.clusters_of(rows, cols, 4, 4)
    assert count == 4  # {o0, o1, m0, m3}, {o2, m1}, {o3}, {m2}
    assert cluster[0] == cluster[1] == cluster[3] != cluster[2]
    assert cluster.shape == (4,)


def test_clusters_are_scipys_connected_components_numbered_alike():
    """The compiled union-find against scipy.sparse.csgraph.connected_components on 300 random
    bipartite graphs (isolated nodes included): the same count and the same label per pair,
    numbered by each component's lowest node."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(5)
    for _ in range(300):
        n, m = (int(v) for v in rng.integers(1, 40, 2))
        pairs = sorted({(int(rng.integers(n)), int(rng.integers(m)))
                        for _ in range(int(rng.integers(0, 80)))})
        rows = np.array([p[0] for p in pairs], dtype=np.int64)
        cols = np.array([p[1] for p in pairs], dtype=np.int64)
        graph = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, n + cols)),
                           shape=(n + m, n + m))
        count, node = connected_components(graph, directed=False)
        got_count, got = lbp_module.clusters_of(rows, cols, n, m)
        assert got_count == count
        np.testing.assert_array_equal(got, node[rows])


def test_a_pair_outside_the_graph_is_refused():
    with pytest.raises(IndexError, match="outside 2 x 3"):
        lbp_module.clusters_of(np.array([0, 2]), np.array([0, 0]), 2, 3)


def test_clusters_from_exactly_cluster_min_pairs_and_exact_fixed_points():
    """256 separate pairs (CLUSTER_MIN_PAIRS): 256 clusters, each a one-to-one problem whose
    messages stop changing at the second iteration. With tol 0 a change of 0 is not below
    it, so no cluster is frozen and BP runs to max_iter; with the default tolerance every
    cluster stops at iteration 2."""
    E = lbp_module.CLUSTER_MIN_PAIRS
    rng = np.random.default_rng(0)
    w_hit, w_miss, w_new = rng.uniform(0.1, 1.0, E), rng.uniform(0.1, 1.0, E), \
        rng.uniform(0.1, 0.9, E)
    pairs = np.arange(E)
    marg = lbp_sparse(pairs, pairs, w_hit, w_miss, w_new, tol=0.0, max_iter=40)
    assert (marg.clusters, marg.iterations) == (E, 40)
    marg = lbp_sparse(pairs, pairs, w_hit, w_miss, w_new)
    assert (marg.clusters, marg.iterations) == (E, 2)
    np.testing.assert_allclose(marg.p_hit, w_hit / (w_hit + w_miss * w_new), rtol=1e-13)
    # dyadic weights: the messages are exact from the first iteration (a change of exactly 0)
    half, one = np.full(E, 0.5), np.ones(E)
    assert lbp_sparse(pairs, pairs, half, one, one, tol=0.0, max_iter=40).iterations == 40
    assert lbp_sparse(pairs, pairs, half, one, one).iterations == 1
    one_less = lbp_sparse(pairs[1:], pairs[1:], w_hit[1:], w_miss, w_new)
    assert one_less.clusters == 1


def test_one_cluster_kernel_is_the_clustered_path_on_one_cluster(monkeypatch):
    """Below CLUSTER_MIN_PAIRS the pairs run as one cluster in one compiled call; on a graph
    that is one connected cluster that call gives the clustered path's numbers to the bit
    (same messages, same order of the sums)."""
    rng = np.random.default_rng(7)
    n, m = 6, 5
    w_hit = rng.uniform(0.1, 1.0, (n, m)) * (rng.random((n, m)) < 0.6)
    w_hit[np.arange(n), np.arange(n) % m] = 0.7  # every object and measurement connected
    w_hit[0, :] = 0.3
    w_miss, w_new = rng.uniform(0.1, 1.0, n), rng.uniform(0.05, 0.5, m)
    i, j = np.nonzero(w_hit)
    small = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=1e-9)
    monkeypatch.setattr(lbp_module, "CLUSTER_MIN_PAIRS", 1)
    clustered = lbp_sparse(i, j, w_hit[i, j], w_miss, w_new, tol=1e-9)
    assert clustered.clusters == small.clusters == 1
    assert small.iterations == clustered.iterations > 1
    for a, b in ((small.p_hit, clustered.p_hit), (small.p_miss, clustered.p_miss),
                 (small.p_new, clustered.p_new)):
        assert np.array_equal(a, b)
