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

from occtrack.jit import njit
from occtrack.occlusion.base import OcclusionContext, OcclusionTerms
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry, _visible_dense
from occtrack.spatial import DENSE_PAIRS


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
        weights = np.asarray(ctx.weights, dtype=float)
        owner = np.asarray(ctx.owner, dtype=np.int64)
        g = self.geometry
        if not ctx.gating or k * len(occluders) <= DENSE_PAIRS:  # one compiled call
            return OcclusionTerms(_visible_behind_means(boxes, weights, owner, occluders, r,
                                                        g.gain, g.ramp_zero, g.ramp_one),
                                  np.zeros(k))
        mean_boxes, own = _occluder_boxes(boxes, weights, owner, occluders)
        visible = g.visible(boxes, mean_boxes, weights=r[occluders], skip=own, sparse=True)
        return OcclusionTerms(visible, np.zeros(k))


@njit
def _visible_behind_means(boxes, weights, owner, occluders, existence, gain, ramp_zero,
                          ramp_one):
    """v_k over every (component, occluder) pair: `_occluder_boxes`, then the product of
    `box_geometry`'s dense form with the occluders' existences as weights."""
    mean_boxes, own = _occluder_boxes(boxes, weights, owner, occluders)
    return _visible_dense(boxes, mean_boxes, existence[occluders], own, gain, ramp_zero,
                          ramp_one)


@njit
def _occluder_boxes(boxes, weights, owner, occluders):
    """The occluders' mean boxes, (n, 2, 2): each the weight-averaged edges of its object's
    components; and each component's place among the occluders (-1: its object is none, or
    it is the Poisson part's), the one occluder it never counts."""
    position = np.full(owner.max() + 1 if len(owner) else 0, -1)
    for i in range(len(occluders)):
        if occluders[i] < len(position):
            position[occluders[i]] = i
    total = np.zeros(len(occluders))
    sums = np.zeros((len(occluders), 2, 2))
    own = np.full(len(owner), -1)
    for k in range(len(owner)):
        if owner[k] >= 0 and position[owner[k]] >= 0:
            i = position[owner[k]]
            own[k] = i
            total[i] += weights[k]
            for axis in range(2):
                for e in range(2):
                    sums[i, axis, e] += weights[k] * boxes[k, axis, e]
    for i in range(len(occluders)):
        for axis in range(2):
            for e in range(2):
                sums[i, axis, e] /= max(total[i], 1e-300)
    return sums, own
