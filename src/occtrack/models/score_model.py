"""How a detector's score speaks for an object against clutter, learnt while tracking.

The clutter term of the box model is kappa p_F(z_j) = clutter_rate g(s_j) / (W H w h): g(s) is
how much likelier a false box is than an object's at score s, relative to a box at the top of
the score range. The calibrated prior is g0(s) = max(s, floor)^-power (FRCNN on MOT17, whose
scores sit near 1). A detector that reports every box down to a score of .01 (YOLOX, as
ByteTrack feeds it) or whose scores mean something else (RRC on KITTI) needs its own g.

The filter already says, for every detection, how likely it is clutter: pi_j, its association
marginal of being new times the clutter share of its new weight (`filters.gmpmb`). Those are
the E-step of an EM for the score mixture (Dempster, Laird and Rubin; online, as the
intensity of a PHD filter with unknown clutter is learnt by Mahler's lambda-CPHD and Vo,
Vo, Hoseinnezhad and Mahler's robust multi-Bernoulli filter): in score bin b the clutter odds
are theta_b = C_b / O_b, C_b = sum pi_j and O_b = sum (1 - pi_j) over the detections in the
bin, discounted with a memory of `memory` seconds so the model follows the scene. Only the
shape is learnt; the level stays anchored at the top bin, where the clutter rate was
calibrated together with the birth rates:

    g(s in b) = exp(log rho_b),    rho_b = theta_b / theta_top,

(g = 1 in the top bin, as g0(1) = 1 where the clutter rate was calibrated),

and log rho_b is shrunk towards the prior's log(g0(s_b) / g0(s_top)) with `prior_weight`
pseudo-detections: log rho_b = (n0 log rho0_b + n_b log rho_hat_b) / (n0 + n_b), n_b the
(discounted) detections behind the bin's and the top bin's estimate (the smaller of the two).
A bin no detector fills keeps the prior; FRCNN's, whose few low scores give the low bins little
weight, keeps nearly all of it.

Hand-written: a few lines of weighted counting on the filter's own marginals; no library
learns a tracker's clutter model from its association probabilities.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.models._models import _score_lookup, _score_update

BINS = 10


class ScoreLearner:
    """Online EM for the score term g(s) of the clutter density (see the module)."""

    def __init__(self, score_floor: float = 0.05, power: float = 2.0, bins: int = BINS,
                 memory: float = 60.0, prior_weight: float = 50.0, refresh: int = 10,
                 log_odds: bool = False):
        if bins < 2:
            raise ValueError(f"bins must be at least 2, not {bins}")
        if not prior_weight > 0:
            raise ValueError(f"prior_weight must be positive, not {prior_weight}")
        self.bins, self.memory, self.prior_weight = bins, float(memory), float(prior_weight)
        self.score_floor, self.power = float(score_floor), float(power)
        # log_odds: bins one unit of log-odds wide from the floor's up (a detector whose
        # probabilities crowd near 1, as a lidar detector's logistic scores do, is told apart
        # there; the probability bins put every score above .9 in one)
        self.log_odds = bool(log_odds)
        self._start = math.log(max(self.score_floor, 1e-6) / (1.0 - max(self.score_floor, 1e-6)))
        if self.log_odds:
            centres = 1.0 / (1.0 + np.exp(-(self._start + np.arange(bins) + 0.5)))
        else:
            centres = (np.arange(bins) + 0.5) / bins
        self._prior = np.maximum(centres, score_floor) ** -power  # g0 at each bin's centre
        self.clutter = np.zeros(bins)  # discounted sum of pi_j per bin
        self.objects = np.zeros(bins)  # discounted sum of 1 - pi_j per bin
        self._table = self._prior / self._prior[-1]  # g of each bin, renewed every `refresh`
        self.refresh, self._updates = int(refresh), 0  # (a frame barely moves a minute's sums)

    def bin_of(self, scores: np.ndarray) -> np.ndarray:
        """The bin of each score, scores below 0 in the first and 1 or above in the last."""
        if self.log_odds:
            s = np.clip(np.asarray(scores, dtype=float), 1e-12, 1.0 - 1e-12)
            b = np.floor(np.log(s / (1.0 - s)) - self._start).astype(np.int64)
            return np.clip(b, 0, self.bins - 1)
        b = (np.clip(np.asarray(scores, dtype=float), 0.0, 1.0) * self.bins).astype(np.int64)
        np.minimum(b, self.bins - 1, out=b)
        return b

    def update(self, scores: np.ndarray, clutter_probability: np.ndarray, dt: float) -> None:
        """One frame: its detections' scores and the filter's clutter probabilities (in
        [0, 1], as the filter gives them)."""
        keep = math.exp(-dt / self.memory)
        if not self.log_odds:  # (the same sums, compiled: `_score_update`)
            _score_update(np.ascontiguousarray(scores, dtype=float),
                          np.ascontiguousarray(clutter_probability, dtype=float), keep,
                          self.clutter, self.objects)
        else:
            self.clutter *= keep
            self.objects *= keep
            if len(scores):
                b = self.bin_of(scores)
                pi = np.asarray(clutter_probability, dtype=float)
                self.clutter += np.bincount(b, weights=pi, minlength=self.bins)
                self.objects += np.bincount(b, weights=1.0 - pi, minlength=self.bins)
        self._updates += 1
        if self._updates % self.refresh == 0:
            self._table = np.exp(self.log_ratio())

    def log_ratio(self) -> np.ndarray:
        """log rho_b of every bin, shrunk towards the prior (see the module)."""
        prior = np.log(self._prior / self._prior[-1])
        eps = 1e-3  # a pseudo-count that keeps an empty side of a bin finite
        theta = np.log((self.clutter + eps) / (self.objects + eps))
        learnt = theta - theta[-1]
        top = self.clutter[-1] + self.objects[-1]
        n = np.minimum(self.clutter + self.objects, top)
        return (self.prior_weight * prior + n * learnt) / (self.prior_weight + n)

    def score_term(self, scores: np.ndarray) -> np.ndarray:
        """g(s_j) of each detection: the clutter density's score factor (the learnt ratio of
        the detection's bin to the top bin's)."""
        if self.log_odds:
            return self._table[self.bin_of(scores)]
        return _score_lookup(np.ascontiguousarray(scores, dtype=float), self._table)

    def log_likelihood_ratio(self, scores: np.ndarray) -> np.ndarray:
        """log f_O(s_j) / f_C(s_j) of each detection: how much likelier its score is from an
        object than from clutter, the two score densities per bin being the learnt
        (discounted) shares of the detections the filter called objects and clutter, each
        with one pseudo-detection a bin (so a bin no detection filled says nothing)."""
        objects = (self.objects + 1.0) / (self.objects.sum() + self.bins)
        clutter = (self.clutter + 1.0) / (self.clutter.sum() + self.bins)
        return np.log(objects / clutter)[self.bin_of(scores)]
