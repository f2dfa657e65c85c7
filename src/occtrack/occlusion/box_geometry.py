"""When one image box hides another: the box geometry both box occlusion models share.

Occluder box B hides box A with probability (DESIGN section 2.2, from the authors' prototype)

    p(A hidden by B) = clip(gain * area(A & B) / area(A), 0, 1)
                       * ramp((bottom_B - bottom_A) / height_B)

ramp rising linearly from 0 at `ramp_zero` (-0.1) to 1 at `ramp_one` (0.25): for people on a
ground plane seen by an upright camera, a lower bottom edge means nearer the camera, so a box is
hidden only by boxes whose bottom is lower in the image. With gain 2, a box half covered counts
as hidden. Several occluders combine as 1 - prod(1 - p).

Boxes are edge arrays (..., 2, 2): [axis, low/high], axis 0 horizontal and 1 vertical.

Only boxes that overlap can hide one another, so `visible` combines the occluders over the
overlapping pairs alone (`occtrack.spatial`): the same numbers as the full K x N table, at a
cost that follows the overlaps rather than K N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from occtrack.jit import njit
from occtrack.spatial import DENSE_PAIRS, overlapping_pairs

NO_WEIGHTS = np.zeros(0)
NO_SKIP = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class BoxOcclusionGeometry:
    gain: float = 2.0
    ramp_zero: float = -0.1
    ramp_one: float = 0.25

    def __post_init__(self) -> None:
        if self.gain <= 0:
            raise ValueError("occlusion gain must be positive")
        if not self.ramp_one > self.ramp_zero:
            raise ValueError("occlusion ramp must rise: ramp_one > ramp_zero")

    def __call__(self, hidden: np.ndarray, occluders: np.ndarray) -> np.ndarray:
        """p[k, n]: probability that box `hidden[k]` is hidden by box `occluders[n]`."""
        return _table(np.asarray(hidden, dtype=float), np.asarray(occluders, dtype=float),
                      self.gain, self.ramp_zero, self.ramp_one)

    def visible(self, hidden: np.ndarray, occluders: np.ndarray,
                weights: np.ndarray | None = None, skip: np.ndarray | None = None,
                sparse: bool = True) -> np.ndarray:
        """prod_n (1 - w_n p[k, n]) for each hidden box k: the probability that no occluder
        hides it, occluder n counting with weight w_n (1 when None) and never the occluder
        skip[k] (-1: none). `sparse` False computes the full table."""
        K, N = len(hidden), len(occluders)
        # (empty weights: all 1; empty skip: none)
        w = NO_WEIGHTS if weights is None else np.asarray(weights, dtype=float)
        never = NO_SKIP if skip is None else np.asarray(skip, np.int64)
        hidden = np.asarray(hidden, dtype=float)
        occluders = np.asarray(occluders, dtype=float)
        if not sparse or K * N <= DENSE_PAIRS:
            return _visible_dense(hidden, occluders, w, never, self.gain, self.ramp_zero,
                                  self.ramp_one)
        k, n = overlapping_pairs(hidden, occluders)
        return _visible_pairs(hidden, occluders, k, n, w, never, self.gain, self.ramp_zero,
                              self.ramp_one)

    def hidden_by_seen(self, boxes: np.ndarray, z: np.ndarray,
                       sparse: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(q, h): 1 - `visible(boxes, z)`, how surely the seen boxes z hide each box, and
        1 - `visible(z, z)` with no box hiding itself, how surely the others hide each z_j
        (measurement-wise occlusion's two terms); one compiled call where both tables are
        small enough to take every pair."""
        boxes, z = np.asarray(boxes, dtype=float), np.asarray(z, dtype=float)
        K, M = len(boxes), len(z)
        if not sparse or (K * M <= DENSE_PAIRS and M * M <= DENSE_PAIRS):
            return _hidden_dense(boxes, z, self.gain, self.ramp_zero, self.ramp_one)
        return (1.0 - self.visible(boxes, z, sparse=sparse),
                1.0 - self.visible(z, z, skip=np.arange(M), sparse=sparse))


@njit
def _hidden_dense(boxes, z, gain, ramp_zero, ramp_one):
    """`hidden_by_seen` over every pair: (1 - prod_n (1 - p[k, n]), the same for z_j over the
    other seen boxes)."""
    none = np.zeros(0)
    q = 1.0 - _visible_dense(boxes, z, none, np.zeros(0, dtype=np.int64), gain, ramp_zero,
                             ramp_one)
    h = 1.0 - _visible_dense(z, z, none, np.arange(len(z)), gain, ramp_zero, ramp_one)
    return q, h


@njit
def _hides(a, b, gain, ramp_zero, ramp_one):
    """p(box a hidden by box b): the formula at the top of this module."""
    cover = 1.0
    for axis in range(2):
        overlap = max(min(a[axis, 1], b[axis, 1]) - max(a[axis, 0], b[axis, 0]), 0.0)
        cover *= overlap / max(a[axis, 1] - a[axis, 0], 1e-9)
    gap = (b[1, 1] - a[1, 1]) / max(b[1, 1] - b[1, 0], 1e-9)
    order = (gap - ramp_zero) / (ramp_one - ramp_zero)
    return min(max(gain * cover, 0.0), 1.0) * min(max(order, 0.0), 1.0)


@njit
def _table(hidden, occluders, gain, ramp_zero, ramp_one):
    """p[k, n] for every pair."""
    out = np.empty((len(hidden), len(occluders)))
    for k in range(len(hidden)):
        for n in range(len(occluders)):
            out[k, n] = _hides(hidden[k], occluders[n], gain, ramp_zero, ramp_one)
    return out


@njit
def _visible_dense(hidden, occluders, weights, skip, gain, ramp_zero, ramp_one):
    """prod_n (1 - w_n p[k, n]) over every occluder n but skip[k]."""
    out = np.ones(len(hidden))
    for k in range(len(hidden)):
        for n in range(len(occluders)):
            if len(skip) == 0 or n != skip[k]:
                p = _hides(hidden[k], occluders[n], gain, ramp_zero, ramp_one)
                out[k] *= 1.0 - (weights[n] * p if len(weights) else p)
    return out


@njit
def _visible_pairs(hidden, occluders, k, n, weights, skip, gain, ramp_zero, ramp_one):
    """The same product over the listed (k, n) pairs only (the others have p = 0), summed
    as logarithms."""
    log_visible = np.zeros(len(hidden))
    for e in range(len(k)):
        if len(skip) == 0 or n[e] != skip[k[e]]:
            p = _hides(hidden[k[e]], occluders[n[e]], gain, ramp_zero, ramp_one)
            if len(weights):
                p *= weights[n[e]]
            log_visible[k[e]] += math.log1p(-min(p, 1.0)) if p < 1.0 else -math.inf
    return np.exp(log_visible)


def combine(p: np.ndarray) -> np.ndarray:
    """Probability of being hidden by at least one of independent occluders: 1 - prod(1 - p)."""
    return 1.0 - np.prod(1.0 - p, axis=-1)
