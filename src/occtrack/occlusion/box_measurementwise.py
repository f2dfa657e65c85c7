"""Measurement-wise occlusion for image boxes: the detections that were seen hide the rest.

Paper eq. "new_individual_MM": a component's miss term gains P_D q_k, with

    q_k = integral p(z | x_k) P(hidden | z, Z_visible) dz

the chance that its own would-be measurement was hidden by the visible detections (a detector's
non-maximum suppression does exactly this). The integral is evaluated at the component's
predicted box, the mean of p(z | x_k), as the authors' prototype did. No inter-object term
enters, so under restricted occlusion this is exact apart from that point evaluation.
"""

from __future__ import annotations

import numpy as np

from occtrack.occlusion.base import OcclusionContext, OcclusionTerms
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry, combine


class MeasurementWise:
    name = "measurement-wise"

    def __init__(self, geometry: BoxOcclusionGeometry | None = None):
        self.geometry = geometry or BoxOcclusionGeometry()

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        k = len(ctx.means)
        if k == 0 or len(ctx.measurements) == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        boxes = ctx.measurement_model.predicted_edges(ctx.means)
        hidden = combine(self.geometry(boxes, ctx.measurements))
        return OcclusionTerms(np.ones(k), hidden)
