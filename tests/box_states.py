"""Boxes for the occlusion tests, written as edges and turned into filter states, and the
context an occlusion model is given."""

from __future__ import annotations

import numpy as np

from occtrack.models.box import BoxMeasurement
from occtrack.occlusion.base import OcclusionContext


def edges(x0, x1, y0, y1):
    return np.array([[x0, x1], [y0, y1]], dtype=float)


def states(*boxes):
    """(centre, velocity 0, half-size) per axis from edge boxes."""
    e = np.array(boxes)
    return np.stack([(e[..., 0] + e[..., 1]) / 2, np.zeros(e.shape[:2]),
                     (e[..., 1] - e[..., 0]) / 2], axis=-1)


def context(means, owner, existence, measurements, weights=None):
    """What the filter hands an occlusion model, for components `means` in a 100 x 100 image."""
    k = len(means)
    return OcclusionContext(means=means, covs=np.tile(np.eye(3), (k, 2, 1, 1)),
                            weights=np.ones(k) if weights is None else weights,
                            owner=np.asarray(owner), existence=np.asarray(existence, float),
                            measurements=measurements,
                            measurement_model=BoxMeasurement((100, 100)))
