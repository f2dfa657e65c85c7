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

from dataclasses import dataclass

import numpy as np

from occtrack.spatial import DENSE_PAIRS, overlapping_pairs


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
        return self._pairwise(hidden[:, None], occluders[None, :])

    def _pairwise(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """p of hidden boxes a and occluders b, broadcast against each other."""
        overlap = np.minimum(a[..., 1], b[..., 1]) - np.maximum(a[..., 0], b[..., 0])
        np.maximum(overlap, 0.0, out=overlap)
        size_a = np.maximum(a[..., 1] - a[..., 0], 1e-9)
        cover = overlap[..., 0] * overlap[..., 1] / (size_a[..., 0] * size_a[..., 1])
        height_b = np.maximum(b[..., 1, 1] - b[..., 1, 0], 1e-9)
        gap = (b[..., 1, 1] - a[..., 1, 1]) / height_b
        order = (gap - self.ramp_zero) / (self.ramp_one - self.ramp_zero)
        return np.clip(self.gain * cover, 0.0, 1.0) * np.clip(order, 0.0, 1.0)

    def visible(self, hidden: np.ndarray, occluders: np.ndarray,
                weights: np.ndarray | None = None, skip: np.ndarray | None = None,
                sparse: bool = True) -> np.ndarray:
        """prod_n (1 - w_n p[k, n]) for each hidden box k: the probability that no occluder
        hides it, occluder n counting with weight w_n (1 when None) and never the occluder
        skip[k] (-1: none). `sparse` False computes the full table."""
        K, N = len(hidden), len(occluders)
        if not sparse or K * N <= DENSE_PAIRS:
            p = self(hidden, occluders)
            if weights is not None:
                p = p * weights
            if skip is not None:
                p[skip[:, None] == np.arange(N)[None, :]] = 0.0
            return np.prod(1.0 - p, axis=-1)
        k, n = overlapping_pairs(hidden, occluders)
        if skip is not None:
            keep = skip[k] != n
            k, n = k[keep], n[keep]
        p = self._pairwise(hidden[k], occluders[n])
        if weights is not None:
            p = p * weights[n]
        with np.errstate(divide="ignore"):
            log_visible = np.bincount(k, weights=np.log1p(-np.minimum(p, 1.0)), minlength=K)
        return np.exp(log_visible)


def combine(p: np.ndarray) -> np.ndarray:
    """Probability of being hidden by at least one of independent occluders: 1 - prod(1 - p)."""
    return 1.0 - np.prod(1.0 - p, axis=-1)
