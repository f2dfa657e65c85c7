"""A heavy tail for the box edges' likelihood: a detection that jumps stays its track's.

The box model's likelihood of a detection is Gaussian in its edges (`models.box`). Real
detections are not: most sit well inside the predicted spread, and a few per cent lie many
standard deviations off (a car that the camera approaches grows faster than the prediction,
a detector's box jumps to a partly hidden object's visible part). Under a Gaussian such a
detection is nearly impossible for the track, so it starts a second track on the same object
(on KITTI's cars most identity switches were such twins). The measured standardised
innovations of the detections that tracks take say it: on KITTI 3.7 % of horizontal edges lie
beyond 3 standard deviations and 1.8 % beyond 5 (a Gaussian: .27 % and .00006 %).

The likelihood here is a scale mixture, the outlier model of robust Kalman filtering:

    p(z | x) = (1 - eps) N(z; H x, S) + eps N(z; H x, kappa^2 S)

over the m measured edges of z (censored border edges keep their own term), so that, with d^2
the Mahalanobis distance of the measured edges under S,

    log p = log N(z; H x, S) + log(1 - eps + eps kappa^-m exp(d^2 (1 - kappa^-2) / 2)).

The tail is a tracked object's only: the Poisson part (objects never detected) has densities
broad enough already, and its pairs are most of a crowd's. Like the Gaussian, it is cut at the
filter's gate (`gate_sigmas` = 9 core standard deviations, 3 of the tail's).

`tail_scale` kappa = 3 and `tail_weight` eps = .05 are fixed by default, chosen on KITTI's
ten given car sequences, where twins cost most, and checked on MOT17 with FRCNN and YOLOX
(object-wise, mean HOTA over the car sequences): .763 without the tail; kappa 3 with eps .05
.790, .1 .792, .2 .792; kappa 5 .780, kappa 2 .772 (eps .05). eps .05 is the largest weight
that keeps each MOT17 FRCNN sequence within .005 HOTA of the Gaussian's (.1 and .2 take
MOT17-04 from .568 to .560: there the innovations sit far inside the predicted spread and
the tail only loosens who takes what in a crowd); with it every KITTI car sequence gains or
holds, and MOT17 YOLOX gains .002 (mean).

The weight can also be learnt (`learn_tail_weight`), by online EM from the detections that
confirmed tracks take: each taken detection's responsibility of the tail,

    rho = eps a / (1 - eps + eps a),    a = kappa^-m exp(d^2 (1 - kappa^-2) / 2),

at the best-fitting component of the track, summed with a memory of `memory` seconds, and
eps = (n0 eps0 + sum rho) / (n0 + n), shrunk toward the prior eps0 with n0 pseudo-detections.
It is off by default because it learns too small a weight: the detections the tail is for are
the ones a Gaussian track did not take (they started twins), so the taken ones under-count
them. On KITTI it learns .004 to .114 (mean HOTA .788 against the fixed weight's .790), on
MOT17 .000 to .001. The Kalman update is the Gaussian one (the detection is taken as it is, as
every box tracker takes it).

Hand-written: a few lines over the pairs the filter has gated; the robust-filtering libraries
(e.g. Stone Soup) have no labelled PMB filter to plug a likelihood into.
"""

from __future__ import annotations

import math

import numpy as np

MAX_EPS = 0.5  # the tail never becomes the likelier explanation of a typical detection


class EdgeTail:
    """The tail's weight eps, fixed or learnt (see the module); `correction` gives the
    log-likelihood term each (component, detection) pair adds to the Gaussian's."""

    def __init__(self, weight: float = 0.05, scale: float = 3.0, memory: float = 60.0,
                 prior_weight: float = 50.0, learn: bool = True):
        if not 0.0 <= weight <= MAX_EPS:
            raise ValueError(f"tail weight must be in [0, {MAX_EPS}], not {weight}")
        if not scale > 1.0:
            raise ValueError(f"tail scale must be above 1, not {scale}")
        self.prior, self.scale, self.memory = float(weight), float(scale), float(memory)
        self.prior_weight, self.learning = float(prior_weight), bool(learn)
        self.weight = self.prior
        self.count = 0.0  # discounted number of taken detections behind the estimate
        self.tail = 0.0  # discounted sum of their tail responsibilities
        self._pairs: tuple[np.ndarray, ...] | None = None  # the last frame's (k, j, d2, m)

    def _log_ratio(self, d2: np.ndarray, m: np.ndarray) -> np.ndarray:
        """log a = log of the tail's density over the core's, per pair."""
        return 0.5 * d2 * (1.0 - self.scale ** -2) - m * math.log(self.scale)

    def remember(self, k: np.ndarray, j: np.ndarray, d2: np.ndarray, m: np.ndarray) -> None:
        """Keep this frame's pairs (k, j) with their d^2 and m for `learn` (the box model's
        compiled likelihood adds the tail and hands them over)."""
        self._pairs = (k, j, d2, m)

    def correction(self, zhat: np.ndarray, S: np.ndarray, z: np.ndarray,
                   observed: np.ndarray, k: np.ndarray, j: np.ndarray) -> np.ndarray:
        """log(1 - eps + eps a) for the pairs (k[e], j[e]) (P,), remembered for `learn`: what
        the box model's compiled likelihood adds, in numpy (its dense form and the tests)."""
        d2, m = mahalanobis(zhat, S, z, observed, k, j)
        self.remember(k, j, d2, m)
        eps = self.weight
        if eps <= 0.0:
            return np.zeros(len(k))
        return np.logaddexp(math.log1p(-eps), math.log(eps) + self._log_ratio(d2, m))

    def learn(self, label: np.ndarray, taken: np.ndarray, confirmed: np.ndarray,
              dt: float) -> None:
        """One EM step from this frame's association: `label` (K,) each component's slot
        (-1: Poisson), `taken` (L,) the detection each slot took (-1: none), `confirmed` (L,)
        the slots that count. Forgets with the memory over `dt` seconds."""
        if not self.learning or self._pairs is None:
            return
        k, j, d2, m = self._pairs
        self._pairs = None
        keep = math.exp(-dt / self.memory)
        self.count *= keep
        self.tail *= keep
        slot = label[k]
        ok = slot >= 0
        ok[ok] = confirmed[slot[ok]] & (taken[slot[ok]] == j[ok])
        if ok.any():
            # the best-fitting component of each slot with the detection it took
            s, dd, mm = slot[ok], d2[ok], m[ok]
            order = np.lexsort((dd, s))
            first = np.ones(len(order), dtype=bool)
            first[1:] = s[order][1:] != s[order][:-1]
            best = order[first]
            eps = self.weight
            log_a = self._log_ratio(dd[best], mm[best])
            rho = 1.0 / (1.0 + np.exp(np.log1p(-eps) - math.log(eps) - log_a))
            self.count += len(best)
            self.tail += float(rho.sum())
        n0 = self.prior_weight
        self.weight = min(MAX_EPS, (n0 * self.prior + self.tail) / (n0 + self.count))


def mahalanobis(zhat: np.ndarray, S: np.ndarray, z: np.ndarray, observed: np.ndarray,
                k: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d^2 of the measured edges of detection j[e] under component k[e]'s innovation (zhat
    (K, 2, 2), S (K, 2, 2, 2) per axis over (low, high) edge), and m, how many edges were
    measured: (P,), (P,). An axis with one edge on the border counts the other alone."""
    r = z[j] - zhat[k]
    obs = observed[j]
    Sk = S[k]
    d2 = np.zeros(len(k))
    for axis in range(2):
        low, high = obs[:, axis, 0], obs[:, axis, 1]
        s00, s01, s11 = Sk[:, axis, 0, 0], Sk[:, axis, 0, 1], Sk[:, axis, 1, 1]
        r0, r1 = r[:, axis, 0], r[:, axis, 1]
        both = low & high
        det = np.where(both, s00 * s11 - s01 * s01, 1.0)
        d2 += np.where(both, (s11 * r0 * r0 - 2.0 * s01 * r0 * r1 + s00 * r1 * r1) / det, 0.0)
        d2 += np.where(low & ~high, r0 * r0 / s00, 0.0)
        d2 += np.where(high & ~low, r1 * r1 / s11, 0.0)
    return d2, obs.sum(axis=(1, 2)).astype(float)
