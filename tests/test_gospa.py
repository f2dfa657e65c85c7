"""GOSPA (alpha = 2): equal to brute force over every partial assignment; the split adds up."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from occtrack.metrics.gospa import Gospa, euclidean, gospa, gospa_from_distances, iou


def partial_assignments(n: int, m: int):
    """Every injective partial map from n truths to m estimates, as lists of (i, j) pairs."""
    for k in range(min(n, m) + 1):
        for rows in itertools.combinations(range(n), k):
            for cols in itertools.permutations(range(m), k):
                yield list(zip(rows, cols, strict=True))


def brute_force(d: np.ndarray, c: float, p: float) -> float:
    """The definition: min over partial assignments gamma of
    sum_gamma d^p + c^p / 2 (n + m - 2 |gamma|), to the power 1 / p."""
    n, m = d.shape
    best = min(sum(d[i, j] ** p for i, j in gamma) + c**p / 2 * (n + m - 2 * len(gamma))
               for gamma in partial_assignments(n, m))
    return best ** (1 / p)


def check_split(g: Gospa, d: np.ndarray, c: float, p: float) -> None:
    n, m = d.shape
    assert g.localisation + g.missed + g.false == pytest.approx(g.total**p, rel=1e-12)
    assert g.matched + g.n_missed == n
    assert g.matched + g.n_false == m
    assert g.missed == pytest.approx(c**p / 2 * g.n_missed)
    assert g.false == pytest.approx(c**p / 2 * g.n_false)
    assert g.localisation <= g.matched * c**p


@pytest.mark.parametrize("c", [0.5, 1.0, 3.0])
@pytest.mark.parametrize("p", [1.0, 2.0, 3.0])
def test_equals_brute_force_on_random_sets(c, p):
    rng = np.random.default_rng(int(10 * c + p))
    for _ in range(40):
        n, m = rng.integers(0, 5, size=2)
        truth, est = rng.uniform(0, 4, (n, 2)), rng.uniform(0, 4, (m, 2))
        d = euclidean(truth, est) if n and m else np.zeros((n, m))
        g = gospa(truth, est, "euclidean", c, p)
        assert g.total == pytest.approx(brute_force(d, c, p), rel=1e-12, abs=1e-12)
        check_split(g, d, c, p)


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_infinite_distances_never_match(p):
    rng = np.random.default_rng(7)
    for _ in range(30):
        n, m = rng.integers(1, 5, size=2)
        d = rng.uniform(0, 2, (n, m))
        d[rng.random((n, m)) < 0.4] = np.inf
        g = gospa_from_distances(d, c=1.5, p=p)
        assert g.total == pytest.approx(brute_force(d, 1.5, p), rel=1e-12)
        check_split(g, d, 1.5, p)


def test_one_minus_iou_boxes_as_the_paper_scores_them():
    rng = np.random.default_rng(3)
    for _ in range(40):
        n, m = rng.integers(0, 5, size=2)
        truth = np.column_stack([rng.uniform(0, 30, (n, 2)), rng.uniform(5, 15, (n, 2))])
        est = np.column_stack([rng.uniform(0, 30, (m, 2)), rng.uniform(5, 15, (m, 2))])
        d = 1 - iou(truth, est) if n and m else np.zeros((n, m))
        g = gospa(truth, est, "iou", c=1.0, p=1.0)
        assert g.total == pytest.approx(brute_force(d, 1.0, 1.0), rel=1e-12, abs=1e-12)
        check_split(g, d, 1.0, 1.0)


def test_hand_computed_frame():
    truth = np.array([[0, 0, 10, 10], [100, 0, 10, 10]], float)
    est = np.array([[2, 0, 10, 10], [300, 0, 10, 10], [0, 50, 10, 10]], float)
    g = gospa(truth, est, "iou", c=1.0, p=1.0)
    # one pair at 1 - 8/12, one truth missed, two estimates false: 1/3 + 1/2 + 2/2
    assert g.total == pytest.approx(1 / 3 + 0.5 + 1.0)
    assert (g.matched, g.n_missed, g.n_false) == (1, 1, 2)
    assert g.localisation == pytest.approx(1 / 3)


def test_metric_properties():
    rng = np.random.default_rng(11)
    for _ in range(30):
        x, y, z = (rng.uniform(0, 3, (rng.integers(0, 4), 2)) for _ in range(3))
        dxy, dyx = gospa(x, y, c=2.0, p=2.0).total, gospa(y, x, c=2.0, p=2.0).total
        assert dxy == pytest.approx(dyx)
        assert gospa(x, x, c=2.0, p=2.0).total == 0.0
        dxz, dzy = gospa(x, z, c=2.0, p=2.0).total, gospa(z, y, c=2.0, p=2.0).total
        assert dxy <= dxz + dzy + 1e-12


def test_empty_sets():
    assert gospa(np.empty((0, 2)), np.empty((0, 2))).total == 0.0
    g = gospa(np.zeros((3, 2)), np.empty((0, 2)), c=2.0, p=2.0)
    assert g.total == pytest.approx(np.sqrt(3 * 2.0**2 / 2))
    assert (g.n_missed, g.n_false) == (3, 0)


def test_sum_over_frames_adds_every_part():
    a = gospa_from_distances(np.array([[0.2, 1.0]]), c=1.0)
    b = gospa_from_distances(np.array([[0.5], [0.9]]), c=1.0)
    s = a + b
    assert s.total == pytest.approx(a.total + b.total)
    assert (s.matched, s.n_missed, s.n_false) == (a.matched + b.matched,
                                                  a.n_missed + b.n_missed,
                                                  a.n_false + b.n_false)


def test_bad_input():
    with pytest.raises(ValueError, match="c > 0"):
        gospa_from_distances(np.zeros((1, 1)), c=0.0)
    with pytest.raises(ValueError, match="NaN"):
        gospa_from_distances(np.array([[np.nan]]), c=1.0)
    with pytest.raises(ValueError, match="unknown distance"):
        gospa(np.zeros((1, 2)), np.zeros((1, 2)), "manhattan")
