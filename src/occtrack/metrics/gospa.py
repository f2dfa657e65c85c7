"""Generalized optimal sub-pattern assignment (GOSPA), alpha = 2.

Rahmathullah, Garcia-Fernandez and Svensson (2017):

    d_p^(c)(X, Y) = ( min_gamma sum_{(i,j) in gamma} d(x_i, y_j)^p
                      + c^p / 2 (|X| + |Y| - 2 |gamma|) )^(1/p)

over partial assignments gamma whose pairs lie closer than c. The minimisation is a rectangular
assignment on min(d, c)^p (scipy's linear_sum_assignment); a pair at distance c or more costs the
same as one missed plus one false object and is counted as such. The metric itself is a few
lines on top of scipy, and the split into localisation / missed / false is what no library
returns, so it is written here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.spatial import iou


@dataclass(frozen=True)
class Gospa:
    """GOSPA and its split. `localisation`, `missed` and `false` are costs in units of
    distance^p; they add up to `total ** p`. Counts: matched pairs, missed true objects, false
    estimates."""

    total: float
    localisation: float
    missed: float
    false: float
    matched: int
    n_missed: int
    n_false: int

    def __add__(self, other: Gospa) -> Gospa:
        """Sum over frames for p = 1 (the way the paper reports it)."""
        return Gospa(self.total + other.total, self.localisation + other.localisation,
                     self.missed + other.missed, self.false + other.false,
                     self.matched + other.matched, self.n_missed + other.n_missed,
                     self.n_false + other.n_false)


def gospa_from_distances(distances: np.ndarray, c: float, p: float = 1.0) -> Gospa:
    """GOSPA from the (n_true, n_estimated) matrix of base distances (inf allowed)."""
    d = np.asarray(distances, dtype=float)
    if d.ndim != 2:
        raise ValueError("distances must be a 2-D (true x estimated) matrix")
    if np.isnan(d).any():
        raise ValueError("distances contain NaN")
    if c <= 0 or p < 1:
        raise ValueError("GOSPA needs c > 0 and p >= 1")
    n_true, n_est = d.shape
    half = c**p / 2.0
    if n_true and n_est:
        cost = np.minimum(d, c) ** p
        rows, cols = linear_sum_assignment(cost)
        real = d[rows, cols] < c
        localisation = float(np.sum(d[rows, cols][real] ** p))
        matched = int(real.sum())
    else:
        localisation, matched = 0.0, 0
    n_missed, n_false = n_true - matched, n_est - matched
    missed, false = half * n_missed, half * n_false
    total = (localisation + missed + false) ** (1.0 / p)
    return Gospa(total, localisation, missed, false, matched, n_missed, n_false)


def gospa(truth: np.ndarray, estimates: np.ndarray,
          distance: Callable[[np.ndarray, np.ndarray], np.ndarray] | str = "euclidean",
          c: float = 1.0, p: float = 1.0) -> Gospa:
    """GOSPA between two sets given as arrays of rows. `distance` is "euclidean", "iou"
    (1 - IoU of left, top, width, height boxes) or a callable (A, B) -> (len(A), len(B))."""
    truth, estimates = _rows(truth), _rows(estimates)
    if callable(distance):
        fn = distance
    elif distance in DISTANCES:
        fn = DISTANCES[distance]
    else:
        raise ValueError(f"unknown distance {distance!r}; choose from {sorted(DISTANCES)} "
                         f"or pass a callable")
    if len(truth) and len(estimates):
        d = fn(truth, estimates)
    else:
        d = np.zeros((len(truth), len(estimates)))
    return gospa_from_distances(d, c, p)


def _rows(x) -> np.ndarray:
    """One row per set member; an empty set may come as shape (0,) or (0, k)."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 2:
        return x
    return x.reshape(len(x), -1) if x.size else np.zeros((len(x), 0))


def euclidean(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))


def one_minus_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return 1.0 - iou(a, b)


DISTANCES = {"euclidean": euclidean, "iou": one_minus_iou}
