"""The confidence of a reported box: the probability that it is a real object at that place.

A user reads a box's confidence as "how often a box like this is right", where right means what
the benchmarks mean: a real object whose true box overlaps the reported one at IoU >= 0.5
(`RIGHT_IOU`). The filter holds both halves of that probability:

    confidence_i = r_i * P(IoU(x_i, b_i) >= 0.5),    x_i ~ p_i,

with r_i the object's existence, b_i the reported box (the detection it took, or the filter's
mean box while it coasts) and p_i its posterior box density, moment-matched to one Gaussian
per image axis over (centre, half-size). A coasting box whose prediction has spread (time
unseen, a camera that moves) is right less often, and its confidence says so. For a detected
box the Gaussian is, by default, the posterior itself, centred on its mean (the exact form,
`confidence_centre = "posterior"`): a detection far from where the object was predicted
moves the posterior only part of the way, and the box is less likely right. The other form
("detection") centres the posterior's spread on the detection and leaves that distance out;
it is too sure in a world drawn from the filter's own model
(benchmarks/calibration_model_world.py). On MOT17 the exact form was too unsure while boxes
cut by the image border kept a hidden edge no measurement pinned; since the border edge is
measured through the aspect ratio and the censored update (`occtrack.models.box`) it is the
calibrated one there too (docs/confidence.md).

The overlap probability has no closed form (IoU is a ratio of piecewise-linear areas), so it
is a Monte Carlo average over `DRAWS` fixed standard-normal draws, the same for every box and
every run (deterministic): its error is below 1 / (2 sqrt(DRAWS)) = .016 per box; as every box
shares the draws it does not average out over similar boxes, and 1024 is what keeps the
mean of MOT17's coasting boxes within .002 of 32,768 draws' (256 were .01 to .02 low). Most
draws are decided without being drawn: the draws come in blocks of
`BLOCK`, ordered by their largest normal, and the IoU is bounded over every box a block can
reach (`_decided`); where the bound decides, every draw of the block would hit or miss, and the
count is the same as drawing them.
"""

from __future__ import annotations

import numpy as np

from occtrack.tracker._tracker import (  # noqa: F401 (kernels kept under their old names)
    _decided,
    _overlap,
    _overlap_probability,
    _report_confidence,
    box_covariances,
    drift_variance,
)

RIGHT_IOU = 0.5
"""A reported box is right when it is matched to a true object at IoU >= this: the event
`confidence` is the probability of, and what `occtrack.metrics.reliability` scores."""
DRAWS = 1024
_Z = np.random.default_rng(20261125).standard_normal((DRAWS // 2, 2, 2))
_Z = np.concatenate([_Z, -_Z])  # antithetic: the draws' mean is exactly 0
"""(DRAWS, axis, (centre, half-size)) standard-normal draws."""
BLOCK = 64
_Z = _Z[np.argsort(np.abs(_Z).reshape(DRAWS, 4).max(axis=1), kind="stable")]
"""... ordered by their largest |normal|, so that the draws near the mean come in blocks."""
_REACH = np.abs(_Z).reshape(DRAWS // BLOCK, BLOCK, 2, 2).max(axis=1)
"""(blocks, axis, 2): the largest |normal| of each block of `BLOCK` draws (a bound's reach)."""


def report_confidence(label, mass, mean, cov, r, means, shown, boxes, detected,
                      on_detection: bool, coast: np.ndarray | None = None,
                      expansion_power: float = 0.0,
                      centre: np.ndarray | None = None, floor: float = 0.0) -> np.ndarray:
    """The confidence of the reported boxes (`Tracker.tracks`): slots `shown` (K,) with their
    reported `boxes` (K, 4) left, top, width, height, `detected` (K,) those that took a
    detection. `label`, `mass`, `mean`, `cov` are the filter's components and `r`, `means`
    its slots' existence and mean states (`object_moments`). A detected box's Gaussian is
    centred on the box itself when `on_detection`, else on the posterior mean. A coasting box's
    Gaussian widens by what the filter leaves out, the camera's expansion (`drift_variance`):
    `coast` the slots' time unseen (s), `expansion_power` the camera's recent k^2 and `centre`
    the image centre. A box below `floor` (the reporting threshold) is only known to be
    below it: its value is an upper bound under `floor` (0: every value exact). (K,)"""
    if coast is None or not expansion_power > 0:
        coast, expansion_power = np.zeros(len(r)), 0.0
    centre = np.zeros(2) if centre is None else np.ascontiguousarray(centre, dtype=float)
    return _report_confidence(label, mass, mean, cov, r, means, shown,
                              np.ascontiguousarray(boxes, dtype=float), detected, on_detection,
                              coast, float(expansion_power), centre, float(floor), RIGHT_IOU, _Z,
                              _REACH)


def overlap_probability(centre: np.ndarray, half: np.ndarray, covariance: np.ndarray,
                        reported: np.ndarray, threshold: float = RIGHT_IOU) -> np.ndarray:
    """P(IoU(x, reported) >= threshold) for boxes x whose (centre, half-size) per axis are
    Gaussian: `centre`, `half` (n, 2) means in px, `covariance` (n, 2, 2, 2) per axis over
    (centre, half-size), `reported` (n, 4) left, top, width, height. (n,) probabilities."""
    return _overlap_probability(np.ascontiguousarray(centre, dtype=float),
                                np.ascontiguousarray(half, dtype=float),
                                np.ascontiguousarray(covariance, dtype=float),
                                np.ascontiguousarray(reported, dtype=float), float(threshold),
                                _Z, _REACH, np.zeros(len(centre)))
