"""Where new objects come from: Poisson births at the image edges plus a spread-out term.

Each step adds to the Poisson intensity of undetected objects five Gaussian components:
one per image edge (centre on the edge, moving inward at `inward_speed`, anywhere along it),
each with mass edge_rate * dt, and one spread over the whole image with mass spread_rate * dt
for objects that appear in the middle (from behind an obstacle, say); at the first frame the
spread component also carries the objects already in view. Box sizes follow a prior
(mean and spread of half-widths and half-heights) that the tracker keeps up to date from the
detections it has seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class EdgeBirths:
    image_size: tuple[float, float]
    inward_speed: float
    speed_std: float

    def components(self, edge_mass: float, spread_mass: float, size_mean: np.ndarray,
                   size_std: np.ndarray,
                   speed_unit: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Masses (5,), means (5, 2, 3) and covariances (5, 2, 3, 3) of the birth components:
        left, right, top, bottom edge (each `edge_mass`), then the spread one. Speeds are in
        units of `speed_unit` px (the box tracker's: the prior's box height)."""
        W, H = self.image_size
        extent = np.array([W, H])
        means = np.zeros((5, 2, 3))
        sds = np.zeros((5, 2, 3))
        means[:, :, 0] = extent / 2.0
        sds[:, :, 0] = extent / 2.0
        sds[:, :, 1] = self.speed_std * speed_unit
        means[:, :, 2] = size_mean
        sds[:, :, 2] = size_std
        for edge, (axis, side) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1)]):
            means[edge, axis, 0] = side * extent[axis]
            sds[edge, axis, 0] = size_mean[axis]
            means[edge, axis, 1] = self.inward_speed * speed_unit * (1 - 2 * side)
        covs = np.zeros((5, 2, 3, 3))
        idx = np.arange(3)
        covs[:, :, idx, idx] = sds**2
        return np.array([edge_mass] * 4 + [spread_mass], dtype=float), means, covs
