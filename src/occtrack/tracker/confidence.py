"""The confidence of a reported box: the probability that it is a real object at that place.

A user reads a box's confidence as "how often a box like this is right", where right means what
the benchmarks mean: a real object whose true box overlaps the reported one at IoU >= 0.5
(`RIGHT_IOU`). The filter holds both halves of that probability:

    confidence_i = r_i * P(IoU(x_i, b_i) >= 0.5),    x_i ~ p_i,

with r_i the object's existence, b_i the reported box (the detection it took, or the filter's
mean box while it coasts) and p_i its posterior box density, moment-matched to one Gaussian
per image axis over (centre, half-size). A coasting box whose prediction has spread (time
unseen, a camera that moves) is right less often, and its confidence says so. For a detected
box the Gaussian is centred on the detection itself (the reported estimate; a detection cut
by the image border would otherwise be compared with a posterior box that runs past it) with
the posterior's spread (`Tracker.tracks`).

The overlap probability has no closed form (IoU is a ratio of piecewise-linear areas), so it
is a Monte Carlo average over `DRAWS` fixed standard-normal draws, the same for every box and
every run (deterministic): its error is below 1 / (2 sqrt(DRAWS)) = .016 per box and averages
out over boxes.
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


def overlap_probability(centre: np.ndarray, half: np.ndarray, covariance: np.ndarray,
                        reported: np.ndarray, threshold: float = RIGHT_IOU) -> np.ndarray:
    """P(IoU(x, reported) >= threshold) for boxes x whose (centre, half-size) per axis are
    Gaussian: `centre`, `half` (n, 2) means in px, `covariance` (n, 2, 2, 2) per axis over
    (centre, half-size), `reported` (n, 4) left, top, width, height. (n,) probabilities."""
    return _overlap_probability(np.asarray(centre, dtype=float), np.asarray(half, dtype=float),
                                np.asarray(covariance, dtype=float),
                                np.asarray(reported, dtype=float), float(threshold), _Z)


@njit
def _overlap_probability(centre, half, covariance, reported, threshold, z):
    n, S = len(centre), len(z)
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
        for d in range(S):
            inter, size = 1.0, 1.0
            for a in range(2):
                c = centre[i, a] + root[a, 0] * z[d, a, 0]
                s = max(half[i, a] + root[a, 1] * z[d, a, 0] + root[a, 2] * z[d, a, 1], 0.0)
                lo, hi = reported[i, a], reported[i, a] + reported[i, 2 + a]
                inter *= max(min(c + s, hi) - max(c - s, lo), 0.0)
                size *= 2.0 * s
            union = size + area - inter
            if union > 0 and inter >= threshold * union:
                hits += 1
        out[i] = hits / S
    return out
