"""How often the detector finds an object it could see, by class and range: learnt while tracking.

The filter's detectability d_k is a two-state Markov feature relaxing to a stationary P_D
(`occtrack.models.markov`), one number for every object. A lidar detector's P_D is not one
number: the points on an object fall off as 1 / r^2, and PointRCNN finds a car it can see at
20 m every time and one at 60 m four times in five. An object missed where the detector
never misses it is gone; one missed where it often does may well be there. So the stationary
P_D is a profile over range, per class, in bands an octave of range wide (the points fall
fourfold an octave), learnt from the tracker's own objects:

    P_D(c, b) = (H_cb + n0 P_D0) / (N_cb + n0),

H_cb and N_cb the discounted sums, over the objects of class c in band b that could be seen
(not hidden by another, as the occlusion model says), of their weight (the probability that
the object is real) times whether it took a detection, and of their weight; n0 = `prior_weight`
pseudo-objects at the configured P_D0 hold a band few objects visit, and the sums forget with
`memory` seconds, so the profile follows the scene.

Hand-written: a weighted count per cell; no library learns a filter's detection profile from
its own tracks.
"""

from __future__ import annotations

import math

import numpy as np

BANDS = (10.0, 20.0, 40.0)
"""m: the band edges, an octave apart (below 10 m, 10-20, 20-40, beyond 40)."""


class DetectionProfile:
    """The learnt stationary P_D per class and range band (see the module)."""

    def __init__(self, prior: float, bands: tuple[float, ...] = BANDS,
                 prior_weight: float = 20.0, memory: float = 60.0):
        if not 0.0 <= prior <= 1.0:
            raise ValueError(f"prior P_D must be in [0, 1], not {prior}")
        if not prior_weight > 0 or not memory > 0:
            raise ValueError("prior_weight and memory must be positive")
        self.prior, self.prior_weight = float(prior), float(prior_weight)
        self.memory = float(memory)
        self.edges = np.asarray(bands, dtype=float)
        self._hits: dict[int, np.ndarray] = {}
        self._trials: dict[int, np.ndarray] = {}

    def band_of(self, ranges: np.ndarray) -> np.ndarray:
        """The band of each range (m): 0 below the first edge, an edge opening its band."""
        return np.searchsorted(self.edges, np.asarray(ranges, dtype=float), side="right")

    def update(self, classes: np.ndarray, ranges: np.ndarray, hit: np.ndarray,
               weight: np.ndarray, dt: float) -> None:
        """One frame: the objects that could be seen, their class, range (m), whether each
        took a detection and its weight (the probability that it is real)."""
        keep = math.exp(-dt / self.memory)
        for table in (*self._hits.values(), *self._trials.values()):
            table *= keep
        band = self.band_of(ranges)
        for c in np.unique(classes).tolist():
            m = np.asarray(classes) == c
            hits = self._hits.setdefault(int(c), np.zeros(len(self.edges) + 1))
            trials = self._trials.setdefault(int(c), np.zeros(len(self.edges) + 1))
            np.add.at(hits, band[m], np.asarray(weight, float)[m] * np.asarray(hit, float)[m])
            np.add.at(trials, band[m], np.asarray(weight, float)[m])

    def probability(self, classes: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """(n,) the stationary P_D of objects of `classes` at `ranges` (m)."""
        band = self.band_of(ranges)
        out = np.full(len(band), self.prior)
        n0 = self.prior_weight
        for c in np.unique(classes).tolist():
            if int(c) not in self._hits:
                continue
            m = np.asarray(classes) == c
            hits, trials = self._hits[int(c)], self._trials[int(c)]
            out[m] = (hits[band[m]] + n0 * self.prior) / (trials[band[m]] + n0)
        return out
