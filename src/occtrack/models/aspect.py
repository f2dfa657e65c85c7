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
(`occtrack.jit`) as the edge update is.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.jit import njit

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


@njit
def _count_aspects(z, observed, stats):
    """Add log(width / height) of the detections with every edge measured to the running
    count, sum and sum of squares `stats` (3,)."""
    for j in range(len(z)):
        if not (observed[j, 0, 0] and observed[j, 0, 1] and observed[j, 1, 0]
                and observed[j, 1, 1]):
            continue
        width, height = z[j, 0, 1] - z[j, 0, 0], z[j, 1, 1] - z[j, 1, 0]
        if width <= 0.0 or height <= 0.0:
            continue
        ratio = math.log(width / height)
        stats[0] += 1.0
        stats[1] += ratio
        stats[2] += ratio * ratio


@njit
def _aspect_update(means, covs, rows, observed, measurement, mu, sigma):
    """The scalar Kalman update of the module docstring, per row whose detection has one axis
    whole and the other cut: s = means[k, cut, 2], P its block, g = P[:, 2] / S,
    m += g (z - s), P -= g g' S."""
    g = np.empty(3)
    for i in range(len(rows)):
        k, j = rows[i], measurement[i]
        whole_x = observed[j, 0, 0] and observed[j, 0, 1]
        whole_y = observed[j, 1, 0] and observed[j, 1, 1]
        if whole_x == whole_y:  # nothing cut, or both axes cut
            continue
        whole, cut = (0, 1) if whole_x else (1, 0)
        sign = -1.0 if cut == 1 else 1.0  # height = width exp(-mu), width = height exp(mu)
        half = means[k, whole, 2]
        if half <= 0.0:
            continue
        scale = math.exp(sign * mu)
        value = half * scale
        var = value * value * sigma * sigma + scale * scale * covs[k, whole, 2, 2]
        P = covs[k, cut]
        S = P[2, 2] + var
        residual = value - means[k, cut, 2]
        for a in range(3):
            g[a] = P[a, 2] / S
        for a in range(3):
            means[k, cut, a] += g[a] * residual
        for a in range(3):
            for b in range(3):
                P[a, b] -= g[a] * g[b] * S
