"""Clutter by range, learned from the scans (issue 41, item 3: clutter is what no person
explains).

`models.scan` takes clutter returns as Poisson along each beam with one density kappa =
clutter_rate / R per metre at every range. A real scanner's spurious returns are not so
spread: a laser at leg height tilted a little strikes the ground or the grass near one range,
and its returns near the end of its range come and go from scan to scan. There a two-beam
segment is no evidence of a person, and a segment the filter takes for one (born there, kept
alive behind the followed person, seen again through the gap between their legs) is a false
track that lives for minutes.

The map keeps the clutter intensity kappa(r) per range bin as a hazard along the beam: the
returns in the bin that no object explains (the tracker says which: `tracker.scan`, the
segments likely objects took and, with legs, the returns near a person it keeps), over the
metres of beam that reached the bin without an earlier return (a beam that hit a leg at
1.8 m says nothing of clutter at 5 m),

    kappa(r) = (c_r + kappa_0 e_0 w) / (e_r + e_0 w),

c_r and e_r summed over the scans with weight exp(-age / memory), kappa_0 the configured
uniform density, e_0 w (w the bin width) a prior of `prior_beams` beams' worth of exposure
per bin. The filter's clutter for segment j is then, against the uniform model its
likelihoods are written in, the product over its returns b of kappa(z_b) / kappa_0 (`ratio`):
a segment where clutter is ten times denser is ten times less likely to be a person, per
return.

The range is from the sensor, whatever its heading, so the map needs no pose and goes with a
moving sensor; walls and posts that stand still are the static scene's (`models.static_scene`).
Written by hand: a hazard histogram is a few numpy lines, no library keeps one.
"""

from __future__ import annotations

import math

import numpy as np


class ClutterMap:
    """Clutter intensity by range from the sensor, learned online (see the module).

    Args:
        kappa: the prior density, returns per beam per metre (clutter_rate / max_range).
        max_range: m; returns at or beyond it are none.
        bin_width: m, the width of a range bin.
        memory: s, the time over which counts fade by e.
        prior_beams: beams' worth of exposure the prior is worth, per bin.
    """

    def __init__(self, kappa: float, max_range: float, bin_width: float = 0.25,
                 memory: float = 10.0, prior_beams: float = 100.0):
        for name, value in (("kappa", kappa), ("max_range", max_range),
                            ("bin_width", bin_width), ("memory", memory),
                            ("prior_beams", prior_beams)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, not {value}")
        self.kappa0, self.max_range = float(kappa), float(max_range)
        self.bins = max(int(math.ceil(self.max_range / bin_width)), 1)
        self.width = self.max_range / self.bins
        self.memory, self.prior = float(memory), float(prior_beams) * self.width
        self.reset()

    def reset(self) -> None:
        self.count = np.zeros(self.bins)  # clutter returns a bin, faded
        self.exposure = np.zeros(self.bins)  # metres of beam that reached the bin, faded

    def density(self) -> np.ndarray:
        """kappa(r) of each bin (bins,), returns per beam per metre."""
        return (self.count + self.kappa0 * self.prior) / (self.exposure + self.prior)

    def bin_of(self, ranges: np.ndarray) -> np.ndarray:
        return np.clip((np.asarray(ranges, float) / self.width).astype(np.int64), 0,
                       self.bins - 1)

    def log_ratio(self, ranges: np.ndarray) -> np.ndarray:
        """log kappa(z_b) / kappa_0 of each return (finite ranges below max_range)."""
        return np.log(self.density()[self.bin_of(ranges)] / self.kappa0)

    def learn(self, ranges: np.ndarray, clutter: np.ndarray, dt: float) -> None:
        """Add one scan: every beam's range (inf: no return) and which of its returns are
        clutter (no object explains them), `dt` s after the last."""
        fade = math.exp(-max(float(dt), 0.0) / self.memory)
        self.count *= fade
        self.exposure *= fade
        z = np.minimum(np.asarray(ranges, float), self.max_range)
        lo = np.arange(self.bins) * self.width
        # metres of each beam in each bin before its return (a beam with none: all of them)
        self.exposure += np.clip(z[:, None] - lo[None, :], 0.0, self.width).sum(axis=0)
        hit = np.asarray(clutter, bool) & (z < self.max_range)
        self.count += np.bincount(self.bin_of(z[hit]), minlength=self.bins)
