"""Boxes for the occlusion tests, written as edges and turned into filter states."""

from __future__ import annotations

import numpy as np


def edges(x0, x1, y0, y1):
    return np.array([[x0, x1], [y0, y1]], dtype=float)


def states(*boxes):
    """(centre, velocity 0, half-size) per axis from edge boxes."""
    e = np.array(boxes)
    return np.stack([(e[..., 0] + e[..., 1]) / 2, np.zeros(e.shape[:2]),
                     (e[..., 1] - e[..., 0]) / 2], axis=-1)
