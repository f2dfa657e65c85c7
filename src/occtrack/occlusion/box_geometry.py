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

The loops are compiled (`_occlusion.pyx`, its `_box_geometry.pxi`): `_hides` (the formula
above for one pair), `_table` (every pair), `_visible_dense` (the product over every
occluder), `_visible_pairs` (over the overlapping pairs only, summed as logarithms) and
`_hidden_dense` (`hidden_by_seen`'s two tables over every pair).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.occlusion._occlusion import (  # the compiled kernels: _box_geometry.pxi
    _hidden_dense,
    _table,
    _visible_dense,
    _visible_pairs,
)
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
        return _table(np.ascontiguousarray(hidden, dtype=float),
                      np.ascontiguousarray(occluders, dtype=float), self.gain, self.ramp_zero,
                      self.ramp_one)

    def visible(self, hidden: np.ndarray, occluders: np.ndarray,
                weights: np.ndarray | None = None, skip: np.ndarray | None = None,
                sparse: bool = True) -> np.ndarray:
        """prod_n (1 - w_n p[k, n]) for each hidden box k: the probability that no occluder
        hides it, occluder n counting with weight w_n (1 when None) and never the occluder
        skip[k] (-1: none). `sparse` False computes the full table."""
        K, N = len(hidden), len(occluders)
        # (empty weights: all 1; empty skip: none)
        # (C order throughout: the compiled kernels read the arrays in place)
        w = NO_WEIGHTS if weights is None else np.ascontiguousarray(weights, dtype=float)
        never = NO_SKIP if skip is None else np.ascontiguousarray(skip, np.int64)
        hidden = np.ascontiguousarray(hidden, dtype=float)
        occluders = np.ascontiguousarray(occluders, dtype=float)
        if not sparse or K * N <= DENSE_PAIRS:
            return _visible_dense(hidden, occluders, w, never, self.gain, self.ramp_zero,
                                  self.ramp_one)
        k, n = overlapping_pairs(hidden, occluders)  # (np.nonzero's: not in C order)
        return _visible_pairs(hidden, occluders, np.ascontiguousarray(k),
                              np.ascontiguousarray(n), w, never, self.gain, self.ramp_zero,
                              self.ramp_one)

    def hidden_by_seen(self, boxes: np.ndarray, z: np.ndarray,
                       sparse: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(q, h): 1 - `visible(boxes, z)`, how surely the seen boxes z hide each box, and
        1 - `visible(z, z)` with no box hiding itself, how surely the others hide each z_j
        (measurement-wise occlusion's two terms); one compiled call where both tables are
        small enough to take every pair."""
        boxes = np.ascontiguousarray(boxes, dtype=float)
        z = np.ascontiguousarray(z, dtype=float)
        K, M = len(boxes), len(z)
        if not sparse or (K * M <= DENSE_PAIRS and M * M <= DENSE_PAIRS):
            return _hidden_dense(boxes, z, self.gain, self.ramp_zero, self.ramp_one)
        return (1.0 - self.visible(boxes, z, sparse=sparse),
                1.0 - self.visible(z, z, skip=np.arange(M), sparse=sparse))


def combine(p: np.ndarray) -> np.ndarray:
    """Probability of being hidden by at least one of independent occluders: 1 - prod(1 - p)."""
    return 1.0 - np.prod(1.0 - p, axis=-1)
