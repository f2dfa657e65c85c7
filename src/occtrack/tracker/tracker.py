"""The box tracker's Python API: `Tracker(config).update(...) -> Tracks`, `step` and `run`.

    from occtrack import Tracker, TrackerConfig

    tracker = Tracker(TrackerConfig(image_size=(1920, 1080), fps=30))
    for t, (boxes, scores, classes) in enumerate(detector_output):   # boxes (M, 4) x1 y1 x2 y2
        tracks = tracker.update(boxes, scores, classes, timestamp=t / 30)
        tracks.ids, tracks.boxes, tracks.classes, tracks.detection_index, tracks.occluded

`update` takes boxes in any of the usual formats ("xyxy", "ltwh", "cxcywh") and returns them in
the same one; each call is one frame, `timestamp` seconds into the video (the time step is the
difference, so dropped and irregular frames are predicted over their true interval; without
timestamps, frames are 1 / fps apart). `step` is the same in left, top, width, height with the
time step given directly (`dt`), and `run` tracks a whole sequence.

Track ids are given when an object is first reported (existence above `report_existence`) and
stay with it for as long as it keeps its label; an id is never reused. An object has one class
for life, that of the detection it was born from, and takes only detections of that class.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from occtrack.config import TrackerConfig
from occtrack.filters.gmpmb import GaussianMixturePMB
from occtrack.io.mot import MotTable
from occtrack.models.box import edges_from_ltwh
from occtrack.models.motion import SizeNoiseLearner
from occtrack.models.occludability import OccludabilityLearner
from occtrack.models.score_model import ScoreLearner
from occtrack.occlusion.base import OcclusionModel
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry
from occtrack.occlusion.boxes import box_occlusion
from occtrack.progress import progress
from occtrack.tracker._tracker import _report_rows, _reported
from occtrack.tracker.boxes import (
    BoxFormat,
    as_array,
    check_classes,
    check_format,
    check_scores,
    check_time,
    checked_frame,
    from_ltwh,
    to_ltwh,
)
from occtrack.tracker.camera import estimate_camera
from occtrack.tracker.confidence import report_confidence
from occtrack.tracker.sizes import SizeHistory

CAMERA_MEMORY = 1.0
"""s: the time constant of the camera's remembered speed (`Tracker.step`)."""
OCCLUDED_ABOVE = 0.5
"""A missed object is reported as occluded when the probability that occlusion caused its miss
is above this."""


@dataclass(frozen=True)
class Tracks:
    """The objects reported at one frame, n of them, sorted by id.

    Attributes:
        ids: (n,) int track ids, unique, never reused.
        boxes: (n, 4) float boxes in `box_format`: the detection's own box for an object that
            took one this frame (an edge of it on the image border replaced by the filter's
            where the person runs on past it), the filter's estimate for one that did not.
        existence: (n,) probability that each object exists.
        confidence: (n,) probability that each box is a real object at that place: the
            object exists and its true box overlaps the reported one at IoU >= 0.5
            (`occtrack.tracker.confidence`), the 7th column of every result file; how well it
            keeps its word is measured by `occtrack eval --calibration` (docs/confidence.md).
        velocities: (n, 2) velocity of each box centre, px / s.
        detection_index: (n,) int, the index of the detection each object took this frame
            (into the boxes given to `update` / `step`), -1 for an object reported without one
            (coasting on the filter's estimate).
        classes: (n,) int class of each object (0 when no classes were given), fixed for life.
        occluded: (n,) bool, True for an object reported without a detection whose miss is
            more likely occlusion's doing than not (never under `occlusion = "none"`).
        box_format: "ltwh" (left, top, width, height), "xyxy" or "cxcywh".
    """

    ids: np.ndarray
    boxes: np.ndarray
    existence: np.ndarray
    velocities: np.ndarray
    detection_index: np.ndarray
    classes: np.ndarray
    occluded: np.ndarray
    confidence: np.ndarray
    box_format: str = "ltwh"

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def coasting(self) -> np.ndarray:
        """(n,) bool: reported without a detection this frame."""
        return self.detection_index < 0

    def moved(self, seconds: float) -> Tracks:
        """The same tracks with boxes carried `seconds` further along their velocities (for
        frames that are not tracked: no detection taken)."""
        step = self.velocities * seconds
        zeros = np.zeros((len(self), 2))
        shift = np.concatenate([step, step if self.box_format == "xyxy" else zeros], axis=1)
        return Tracks(self.ids, self.boxes + shift, self.existence, self.velocities,
                      np.full(len(self), -1, dtype=np.int64), self.classes, self.occluded,
                      self.confidence, self.box_format)

    def select(self, keep: np.ndarray) -> Tracks:
        """The tracks where `keep` (n,) bool is True, in the same order."""
        return Tracks(self.ids[keep], self.boxes[keep], self.existence[keep],
                      self.velocities[keep], self.detection_index[keep], self.classes[keep],
                      self.occluded[keep], self.confidence[keep], self.box_format)

    def in_format(self, box_format: BoxFormat) -> Tracks:
        """The same tracks with boxes in another format."""
        check_format(box_format)
        if box_format == self.box_format:
            return self
        ltwh = to_ltwh(self.boxes, self.box_format)
        return Tracks(self.ids, from_ltwh(ltwh, box_format), self.existence, self.velocities,
                      self.detection_index, self.classes, self.occluded, self.confidence,
                      box_format)


@dataclass(frozen=True)
class TrackResult:
    """Every reported box of a run, one row each, ready for `occtrack.io.mot.write_mot`."""

    frame: np.ndarray
    id: np.ndarray
    box: np.ndarray
    existence: np.ndarray
    frames: int
    seconds_tracking: float = 0.0  # inside the tracker's steps (and the frames carried between
    # them) only: reading detections and gathering these rows are left out
    coasting: np.ndarray | None = None  # (N,) bool: reported without a detection
    occluded: np.ndarray | None = None  # (N,) bool: ... and its miss put down to occlusion
    confidence: np.ndarray | None = None  # (N,) Tracks.confidence: the result file's 7th column
    classes: np.ndarray | None = None  # (N,) Tracks.classes: each object's class for life
    detection_row: np.ndarray | None = None  # (N,) the row of the MotTable run on whose box the
    # object took in its frame, -1 where none (coasting, or a frame carried between steps)

    @property
    def num_tracks(self) -> int:
        return len(np.unique(self.id))


@dataclass(frozen=True)
class FrameReport:
    """One frame of `Tracker.run_frames`: its number (from 1), the tracks reported, for each
    the row of the MotTable whose box it took (-1: none), and the seconds spent inside the
    tracker on it (the step, or carrying the tracks between steps)."""

    frame: int
    tracks: Tracks
    detection_row: np.ndarray
    seconds: float


MIN_DT = 1e-6  # s: the shortest time between two frames
REFRESH_NOISE = 10  # tracked frames between renewals of the learnt size noise
EXPANSION_SIGMAS = 5.0
"""With `camera_expansion`: the camera's forward motion k moves the predictions only as far as
the detections pin it, k (1 - (z sigma_k / k)^2)^+: none below z standard errors. 5 is the
smallest of 3, 5 and 8 that keeps MOT17's FRCNN sequences within .005 HOTA (docs/benchmarks.md)."""


class Tracker:
    """Gaussian-mixture PMB box tracker.

    Args:
        config: every setting (`TrackerConfig`); the image size and frame rate matter most:
            births come in at the image's edges and the time step without timestamps is
            1 / fps. Defaults: `TrackerConfig()` (1920 x 1080 at 30 fps).
        occlusion: an occlusion model (any object with `terms(ctx) -> OcclusionTerms`, see
            `occtrack.occlusion.base`); by default the one `config.occlusion` names.
    """

    def __init__(self, config: TrackerConfig | None = None,
                 occlusion: OcclusionModel | None = None):
        if config is not None and not isinstance(config, TrackerConfig):
            raise ValueError(f"config must be a TrackerConfig, not {type(config).__name__}")
        self.config = config or TrackerConfig()
        c = self.config
        if occlusion is None:
            geometry = BoxOcclusionGeometry(c.occlusion_gain, *c.occlusion_ramp)
            occlusion = box_occlusion(c.occlusion, geometry, c.occluder_min_existence)
        self.occlusion = occlusion
        self._centre = np.asarray(c.image_size, dtype=float) / 2.0  # the focus of the
        # camera's expansion (`_camera_motion`)
        self.reset()

    def reset(self) -> None:
        """Forget every object and start again (ids start again at 1)."""
        c = self.config
        self.filter = GaussianMixturePMB(c, self.occlusion)
        L = len(self.filter.slot_used)  # per label slot, growing with the filter's
        self._reported_serial = np.full(L, -1, dtype=np.int64)
        self._report_id = np.zeros(L, dtype=np.int64)
        self._next_id = 1
        self._boxes = np.zeros((0, 4))  # the last step's detections (camera shift, reports)
        self._timestamp: float | None = None
        self._camera_power = np.zeros(2)
        self._expansion_power = 0.0  # 1 / (px s)^2: the camera's recent squared expansion rate
        self._sizes = SizeHistory(SizeNoiseLearner(c.size_noise))
        self._scores = ScoreLearner(c.score_floor, c.clutter_score_power)
        if c.learn_occludability:
            self.filter.occludability_learner = OccludabilityLearner(c.occludability)
        if c.learn_score_model:
            self.filter.measurement.score_model = self._scores

    def _restart(self) -> None:
        """Forget every object, as `reset`, but go on numbering ids where they were (a
        restart inside one run must not give a new object an old object's id)."""
        next_id = self._next_id
        self.reset()
        self._next_id = next_id

    def update(self, boxes: npt.ArrayLike, scores: npt.ArrayLike | None = None,
               classes: npt.ArrayLike | None = None, timestamp: float | None = None,
               box_format: BoxFormat = "xyxy",
               camera_motion: npt.ArrayLike | None = None) -> Tracks:
        """Track one frame's detections and return the objects reported now.

        Args:
            boxes: (M, 4) detections in pixels, in `box_format`: "xyxy" (x1, y1, x2, y2, the
                default, as YOLO and supervision give them), "ltwh" (left, top, width,
                height) or "cxcywh" (centre x, centre y, width, height).
            scores: (M,) detector confidences in [0, 1]; None: all 1.
            classes: (M,) class ids; an object keeps the class it was born with and takes
                only detections of that class. None: one class (reported as 0).
            timestamp: when the frame was taken, in seconds (any origin, increasing). The
                time step is the difference from the previous call's, so irregular and
                dropped frames are predicted over their true interval. None: 1 / fps (times
                `frame_step`) after the previous frame.
            box_format: the format of `boxes`, and of the boxes returned.
            camera_motion: a 2 x 3 affine matrix from the previous frame's image to this
                one's (see `step`); None: estimated from the detections, as configured.

        Returns:
            `Tracks`: ids, boxes (in `box_format`), existence, velocities, classes,
                detection_index (into `boxes`; -1: none taken) and occluded, sorted by id.

        Raises:
            ValueError: a bad box format, shape or value, scores or classes that do not
                match the boxes, or a timestamp that does not increase.
        """
        check_format(box_format)
        ltwh = to_ltwh(boxes, box_format)
        dt = None
        if timestamp is not None:
            now = check_time(timestamp, "timestamp")
            if self._timestamp is not None:
                dt = now - self._timestamp
                if dt <= 0:
                    raise ValueError(f"timestamp {now} does not follow the previous frame's "
                                     f"{self._timestamp}; timestamps must increase")
        tracks = self.step(ltwh, scores, camera_motion, classes=classes, dt=dt)
        if timestamp is not None:
            self._timestamp = now
        elif self._timestamp is not None:
            self._timestamp += self.filter.dt
        out = tracks.in_format(box_format)
        index = out.detection_index
        # the caller's own boxes, not a round trip through ltwh, where the box is the
        # detection's (a box the image border cuts runs on to the state's edge: `_report_rows`)
        copied = index >= 0
        copied[copied] = (tracks.boxes[copied] == ltwh[index[copied]]).all(axis=1)
        if copied.any():
            original = np.asarray(boxes, dtype=float).reshape(-1, 4)
            out.boxes[copied] = original[index[copied]]
        return out

    def step(self, boxes: npt.ArrayLike, scores: npt.ArrayLike | None = None,
             camera_motion: npt.ArrayLike | None = None, *,
             classes: npt.ArrayLike | None = None, dt: float | None = None) -> Tracks:
        """Track one frame's detections: boxes (M, 4) left, top, width, height in px, scores
        (M,) detector confidences (1 when None), classes (M,) class ids (None: one class),
        `dt` seconds after the previous step (None: `config.dt`, frame_step / fps).
        `camera_motion`, a 2 x 3 affine matrix, maps the previous tracked frame's image
        points to this one's (its rotation and shear are ignored: the state holds boxes);
        without it the camera's shift is estimated from the detections
        (`camera_motion = "detections"`) or taken as none. Boxes of the returned tracks are
        left, top, width, height."""
        checked = checked_frame(boxes, scores)
        if checked is None:
            boxes = to_ltwh(boxes, "ltwh")
            scores = check_scores(scores, len(boxes))
            boxes[:, 2:] = np.maximum(boxes[:, 2:], 1.0)
        else:
            boxes = checked
        labels = check_classes(classes, len(boxes))
        if dt is not None:
            dt = check_time(dt, "dt")
            if dt < MIN_DT:
                raise ValueError(f"dt must be at least {MIN_DT:g} s (frames a microsecond "
                                 f"apart are one frame), not {dt:g}")
            if dt > self.config.max_gap:
                warnings.warn(f"occtrack: {dt:g} s since the previous frame, more than "
                              f"max_gap ({self.config.max_gap:g} s): every track ends and "
                              f"tracking starts afresh", stacklevel=2)
                self._restart()
                dt = None
        camera = None
        if camera_motion is not None:
            affine = as_array(camera_motion, "camera_motion", "(a 2 x 3 affine matrix)")
            if affine.shape != (2, 3) or not np.isfinite(affine).all():
                raise ValueError("camera_motion must be a finite 2 x 3 affine matrix")
            camera = (np.diag(affine[:, :2]).copy(), affine[:, 2].copy())
        elif self.config.camera_motion == "detections":
            camera = self._camera_motion(boxes, self.config.dt if dt is None else dt)
        edges = edges_from_ltwh(boxes)
        self.filter.step(edges, scores, camera, dt=dt, classes=labels)
        if self.config.learn_score_model:
            self._scores.update(scores, self.filter.clutter_probability, self.filter.dt)
        if self.config.learn_size_noise:
            f = self.filter
            self._sizes.record(f.slot_serial, f.slot_detection, boxes, f.observed)
            # (the differences span tracked frames of the nominal step, whatever this step's;
            # once the learner holds its full memory, a few frames' new differences barely
            # move the medians of thousands, and the estimate is renewed every REFRESH_NOISE
            # tracked frames; until then every frame)
            learner = self._sizes.learner
            if not learner.full or self._sizes.step % REFRESH_NOISE == 1:
                f.size_noise = learner.noise(self.config.dt)
        self._boxes = boxes
        return self.tracks()

    def _camera_motion(self, boxes: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
        """The camera's shift from the last frame's detections to these, and its variance:
        the estimate's own (how well the detections pin it, `estimate_camera`) or, where
        too few boxes pair up and the shift is taken as 0, the camera's recent mean square
        shift (how fast it has been moving: an exponential average over `CAMERA_MEMORY`
        seconds). Every prediction widens by that variance, coasting boxes included, so a
        camera that turns makes their confidence fall (a still camera: about 0).

        The same memory keeps the camera's recent squared expansion rate (`_expansion_power`,
        `estimate_expansion`: k^2 less its variance, so that a still camera's noise averages to
        0, per second squared): what the one shift leaves out, which `tracks` adds to the
        spread of a coasting box's confidence."""
        motion = estimate_camera(self._boxes, boxes, self._centre)
        keep = math.exp(-dt / CAMERA_MEMORY)
        expansion = motion[2] if motion is not None else None
        rate = 0.0 if expansion is None else (expansion[0] ** 2 - expansion[1]) / dt ** 2
        self._expansion_power = keep * self._expansion_power + (1.0 - keep) * rate
        if motion is None:
            return np.ones(2), np.zeros(2), self._camera_power.copy()
        shift, error = motion[0], motion[1]
        self._camera_power = keep * self._camera_power + (1.0 - keep) * shift ** 2
        if self.config.camera_expansion and expansion is not None:
            k, variance = expansion
            # an estimate that the detections do not pin is shrunk toward a still camera
            # (k (1 - z^2 var / k^2)^+, z = EXPANSION_SIGMAS), so a walker's own steps move
            # no box
            k = k * max(0.0, 1.0 - EXPANSION_SIGMAS**2 * variance / max(k * k, 1e-300))
            return np.ones(2), shift, error ** 2, (self._centre, k)
        return np.ones(2), shift, error ** 2

    def tracks(self) -> Tracks:
        """The objects reported now, by id: existence above `report_existence` and confidence
        at least `report_min_confidence` (by default .5: a box more likely right than wrong;
        a coasting estimate drifts, its confidence falls, and it goes), and, where the optional
        coast limits are set, an undetected one only while unseen for at most
        `report_coast_time` with its centre known to within `report_centre_std` box heights.
        Boxes are left, top, width, height."""
        f, c = self.filter, self.config
        grow = len(f.slot_used) - len(self._report_id)
        if grow > 0:
            self._reported_serial = np.append(self._reported_serial, np.full(grow, -1))
            self._report_id = np.append(self._report_id, np.zeros(grow, dtype=np.int64))
        r, means, centre_std = f.object_moments()
        took = f.slot_detection
        shown, self._next_id = _reported(
            r, means, centre_std, f.slot_used, took, f.slot_coast, f.slot_serial,
            self._reported_serial, self._report_id, self._next_id, c.report_existence,
            math.inf if c.report_coast_time is None else c.report_coast_time,
            math.inf if c.report_centre_std is None else c.report_centre_std)
        boxes, existence, velocities, index, classes, occluded = _report_rows(
            shown, r, means, took, self._boxes, f.slot_hidden, f.slot_class, OCCLUDED_ABOVE,
            f.observed)
        n = f.n
        confidence = report_confidence(f.label[:n], f.mass[:n], f.mean[:n], f.cov[:n], r, means,
                                       shown, boxes, index >= 0,
                                       c.confidence_centre == "detection", f.slot_coast,
                                       self._expansion_power, self._centre,
                                       c.report_min_confidence)
        tracks = Tracks(self._report_id[shown], boxes, existence, velocities, index, classes,
                        occluded, confidence)
        if c.report_min_confidence > 0 and confidence.min(initial=1.0) < c.report_min_confidence:
            tracks = tracks.select(confidence >= c.report_min_confidence)
        return tracks

    def run(self, detections: MotTable | Iterable[npt.ArrayLike], num_frames: int | None = None,
            quiet: bool = True, desc: str = "tracking", classes: bool = False) -> TrackResult:
        """Track a whole sequence, reporting at every frame.

        `detections` is a MotTable (frames 1..num_frames; `occtrack.io.mot.read_detections`
        reads one from a file) or one array per frame, (M, 4) boxes left, top, width, height
        or (M, 5) boxes and scores. Every `frame_step`-th frame is tracked, starting with the
        first; in between, the last tracks are carried along their velocities. Frames are
        read one at a time, so a long stream is never held in memory (only the result rows;
        `run_frames` hands them over a frame at a time instead).
        `classes` (a MotTable only): its `cls` column is each detection's class (`step`'s
        `classes`), as KITTI's types are (`occtrack.io.kitti`)."""
        keys = ("frame", "id", "box", "r", "coast", "occ", "conf", "cls", "row")
        rows: dict[str, list] = {k: [] for k in keys}
        count, seconds = 0, 0.0
        for frame in self.run_frames(detections, num_frames, quiet, desc, classes):
            count += 1
            seconds += frame.seconds
            shown = frame.tracks
            rows["frame"].append(np.full(len(shown), frame.frame))
            rows["id"].append(shown.ids)
            rows["box"].append(shown.boxes)
            rows["r"].append(shown.existence)
            rows["coast"].append(shown.coasting)
            rows["occ"].append(shown.occluded)
            rows["conf"].append(shown.confidence)
            rows["cls"].append(shown.classes)
            rows["row"].append(frame.detection_row)
        if not count:
            return TrackResult(np.zeros(0, int), np.zeros(0, int), np.zeros((0, 4)),
                               np.zeros(0), 0, seconds, np.zeros(0, bool), np.zeros(0, bool),
                               np.zeros(0), np.zeros(0, int), np.zeros(0, int))
        return TrackResult(*(np.concatenate(rows[k]) for k in ("frame", "id", "box", "r")),
                           count, seconds, *(np.concatenate(rows[k])
                                             for k in ("coast", "occ", "conf", "cls", "row")))

    def run_frames(self, detections: MotTable | Iterable[npt.ArrayLike],
                   num_frames: int | None = None, quiet: bool = True, desc: str = "tracking",
                   classes: bool = False) -> Iterator[FrameReport]:
        """`run`, one `FrameReport` a frame as it is tracked: what a writer streams to a file,
        so that memory stays that of the scene however long the sequence."""
        if isinstance(detections, str | bytes | os.PathLike):
            raise ValueError(f"Tracker.run takes detections, not a file name ({detections!r}):"
                             f" read the file first, e.g. occtrack.io.mot.read_detections("
                             f"path, image_size), or run `occtrack track FILE -o RESULT`")
        if not isinstance(detections, MotTable | Iterable):
            raise ValueError(f"Tracker.run takes a MotTable or one (M, 4) or (M, 5) array per "
                             f"frame, not {type(detections).__name__}")
        total = num_frames
        if total is None and isinstance(detections, MotTable):
            total = detections.num_frames
        elif total is None and hasattr(detections, "__len__"):
            total = len(detections)
        c = self.config
        tracks = None
        frames = _frames(detections, num_frames, classes)
        for index, (boxes, scores, labels, source) in enumerate(progress(frames, total, desc,
                                                                         quiet)):
            offset = index % c.frame_step
            start = time.perf_counter()
            if offset == 0:
                tracks = self.step(boxes, scores, classes=labels)
                shown = tracks
                took = shown.detection_index
                row = np.where(took >= 0, source[np.maximum(took, 0)] if len(source) else -1,
                               -1)
            else:
                shown = tracks.moved(offset / c.fps)
                row = np.full(len(shown), -1)
            yield FrameReport(index + 1, shown, row.astype(np.int64),
                              time.perf_counter() - start)


def _frames(detections, num_frames: int | None, classes: bool = False
            ) -> Iterator[tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray]]:
    """Per frame: boxes (ltwh), scores, classes (None: one class) and the detections' rows in
    the MotTable (empty for arrays)."""
    if isinstance(detections, MotTable):
        for rows in detections.frame_slices(num_frames):
            yield (detections.box[rows], detections.score[rows],
                   detections.cls[rows] if classes else None, rows)
        return
    if classes:
        raise ValueError("Tracker.run(classes=True) takes a MotTable, whose cls column holds "
                         "the classes")
    none = np.zeros(0, dtype=np.int64)
    for index, frame in enumerate(detections):
        if num_frames is not None and index >= num_frames:
            return
        arr = as_array(frame, f"frame {index + 1}: detections", "(M, 4) or (M, 5)")
        if arr.size == 0:
            arr = arr.reshape(0, 4)
        if arr.ndim != 2 or arr.shape[1] not in (4, 5):
            raise ValueError(f"frame {index + 1}: detections must be (M, 4) or (M, 5), "
                             f"not {arr.shape}")
        yield arr[:, :4], (arr[:, 4] if arr.shape[1] == 5 else None), None, none
