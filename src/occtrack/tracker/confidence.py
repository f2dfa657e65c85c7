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
calibrated one there too (README).

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

import math

import numpy as np

from occtrack.jit import njit

RIGHT_IOU = 0.5
DRAWS = 1024
_Z = np.random.default_rng(20261125).standard_normal((DRAWS // 2, 2, 2))
_Z = np.concatenate([_Z, -_Z])  # antithetic: the draws' mean is exactly 0
"""(DRAWS, axis, (centre, half-size)) standard-normal draws."""
BLOCK = 64
_Z = _Z[np.argsort(np.abs(_Z).reshape(DRAWS, 4).max(axis=1), kind="stable")]
"""... ordered by their largest |normal|, so that the draws near the mean come in blocks."""
_REACH = np.abs(_Z).reshape(DRAWS // BLOCK, BLOCK, 2, 2).max(axis=1)
"""(blocks, axis, 2): the largest |normal| of each block of `BLOCK` draws (a bound's reach)."""


@njit
def box_covariances(label, mass, mean, cov, r, means, L):
    """Per label slot and image axis the 2 x 2 covariance of (centre, half-size) of its
    mixture (state entries 0 and 2), the spread of the component means included: (L, 2, 2, 2).
    `r` and `means` are the slots' existence and mean states (`object_moments`)."""
    out = np.zeros((L, 2, 2, 2))
    for k in range(len(label)):
        i = label[k]
        if i < 0:
            continue
        share = mass[k] / max(r[i], 1e-300)
        for a in range(2):
            d0 = mean[k, a, 0] - means[i, a, 0]
            d2 = mean[k, a, 2] - means[i, a, 2]
            out[i, a, 0, 0] += share * (cov[k, a, 0, 0] + d0 * d0)
            out[i, a, 0, 1] += share * (cov[k, a, 0, 2] + d0 * d2)
            out[i, a, 1, 1] += share * (cov[k, a, 2, 2] + d2 * d2)
        out[i, :, 1, 0] = out[i, :, 0, 1]
    return out


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
    centre = np.zeros(2) if centre is None else np.asarray(centre, dtype=float)
    return _report_confidence(label, mass, mean, cov, r, means, shown,
                              np.asarray(boxes, dtype=float), detected, on_detection, coast,
                              float(expansion_power), centre, float(floor), RIGHT_IOU, _Z,
                              _REACH)


@njit
def drift_variance(mean, unseen, power, image_centre, axis):
    """The variances (centre, half-size) on `axis` that a coasting box's confidence adds for the
    camera's expansion (`occtrack.tracker.camera.estimate_expansion`): the filter follows the
    one shift a frame, and a box unseen for t s drifts from its prediction by k h (x - centre) t,
    k the expansion rate (1 / (px s)), h its height; k^2 is taken as the camera's recent
    `power`, and the half-size grows alike (k h s t). On any camera, resolution and frame rate:
    k is measured from that video's detections in its own units, and a still camera's is 0."""
    lever = 2.0 * mean[1, 2] * unseen
    return (power * (lever * (mean[axis, 0] - image_centre[axis])) ** 2,
            power * (lever * mean[axis, 2]) ** 2)


@njit
def _report_confidence(label, mass, mean, cov, r, means, shown, boxes, detected, on_detection,
                       coast, power, image_centre, floor, threshold, z, reach):
    covariances = box_covariances(label, mass, mean, cov, r, means, len(r))
    K = len(shown)
    centre, half = np.empty((K, 2)), np.empty((K, 2))
    spread = np.empty((K, 2, 2, 2))
    existence = np.empty(K)
    for a in range(K):
        k = shown[a]
        existence[a] = r[k]
        spread[a] = covariances[k]
        if power > 0.0 and not detected[a]:
            for axis in range(2):
                add_centre, add_half = drift_variance(means[k], coast[k], power, image_centre,
                                                      axis)
                spread[a, axis, 0, 0] += add_centre
                spread[a, axis, 1, 1] += add_half
        for axis in range(2):
            if on_detection and detected[a]:
                half[a, axis] = boxes[a, 2 + axis] / 2.0
                centre[a, axis] = boxes[a, axis] + half[a, axis]
            else:
                centre[a, axis], half[a, axis] = means[k, axis, 0], means[k, axis, 2]
    # a box whose existence cannot carry it to `floor` needs only to be known below it
    need = np.zeros(K)
    if floor > 0.0:
        for a in range(K):
            need[a] = floor / max(existence[a], 1e-300)
    return existence * _overlap_probability(centre, half, spread, boxes, threshold, z, reach,
                                            need)


def overlap_probability(centre: np.ndarray, half: np.ndarray, covariance: np.ndarray,
                        reported: np.ndarray, threshold: float = RIGHT_IOU) -> np.ndarray:
    """P(IoU(x, reported) >= threshold) for boxes x whose (centre, half-size) per axis are
    Gaussian: `centre`, `half` (n, 2) means in px, `covariance` (n, 2, 2, 2) per axis over
    (centre, half-size), `reported` (n, 4) left, top, width, height. (n,) probabilities."""
    return _overlap_probability(np.asarray(centre, dtype=float), np.asarray(half, dtype=float),
                                np.asarray(covariance, dtype=float),
                                np.asarray(reported, dtype=float), float(threshold), _Z, _REACH,
                                np.zeros(len(centre)))


@njit
def _overlap(c, s, lo, hi):
    """Length of [c - s, c + s] within [lo, hi]."""
    return max(min(c + s, hi) - max(c - s, lo), 0.0)


@njit
def _overlap_probability(centre, half, covariance, reported, threshold, z, reach, need):
    """`overlap_probability`, block by block (`_decided`); box i stops as soon as even every
    draw left could not lift its count to `need[i]` (a probability; 0: never), and then its
    value is that bound, below need[i] (the reporting rule drops it whatever it is)."""
    n, S, B = len(centre), len(z), len(reach)
    block = S // B
    out = np.zeros(n)
    root = np.zeros((2, 3))
    for i in range(n):
        for a in range(2):  # a lower-triangular square root of the axis' 2 x 2 covariance
            l00 = math.sqrt(max(covariance[i, a, 0, 0], 0.0))
            l10 = covariance[i, a, 0, 1] / l00 if l00 > 0 else 0.0
            root[a, 0], root[a, 1] = l00, l10
            root[a, 2] = math.sqrt(max(covariance[i, a, 1, 1] - l10 * l10, 0.0))
        area = reported[i, 2] * reported[i, 3]
        hits = 0
        for b in range(B):
            if hits + (B - b) * block < need[i] * S:
                hits += (B - b) * block  # the bound: every draw left a hit
                break
            decided = _decided(centre[i], half[i], root, reported[i], area, threshold,
                               reach[b])
            if decided == 1:
                hits += block
            if decided != 0:
                continue
            for d in range(b * block, (b + 1) * block):
                inter, size = 1.0, 1.0
                for a in range(2):
                    c = centre[i, a] + root[a, 0] * z[d, a, 0]
                    s = max(half[i, a] + root[a, 1] * z[d, a, 0] + root[a, 2] * z[d, a, 1],
                            0.0)
                    lo, hi = reported[i, a], reported[i, a] + reported[i, 2 + a]
                    inter *= max(min(c + s, hi) - max(c - s, lo), 0.0)
                    size *= 2.0 * s
                union = size + area - inter
                if union > 0 and inter >= threshold * union:
                    hits += 1
        out[i] = hits / S
    return out


@njit
def _decided(centre, half, root, reported, area, threshold, reach):
    """1 if every draw whose normals lie within `reach` (axis, 2) hits, -1 if every one
    misses, 0 if the bound cannot tell. Per axis the centre lies within c_lo..c_hi and the
    half-size within s_lo..s_hi; the overlap is least at a corner, most at the reported box's
    centre (clamped) with the largest half-size; IoU = I / (S + area - I) rises with the
    overlap I and falls with the size S, so the least I with the largest S bounds it below and
    the reverse above."""
    least, most, smallest, largest = 1.0, 1.0, 1.0, 1.0
    for a in range(2):
        dc = root[a, 0] * reach[a, 0]
        ds = abs(root[a, 1]) * reach[a, 0] + root[a, 2] * reach[a, 1]
        c_lo, c_hi = centre[a] - dc, centre[a] + dc
        s_lo, s_hi = max(half[a] - ds, 0.0), max(half[a] + ds, 0.0)
        lo, hi = reported[a], reported[a] + reported[2 + a]
        least *= min(_overlap(c_lo, s_lo, lo, hi), _overlap(c_hi, s_lo, lo, hi))
        most *= _overlap(min(max((lo + hi) / 2.0, c_lo), c_hi), s_hi, lo, hi)
        smallest *= 2.0 * s_lo
        largest *= 2.0 * s_hi
    margin = 1e-9 * max(area, 1.0)  # (rounding: no draw may straddle the bound)
    if largest + area - least > 0 and least - margin >= threshold * (largest + area - least):
        return 1
    if most + margin < threshold * (smallest + area - most):
        return -1
    return 0
