"""The shape of the boxes: where the image border hides an edge, the other axis says where it is.

A detector clips its boxes to the image, and `BoxMeasurement` leaves an edge on the border
unmeasured; an axis with such an edge has its half-size pinned by nothing but the prediction.
A person walking out at the bottom of the image keeps growing as they near the camera, the
prediction does not, and the filter's hidden edge falls short of the true one (on MOT17's
detections the hidden bottom edge of a tracked box lay .09 to .36 box heights inside the true
box, median). The boxes of one class keep a shape, though: a pedestrian's width over height is
about .35 whoever and wherever they are (log-ratio spread about .14 on MOT17's detections). So
when one axis of a detection is measured whole (both edges inside the image) and the other is
cut by the border, the cut axis's half-size is measured through the aspect ratio,

    log s_cut = log s_whole -/+ mu + eps,   eps ~ N(0, sigma^2),

mu and sigma the mean and standard deviation of log(width / height) over the detections with all
four edges inside the image so far (learnt online, like the newborns' size: no setting to fit
per camera; nothing is done before `MIN_BOXES` of them). Linearised about the whole axis's
half-size s_w as the filter knows it after the edge update (mean s_w, variance P_w), the
pseudo-measurement of the cut axis's half-size is

    z = s_w exp(-/+ mu),   var = z^2 sigma^2 + exp(-/+ 2 mu) P_w,

- for the vertical axis from the width, + for the horizontal from the height, and it enters a
scalar Kalman update of that half-size after the edge update (`BoxMeasurement.update_rows`);
the measured edge of the cut axis then places the hidden one. (The two axes' errors are taken
as independent, as the state's axes are.) A box cut on both axes (a corner) is left as it was.

Hand-written: the update is one scalar Kalman step on a 3-state block a row, compiled
(`occtrack.models._models`, its `_aspect.pxi`) as the edge update is.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.models._models import _aspect_update, _count_aspects  # noqa: F401

MIN_BOXES = 10
"""Whole detections needed before the aspect ratio is used."""


class AspectPrior:
    """The class's aspect ratio, learnt from whole detections (`learn`); its `moments` feed
    `_aspect_update`, the half-size of an axis the image border cuts, which
    `BoxMeasurement.update_rows` calls with its own border step."""

    def __init__(self) -> None:
        self.stats = np.zeros(3)  # count, sum and sum of squares of log(width / height)

    def learn(self, z: np.ndarray, observed: np.ndarray) -> None:
        """Count the detections z (M, 2, 2) with every edge measured (`observed`)."""
        _count_aspects(z, observed, self.stats)

    def moments(self) -> tuple[float, float] | None:
        """(mu, sigma) of log(width / height), None before `MIN_BOXES` whole detections."""
        count, total, squares = self.stats
        if count < MIN_BOXES:
            return None
        mu = total / count
        return mu, math.sqrt(max(squares / count - mu * mu, 0.0))
