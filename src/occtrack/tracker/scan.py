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
`report_existence` and confidence at least `report_min_confidence` (default 0: off), whose
centre lies in the sensor's field of view (the beams' span and range; a disc whose centre
leaves it takes the filter's exit_survival, and the filter's square goes with the sensor).
With body "legs" (a laser at leg height) the discs are legs, and the reported objects are the
people `tracker.people.LegPairing` makes of them.
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
from scipy.spatial import cKDTree

from occtrack.config.scan import CENTIMETRES, ScanTrackerConfig
from occtrack.filters.gmpmb import GaussianMixturePMB
from occtrack.io.scans import Tracks
from occtrack.models.beam import BeamModel
from occtrack.models.clutter_map import ClutterMap
from occtrack.models.point import PointMeasurement
from occtrack.models.scan_hand_made import HandMadeScanMeasurement
from occtrack.models.scan_segments import ScanBirths, ScanMeasurement
from occtrack.models.static_scene import StaticScene
from occtrack.occlusion.scan import scan_occlusion
from occtrack.tracker.people import LegPairing

HIDDEN_ABOVE = 0.5  # a missed object is reported hidden when occlusion more likely caused it


@dataclass(frozen=True)
class ScanTracks:
    """The objects reported after one scan, n of them, sorted by id: ids (n,), positions and
    velocities (n, 2) in the world (m, m/s), existence and confidence (n,), occluded (n,)
    (missed this scan, and more likely hidden than not; never under occlusion "none") and
    segment (n,) the index of the segment each took (-1: none; a person: a leg's)."""

    ids: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    occluded: np.ndarray
    segment: np.ndarray
    legs: np.ndarray | None = None  # (n, 2) with body "legs": each person's leg track ids

    def __len__(self) -> int:
        return len(self.ids)


ScanTrackResult = Tracks
"""Every reported object of a run, one row an object a scan: time, id, position (N, 2),
velocity (N, 2), existence, confidence, occluded; a tracks file's rows (`io.scans.Tracks`,
which `write_tracks` writes and `read_tracks` reads back)."""


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
            self.measurement = PointMeasurement(self.beam_model, c.disc_radius, c.cluster_noise,
                                                c.clutter_per_scan, *frame)
        elif c.likelihood == "hand-made":
            self.measurement = HandMadeScanMeasurement(self.beam_model, c.disc_radius, *frame)
        else:
            self.measurement = ScanMeasurement(self.beam_model, c.disc_radius, *frame)
        births = ScanBirths(self.measurement, c.birth_mass, c.edge_birth_mass,
                            c.initial_birth_mass, c.edge_width, c.birth_position_std,
                            c.birth_speed_std, c.min_birth_beams)
        self.filter = GaussianMixturePMB(c.filter_config(self.rate), scan_occlusion(c.occlusion),
                                         self.measurement, births)
        self.pairing = (LegPairing(c.leg_separation, c.leg_gate, c.leg_hold, c.leg_pairs_only)
                        if c.body == "legs" else None)
        self.scene = StaticScene(c.max_range) if c.static_scene else None
        self.clutter = (ClutterMap(self.beam_model.kappa, c.max_range, memory=c.clutter_memory)
                        if c.clutter_map and c.likelihood != "cluster" else None)
        self._last_time: float | None = None
        self._reported: tuple[int, ScanTracks] | None = None
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
            person = None if self.pairing is None else self.pairing._next
            self.reset()
            self.filter._next_serial = serial  # ids go on where they were, never reused
            if person is not None:
                self.pairing._next = person
            dt = 1.0 / self.rate
        self._last_time = t
        where = self.origin if origin is None else np.asarray(origin, float)
        shift = self.measurement.recentre(where)  # the survival region goes with the sensor
        z = self.measurement.segments(angles, ranges, where)
        if self.scene is not None:  # what stood there before this scan, then this scan
            z.static = self.scene.static_probability(*z.points(), len(z))
            self.scene.add_scan(where, angles, ranges)
        returned = np.isfinite(ranges) & (ranges < self.config.max_range)
        if self.clutter is not None:  # each segment's returns against the clutter there
            per_beam = np.zeros(len(ranges))
            per_beam[returned] = self.clutter.log_ratio(ranges[returned])
            z.clutter_log = np.add.reduceat(per_beam[z.beam], z.start[:-1]) if len(z) else (
                np.zeros(0))
        self.segments = z
        camera = (np.ones(2), shift) if shift.any() else None
        self.filter.step(z, np.ones(len(z)), camera=camera, dt=dt)
        if self.clutter is not None:  # the returns no likely object explains were clutter
            self.clutter.learn(ranges, returned & ~self._on_objects(angles, ranges, where), dt)
        return self.tracks()

    def _two_legs_wide(self, segment: np.ndarray) -> np.ndarray:
        """Per segment index (-1: none), whether that segment of this scan is wider than one
        leg can look and at most two legs side by side: (2, 4] leg radii from its first
        return to its last."""
        z, a = self.segments, self.config.leg_radius
        out = np.zeros(len(segment), bool)
        if z is None or len(z) == 0 or not (segment >= 0).any():
            return out
        points, seg = z.points()
        first = np.searchsorted(seg, np.arange(len(z)), side="left")
        last = np.searchsorted(seg, np.arange(len(z)), side="right") - 1
        has = last >= first
        width = np.zeros(len(z))
        width[has] = np.hypot(*(points[last[has]] - points[first[has]]).T)
        w = width[np.maximum(segment, 0)]
        return (segment >= 0) & (w > 2 * a) & (w <= 4 * a)

    def _on_objects(self, angles: np.ndarray, ranges: np.ndarray,
                    origin: np.ndarray) -> np.ndarray:
        """Which returns (B,) are an object's, not clutter: those of the segments a likely
        object (existence above report_existence) took and, with legs, those within half a
        stride and a leg's radius of a person the pairing keeps (where a leg of theirs can
        return from: a leg this scan cut into pieces, a person whose leg tracks broke and
        begin again)."""
        f, z = self.filter, self.segments
        r = f.object_moments()[0]
        took = f.slot_detection[(r > self.config.report_existence) & (f.slot_detection >= 0)]
        on = np.isin(z.segment_of_beam, took)
        people = None if self.pairing is None else self.pairing.kept_positions()
        if people is not None and len(people):
            fin = np.flatnonzero(np.isfinite(ranges))
            points = origin + ranges[fin, None] * np.c_[np.cos(angles[fin]),
                                                         np.sin(angles[fin])]
            reach = self.config.leg_separation / 2 + self.config.leg_radius
            near = cKDTree(people).query(points, distance_upper_bound=reach)
            on[fin] |= np.isfinite(near[0])
        return on

    def tracks(self) -> ScanTracks:
        """The objects reported now: the filter's discs, or with body "legs" the people its
        legs make (`tracker.people`; a person's confidence is its surest leg's, its centre
        within half a stride, `leg_separation` / 2, of the reported one). The people are
        paired once a scan, so asking again before the next scan gives the same answer."""
        if self._reported is not None and self._reported[0] == self.filter.steps:
            return self._reported[1]
        out = self._tracks()
        self._reported = (self.filter.steps, out)
        return out

    def _tracks(self) -> ScanTracks:
        f, c = self.filter, self.config
        r, means, sd = f.object_moments()
        confirmed = f.confirmed()
        # with legs, a leg not yet confirmed may keep its person (a leg track that broke and
        # started again), never start one
        shown = np.flatnonzero((confirmed | (self.pairing is not None))
                               & (r > c.report_existence))
        shown = shown[np.argsort(f.slot_serial[shown], kind="stable")]
        s = sd[shown] / self.measurement.unit
        a = c.radius if self.pairing is None else c.leg_separation / 2
        within = 1.0 - np.exp(-a * a / (2.0 * np.maximum(s[:, 0] * s[:, 1], 1e-12)))
        confidence = r[shown] * within
        pos, vel = self.measurement.to_world(means[shown])
        # a centre the update put beyond the view's edge (a leg seen by the last beams) is
        # not reported: nothing is reported where no beam looks
        keep = (confidence >= c.report_min_confidence) & self.measurement.sees(pos)
        shown, confidence, pos, vel = shown[keep], confidence[keep], pos[keep], vel[keep]
        took = f.slot_detection[shown]
        hidden = (took < 0) & (f.slot_hidden[shown] > HIDDEN_ABOVE)
        if self.pairing is None:
            return ScanTracks(f.slot_serial[shown].copy(), pos, vel, r[shown].copy(),
                              confidence, hidden, took.copy())
        people = self.pairing.update(self._last_time or 0.0, f.slot_serial[shown], pos, vel,
                                     r[shown], confidence, hidden, ~confirmed[shown],
                                     self._two_legs_wide(took))
        people = people.select(self.measurement.sees(people.positions))
        segment = np.full(len(people), -1, dtype=np.int64)
        leg_took = dict(zip(f.slot_serial[shown].tolist(), took.tolist(), strict=True))
        for i, legs in enumerate(people.legs.tolist()):
            segment[i] = max(leg_took.get(leg, -1) for leg in legs)
        return ScanTracks(people.ids, people.positions, people.velocities, people.existence,
                          people.confidence, people.occluded, segment, people.legs)

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
