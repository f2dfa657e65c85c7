"""Object-wise occlusion for image boxes, static expected-value approximation.

Paper eq. "misstermOWO": occlusion multiplies P_D by P(visible | x). The exact visibility
depends on every other object jointly; the expected-value approximation replaces each other
object i by its mean box, weighted by its existence r_i (only objects with r_i above
`min_existence`, 0.1 in the paper's prototype), and combines the occluders as independent:

    v_k = prod_{i != owner(k)} (1 - r_i p(box_k hidden by mean box_i))

An object never occludes itself; the Poisson part (objects not yet detected) occludes nothing.
"""

from __future__ import annotations

import numpy as np

from occtrack.occlusion.base import OcclusionContext, OcclusionTerms
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry


class ObjectWiseExpectedValue:
    name = "object-wise"

    def __init__(self, geometry: BoxOcclusionGeometry | None = None,
                 min_existence: float = 0.1):
        self.geometry = geometry or BoxOcclusionGeometry()
        self.min_existence = float(min_existence)

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        k = len(ctx.means)
        r = np.asarray(ctx.existence, dtype=float)
        occluders = np.flatnonzero(r > self.min_existence)
        if k == 0 or len(occluders) == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        boxes = ctx.measurement_model.predicted_edges(ctx.means)
        mean_boxes = _mean_boxes(boxes, ctx.weights, ctx.owner, len(r))[occluders]
        position = np.full(len(r) + 1, -1)  # an object's place among the occluders
        position[occluders] = np.arange(len(occluders))
        own = position[ctx.owner]  # (the Poisson part, owner -1, reads the last: -1)
        visible = self.geometry.visible(boxes, mean_boxes, weights=r[occluders], skip=own,
                                        sparse=ctx.gating)
        return OcclusionTerms(visible, np.zeros(k))


def _mean_boxes(boxes: np.ndarray, weights: np.ndarray, owner: np.ndarray,
                n_objects: int) -> np.ndarray:
    """Each object's mean box: the weight-averaged edges of its components, (n, 2, 2)."""
    mine = owner >= 0
    flat = boxes[mine].reshape(-1, 4)
    w = weights[mine]
    total = np.bincount(owner[mine], weights=w, minlength=n_objects)
    sums = np.stack([np.bincount(owner[mine], weights=w * flat[:, c], minlength=n_objects)
                     for c in range(4)], axis=1)
    return (sums / np.maximum(total, 1e-300)[:, None]).reshape(n_objects, 2, 2)
