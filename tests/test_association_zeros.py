"""Zero miss and new weights are hard constraints (an object surely detected, a measurement
surely an object's): the dense and the sparse loopy BP against exact enumeration on them,
the forced pairs by hand, and the errors when nothing can meet a constraint."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.association import exact_marginals, lbp_marginals, lbp_sparse
from occtrack.association.lbp import CLUSTER_MIN_PAIRS, forced_pairs
from test_lbp import max_error, random_forest, random_problem


def sparse_of(w_hit, w_miss, w_new, **kw):
    """lbp_sparse on the positive pairs of a dense problem, its p_hit put back in (n, m)."""
    rows, cols = np.nonzero(w_hit > 0)
    marg = lbp_sparse(rows, cols, w_hit[rows, cols], w_miss, w_new, **kw)
    p_hit = np.zeros(w_hit.shape)
    p_hit[rows, cols] = marg.p_hit
    return type("Dense", (), {"p_hit": p_hit, "p_miss": marg.p_miss, "p_new": marg.p_new})


def test_a_measurement_only_one_object_can_explain_is_that_objects():
    """w_new = 0: measurement 0 must be the object's, whatever the weights; before, the
    message 1 / (w_new + 0) overflowed and every marginal was NaN."""
    problem = np.array([[0.5]]), np.array([0.5]), np.array([0.0])
    for marg in (lbp_marginals(*problem), sparse_of(*problem), exact_marginals(*problem)):
        assert (marg.p_hit.tolist(), marg.p_miss.tolist(), marg.p_new.tolist()) == (
            [[1.0]], [0.0], [0.0])


def test_forced_pairs_chain_by_hand():
    """Measurement 1 can only be object 0's, so object 0 takes it; measurement 0 is then left
    to object 1 alone: the one association of positive weight is (0 -> 1, 1 -> 0)."""
    problem = np.array([[0.5, 0.2], [0.3, 0.0]]), np.array([0.5, 0.4]), np.array([0.0, 0.0])
    rows, cols = np.nonzero(problem[0] > 0)
    taken, objects, measurements = forced_pairs(rows, cols, problem[1], problem[2])
    assert np.stack([rows[taken], cols[taken]], axis=1).tolist() == [[0, 1], [1, 0]]
    assert not objects.any() and not measurements.any()
    for marg in (lbp_marginals(*problem), sparse_of(*problem), exact_marginals(*problem)):
        assert marg.p_hit.tolist() == [[0.0, 1.0], [1.0, 0.0]]
        assert marg.p_miss.tolist() == [0.0, 0.0] and marg.p_new.tolist() == [0.0, 0.0]


def test_a_surely_detected_object_with_two_choices_splits_between_them():
    """w_miss = 0 with two measurements: p_hit is w_hit_j / w_new_j over its sum (each
    association leaves the other measurement new), with no forced pair."""
    problem = np.array([[0.6, 0.2]]), np.array([0.0]), np.array([0.3, 0.4])
    a, b = 0.6 * 0.4, 0.2 * 0.3
    for marg in (lbp_marginals(*problem), sparse_of(*problem), exact_marginals(*problem)):
        np.testing.assert_allclose(marg.p_hit, [[a / (a + b), b / (a + b)]], rtol=1e-12)
        np.testing.assert_allclose(marg.p_miss, [0.0], atol=1e-140)


def forest_with_zeros(rng, low: int, high: int, share: float):
    """A tree-shaped problem of low to high - 1 objects and measurements whose miss and new
    weights are each 0 with probability `share`."""
    n, m = int(rng.integers(low, high)), int(rng.integers(low, high))
    w_hit, w_miss, w_new = random_problem(rng, n, m, random_forest(rng, n, m))
    w_miss[rng.random(n) < share] = 0.0
    w_new[rng.random(m) < share] = 0.0
    return w_hit, w_miss, w_new


@pytest.mark.parametrize("seed", range(60))
def test_zeros_on_trees_are_exact(seed):
    """Tree-shaped problems (where BP is exact) with random miss and new weights set to 0:
    the dense and the sparse form agree with enumeration to 1e-9 where some association has
    positive weight, and all three raise where none has."""
    w_hit, w_miss, w_new = forest_with_zeros(np.random.default_rng(1000 + seed), 1, 6, 0.4)
    try:
        exact = exact_marginals(w_hit, w_miss, w_new)
    except ValueError:
        for solve in (lbp_marginals, sparse_of):
            with pytest.raises(ValueError, match="no association has positive weight"):
                solve(w_hit, w_miss, w_new)
        return
    for marg in (lbp_marginals(w_hit, w_miss, w_new, tol=1e-13, max_iter=10_000),
                 sparse_of(w_hit, w_miss, w_new, tol=1e-13, max_iter=10_000)):
        assert max_error(marg, exact) < 1e-9
        np.testing.assert_allclose(marg.p_miss + marg.p_hit.sum(axis=1), 1.0, rtol=1e-12)
        np.testing.assert_allclose(marg.p_new + marg.p_hit.sum(axis=0), 1.0, rtol=1e-12)


def test_zeros_in_many_clusters_are_exact():
    """The sparse form's cluster-by-cluster path (at least CLUSTER_MIN_PAIRS pairs): 120
    independent tree problems side by side, with zeros, each against its own enumeration."""
    rng = np.random.default_rng(7)
    blocks, n0, m0 = [], 0, 0
    rows, cols, hits, misses, news = [], [], [], [], []
    while len(blocks) < 120:
        w_hit, w_miss, w_new = forest_with_zeros(rng, 2, 5, 0.3)
        n, m = len(w_miss), len(w_new)
        try:
            exact = exact_marginals(w_hit, w_miss, w_new)
        except ValueError:
            continue
        r, c = np.nonzero(w_hit > 0)
        blocks.append((n0, m0, len(np.concatenate(rows)) if rows else 0, r, c, exact))
        rows.append(r + n0)
        cols.append(c + m0)
        hits.append(w_hit[r, c])
        misses.append(w_miss)
        news.append(w_new)
        n0, m0 = n0 + n, m0 + m
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    assert len(rows) >= CLUSTER_MIN_PAIRS
    marg = lbp_sparse(rows, cols, np.concatenate(hits), np.concatenate(misses),
                      np.concatenate(news), tol=1e-13, max_iter=10_000)
    for n0, m0, e0, r, c, exact in blocks:
        np.testing.assert_allclose(marg.p_hit[e0:e0 + len(r)], exact.p_hit[r, c], atol=1e-9)
        np.testing.assert_allclose(marg.p_miss[n0:n0 + len(exact.p_miss)], exact.p_miss,
                                   atol=1e-9)
        np.testing.assert_allclose(marg.p_new[m0:m0 + len(exact.p_new)], exact.p_new, atol=1e-9)


@pytest.mark.parametrize("problem, message", [
    ((np.array([[0.5, 0.0]]), np.array([0.5]), np.array([0.2, 0.0])),
     "measurement 1 has w_new = 0 and no object left to produce it"),
    ((np.array([[0.0], [0.4]]), np.array([0.0, 0.5]), np.array([0.2])),
     "object 0 has w_miss = 0 and no measurement left to produce"),
    ((np.array([[0.5, 0.4]]), np.array([0.5]), np.array([0.0, 0.0])),
     "object 0 is all that is left to pair with both measurements 0 and 1"),
    ((np.array([[0.5], [0.4]]), np.array([0.0, 0.0]), np.array([0.3])),
     "measurement 0 is all that is left to pair with both objects 0 and 1"),
])
def test_impossible_constraints_are_named(problem, message):
    with pytest.raises(ValueError, match="no association has positive weight"):
        exact_marginals(*problem)
    for solve in (lbp_marginals, sparse_of):
        with pytest.raises(ValueError, match=message):
            solve(*problem)


@pytest.mark.parametrize("which, value", [(0, -0.1), (1, np.nan), (2, np.inf)])
def test_negative_or_non_finite_weights_are_refused(which, value):
    problem = [np.array([[0.5]]), np.array([0.5]), np.array([0.0])]
    problem[which] = np.full_like(problem[which], value)
    name = ("w_hit", "w_miss", "w_new")[which]
    with pytest.raises(ValueError, match=f"{name} must hold finite weights >= 0"):
        lbp_marginals(*problem)


def test_the_sparse_form_checks_the_weights_where_it_meets_a_zero_or_less():
    """(The filter's own weights are positive by construction; checking them every frame
    would cost more than a small cluster's BP.)"""
    with pytest.raises(ValueError, match="w_miss must hold finite weights >= 0, not -0.1"):
        lbp_sparse([0], [0], [0.5], [-0.1], [0.3])
    with pytest.raises(ValueError, match="w_hit must hold finite weights >= 0, not nan"):
        lbp_sparse([0], [0], [np.nan], [0.5], [0.0])
