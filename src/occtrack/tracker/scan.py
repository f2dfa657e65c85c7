"""The lidar scan tracker (issue 24, item 2): the box tracker's Poisson multi-Bernoulli filter
(`occtrack.filters.gmpmb`) fed whole 2-D scans through the scan measurement model
(`occtrack.models.scan_segments`) and the scan occlusion term (`occtrack.occlusion.scan`).
`likelihood` picks the baselines: "hand-made" (`models.scan_hand_made`), "cluster"
(cluster-then-track, `models.point`).

    tracker = ScanTracker(ScanTrackerConfig(occlusion="measurement-wise"))
    for time, angles, ranges in scans:          # angles in the world frame, ranges inf: none
        tracks = tracker.update(ranges, angles, time)
        tracks.ids, tracks.positions, tracks.velocities, tracks.existence, tracks.occluded

Objects are discs of `radius`; a reported object is a confirmed Bernoulli with existence above
`report_existence` and confidence at least `report_min_confidence` (default 0: off).
`confidence` is existence times the probability that the true centre lies within one radius
of the reported one (the centre's Gaussian taken as round, with variance sx sy:
1 - exp(-a^2 / (2 sx sy))).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from occtrack.config.scan import CENTIMETRES, ScanTrackerConfig
from occtrack.filters.gmpmb import GaussianMixturePMB
from occtrack.models.beam import BeamModel
from occtrack.models.point import PointMeasurement
from occtrack.models.scan_hand_made import HandMadeScanMeasurement
from occtrack.models.scan_segments import ScanBirths, ScanMeasurement
from occtrack.occlusion.scan import scan_occlusion

HIDDEN_ABOVE = 0.5  # a missed object is reported hidden when occlusion more likely caused it


@dataclass(frozen=True)
class ScanTracks:
    """The objects reported after one scan, n of them, sorted by id: ids (n,), positions and
    velocities (n, 2) in the world (m, m/s), existence and confidence (n,), occluded (n,)
    (missed this scan, and more likely hidden than not; never under occlusion "none") and
    segment (n,) the index of the segment each took (-1: none)."""

    ids: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    occluded: np.ndarray
    segment: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)


@dataclass(frozen=True)
class ScanTrackResult:
    """Every reported object of a run, one row an object a scan: time, id, position (N, 2),
    velocity (N, 2), existence, confidence, occluded."""

    time: np.ndarray
    id: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    occluded: np.ndarray

    def __len__(self) -> int:
        return len(self.time)


class ScanTracker:
    """`update(ranges, angles, timestamp)` a scan; `run(scans)` over many."""

    def __init__(self, config: ScanTrackerConfig | None = None, beams: int = 720,
                 rate: float = 10.0, origin: tuple[float, float] = (0.0, 0.0)):
        self.config = config or ScanTrackerConfig()
        self.beams, self.rate = int(beams), float(rate)
        self.origin = np.asarray(origin, float)
        self.reset()

    def reset(self) -> None:
        c = self.config
        self.beam_model = BeamModel(p_d=c.p_d, sigma=c.range_noise,
                                    clutter_rate=c.clutter_per_scan / self.beams,
                                    max_range=c.max_range)
        frame = (c.segment_jump, c.segment_gap, CENTIMETRES, tuple(self.origin))
        if c.likelihood == "cluster":
            self.measurement = PointMeasurement(self.beam_model, c.radius, c.cluster_noise,
                                                c.clutter_per_scan, *frame)
        elif c.likelihood == "hand-made":
            self.measurement = HandMadeScanMeasurement(self.beam_model, c.radius, *frame)
        else:
            self.measurement = ScanMeasurement(self.beam_model, c.radius, *frame)
        births = ScanBirths(self.measurement, c.birth_mass, c.edge_birth_mass,
                            c.initial_birth_mass, c.edge_width, c.birth_position_std,
                            c.birth_speed_std, c.min_birth_beams)
        self.filter = GaussianMixturePMB(c.filter_config(self.rate), scan_occlusion(c.occlusion),
                                         self.measurement, births)
        self._last_time: float | None = None
        self.segments = None

    def update(self, ranges: npt.ArrayLike, angles: npt.ArrayLike, timestamp: float,
               origin: npt.ArrayLike | None = None) -> ScanTracks:
        """Track one scan: `ranges` (B,) m (inf or >= max_range: no return) along world
        `angles` (B,) rad, sorted, from the sensor at `origin` (default: the tracker's),
        taken at `timestamp` s. Returns the objects reported after it."""
        angles = np.asarray(angles, float)
        ranges = np.asarray(ranges, float)
        if angles.shape != ranges.shape or angles.ndim != 1:
            raise ValueError("ranges and angles must be 1-D arrays of the same length")
        if np.any(np.diff(angles) <= 0):
            raise ValueError("angles must increase from beam to beam")
        if np.isnan(ranges).any() or (ranges < 0).any():
            raise ValueError("ranges must be >= 0 (inf for no return)")
        t = float(timestamp)
        if not math.isfinite(t):
            raise ValueError(f"timestamp must be a finite number of seconds, not {t}")
        dt = 1.0 / self.rate if self._last_time is None else t - self._last_time
        if not dt > 0:
            raise ValueError(f"timestamp {t} is not after the last ({self._last_time})")
        if dt > self.config.max_gap:  # no prediction bridges it (its covariance would overflow)
            warnings.warn(f"occtrack: {dt:g} s since the previous scan, more than max_gap "
                          f"({self.config.max_gap:g} s): every track ends and tracking starts "
                          f"afresh", stacklevel=2)
            serial = self.filter._next_serial
            self.reset()
            self.filter._next_serial = serial  # ids go on where they were, never reused
            dt = 1.0 / self.rate
        self._last_time = t
        where = self.origin if origin is None else np.asarray(origin, float)
        z = self.measurement.segments(angles, ranges, where)
        self.segments = z
        self.filter.step(z, np.ones(len(z)), dt=dt)
        return self.tracks()

    def tracks(self) -> ScanTracks:
        f, c = self.filter, self.config
        r, means, sd = f.object_moments()
        shown = np.flatnonzero(f.confirmed() & (r > c.report_existence))
        shown = shown[np.argsort(f.slot_serial[shown], kind="stable")]
        s = sd[shown] / self.measurement.unit
        a = c.radius
        within = 1.0 - np.exp(-a * a / (2.0 * np.maximum(s[:, 0] * s[:, 1], 1e-12)))
        confidence = r[shown] * within
        keep = confidence >= c.report_min_confidence
        shown, confidence = shown[keep], confidence[keep]
        pos, vel = self.measurement.to_world(means[shown])
        took = f.slot_detection[shown]
        hidden = (took < 0) & (f.slot_hidden[shown] > HIDDEN_ABOVE)
        return ScanTracks(f.slot_serial[shown].copy(), pos, vel, r[shown].copy(), confidence,
                          hidden, took.copy())

    def run(self, scans: Iterable) -> ScanTrackResult:
        """Track every scan of `scans`: (time, world angles, ranges) or (time, angles,
        ranges, origin) tuples (`occtrack.io.scans.Scans` iterates so)."""
        rows = []
        for scan in scans:
            t, angles, ranges = scan[:3]
            origin = scan[3] if len(scan) > 3 else None
            tr = self.update(ranges, angles, t, origin)
            rows.append((np.full(len(tr), float(t)), tr))
        if not rows:
            empty = np.zeros(0)
            return ScanTrackResult(empty, np.zeros(0, np.int64), np.zeros((0, 2)),
                                   np.zeros((0, 2)), empty, empty, np.zeros(0, bool))
        return ScanTrackResult(
            np.concatenate([t for t, _ in rows]),
            np.concatenate([tr.ids for _, tr in rows]),
            np.concatenate([tr.positions for _, tr in rows]),
            np.concatenate([tr.velocities for _, tr in rows]),
            np.concatenate([tr.existence for _, tr in rows]),
            np.concatenate([tr.confidence for _, tr in rows]),
            np.concatenate([tr.occluded for _, tr in rows]))
