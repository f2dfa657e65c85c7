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

from occtrack.models._models import _components


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
        return _components(np.asarray(self.image_size, dtype=float), self.inward_speed,
                           self.speed_std, float(edge_mass), float(spread_mass),
                           np.asarray(size_mean, dtype=float), np.asarray(size_std, dtype=float),
                           float(speed_unit))
