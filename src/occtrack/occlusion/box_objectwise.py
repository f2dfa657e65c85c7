"""Object-wise occlusion for image boxes, static expected-value approximation.

Paper eq. "misstermOWO": occlusion multiplies P_D by P(visible | x). The exact visibility
depends on every other object jointly; the expected-value approximation replaces each other
object i by its mean box, weighted by its existence r_i (only objects with r_i above
`min_existence`, 0.1 in the paper's prototype), and combines the occluders as independent:

    v_k = prod_{i != owner(k)} (1 - r_i p(box_k hidden by mean box_i))

An object never occludes itself; the Poisson part (objects not yet detected) occludes nothing.

The loops are compiled (`_occlusion.pyx`, its `_box_objectwise.pxi`): `_occluder_boxes` (the
occluders' mean boxes, each the weight-averaged edges of its object's components, and each
component's place among the occluders, the one it never counts) and `_visible_behind_means`
(those, then `box_geometry`'s dense product with the existences as weights, in one call).
"""

from __future__ import annotations

import numpy as np

from occtrack.occlusion._occlusion import (  # the compiled kernels: _box_objectwise.pxi
    _occluder_boxes,
    _visible_behind_means,
)
from occtrack.occlusion.base import OcclusionContext, OcclusionTerms
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry
from occtrack.spatial import DENSE_PAIRS


class ObjectWiseExpectedValue:
    name = "object-wise"

    def __init__(self, geometry: BoxOcclusionGeometry | None = None,
                 min_existence: float = 0.1):
        self.geometry = geometry or BoxOcclusionGeometry()
        self.min_existence = float(min_existence)

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        k = len(ctx.means)
        # (C order throughout: the compiled kernels read the arrays in place)
        r = np.ascontiguousarray(ctx.existence, dtype=float)
        occluders = np.flatnonzero(r > self.min_existence)
        if k == 0 or len(occluders) == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        boxes = np.ascontiguousarray(ctx.measurement_model.predicted_edges(ctx.means),
                                     dtype=float)
        weights = np.ascontiguousarray(ctx.weights, dtype=float)
        owner = np.ascontiguousarray(ctx.owner, dtype=np.int64)
        g = self.geometry
        if not ctx.gating or k * len(occluders) <= DENSE_PAIRS:  # one compiled call
            return OcclusionTerms(_visible_behind_means(boxes, weights, owner, occluders, r,
                                                        g.gain, g.ramp_zero, g.ramp_one),
                                  np.zeros(k))
        mean_boxes, own = _occluder_boxes(boxes, weights, owner, occluders)
        visible = g.visible(boxes, mean_boxes, weights=r[occluders], skip=own, sparse=True)
        return OcclusionTerms(visible, np.zeros(k))
