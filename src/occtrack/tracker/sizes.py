"""The sizes of the detections each track takes, for learning the half-size process noise.

Per label slot the last `lag + 1` tracked frames' detected half-sizes (both axes, with the
box height and whether both edges of the axis were measured: an edge on the image border is
not), and the Bernoulli they belonged to (`slot_serial`: a slot reused by another object
starts afresh). Each frame, for every slot that took a detection, the relative half-size
changes to its detections 1 and `lag` tracked frames before go to the
`models.motion.SizeNoiseLearner`. Memory is that of the label slots: bounded by the scene.
"""

from __future__ import annotations

import numpy as np

from occtrack.models.motion import SizeNoiseLearner
from occtrack.tracker._tracker import _record_sizes


class SizeHistory:
    def __init__(self, learner: SizeNoiseLearner):
        self.learner = learner
        self.depth = learner.lag + 1
        self.step = 0
        self._grow(0)

    def _grow(self, slots: int) -> None:
        old = getattr(self, "serial", np.zeros(0, np.int64))
        extra = slots - len(old)
        if extra <= 0 and slots:
            return
        d = self.depth
        if not slots:
            self.serial = np.full(0, -1, np.int64)
            self.when = np.full((0, d), -1, np.int64)
            self.half = np.zeros((0, d, 2))
            self.height = np.ones((0, d))
            self.valid = np.zeros((0, d, 2), bool)
            return
        self.serial = np.append(self.serial, np.full(extra, -1, np.int64))
        self.when = np.concatenate([self.when, np.full((extra, d), -1, np.int64)])
        self.half = np.concatenate([self.half, np.zeros((extra, d, 2))])
        self.height = np.concatenate([self.height, np.ones((extra, d))])
        self.valid = np.concatenate([self.valid, np.zeros((extra, d, 2), bool)])

    def record(self, serial: np.ndarray, took: np.ndarray, boxes: np.ndarray,
               observed: np.ndarray) -> None:
        """One tracked frame: `serial` (L,) each slot's Bernoulli, `took` (L,) the detection
        it took (-1: none), `boxes` (M, 4) left, top, width, height, `observed` (M, 2, 2)
        which of their edges were measured. (The loop over slots is compiled:
        `_record_sizes`.)"""
        self._grow(len(serial))
        t = self.step
        self.step += 1
        if not (took >= 0).any():
            return
        first, later = _record_sizes(
            self.serial, self.when, self.half, self.height, self.valid,
            np.ascontiguousarray(serial, dtype=np.int64),
            np.ascontiguousarray(took, dtype=np.int64),
            np.ascontiguousarray(boxes, dtype=float),
            np.ascontiguousarray(observed, dtype=bool), t, self.learner.lag)
        self.learner.add(1, first)
        self.learner.add(self.learner.lag, later)
