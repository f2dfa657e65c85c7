"""Loopy belief propagation against exact enumeration of every association."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.association import exact_marginals, lbp_marginals


def random_forest(rng, n, m):
    """w_hit pattern of a bipartite forest: each node after the first joins one earlier node
    of the other kind (or starts a new tree), so the factor graph has no loop."""
    mask = np.zeros((n, m), dtype=bool)
    objects, measurements = [0], []
    for node in rng.permutation([("o", i) for i in range(1, n)] + [("m", j) for j in range(m)]):
        kind, index = node[0], int(node[1])
        pool = measurements if kind == "o" else objects
        if pool and rng.random() < 0.85:
            other = pool[rng.integers(len(pool))]
            if kind == "o":
                mask[index, other] = True
            else:
                mask[other, index] = True
        (objects if kind == "o" else measurements).append(index)
    return mask


def random_problem(rng, n, m, mask=None):
    r = rng.uniform(0.05, 1.0, n)
    w_hit = r[:, None] * rng.uniform(0.0, 1.0, (n, m)) * 0.9
    if mask is not None:
        w_hit = w_hit * mask
    w_miss = 1.0 - r + 0.1 * r
    w_new = rng.uniform(0.01, 1.0, m)
    return w_hit, w_miss, w_new


def max_error(a, b):
    return max(np.abs(a.p_hit - b.p_hit).max(initial=0), np.abs(a.p_miss - b.p_miss).max(),
               np.abs(a.p_new - b.p_new).max(initial=0))


@pytest.mark.parametrize("seed", range(40))
def test_exact_on_tree_structured_problems(seed):
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(1, 6)), int(rng.integers(1, 6))
    problem = random_problem(rng, n, m, random_forest(rng, n, m))
    lbp = lbp_marginals(*problem, tol=1e-13, max_iter=10_000)
    assert max_error(lbp, exact_marginals(*problem)) < 1e-9


def test_within_stated_bound_on_small_loopy_problems():
    """Fully connected problems up to 4 x 4 (every pair may associate, so the graph has
    loops): over 200 seeded problems the largest error of any marginal stays below 0.15 and
    the mean largest error below 0.03 (measured: 0.10 and 0.017)."""
    rng = np.random.default_rng(1)
    errors = []
    for _ in range(200):
        problem = random_problem(rng, int(rng.integers(2, 5)), int(rng.integers(2, 5)))
        lbp = lbp_marginals(*problem, tol=1e-12, max_iter=10_000)
        assert lbp.iterations < 10_000
        errors.append(max_error(lbp, exact_marginals(*problem)))
    assert max(errors) < 0.15
    assert np.mean(errors) < 0.03


def test_marginals_are_distributions_and_stop_on_tolerance():
    rng = np.random.default_rng(5)
    problem = random_problem(rng, 30, 25)
    coarse = lbp_marginals(*problem, tol=1e-3, max_iter=1000)
    fine = lbp_marginals(*problem, tol=1e-12, max_iter=1000)
    assert coarse.iterations < fine.iterations < 1000
    np.testing.assert_allclose(fine.p_miss + fine.p_hit.sum(axis=1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(fine.p_new + fine.p_hit.sum(axis=0), 1.0, rtol=1e-9)
    assert lbp_marginals(*problem, tol=0.0, max_iter=7).iterations == 7
