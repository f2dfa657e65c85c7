"""The box tracker's Python API: `Tracker(config).step(detections) -> Tracks`, and `run`.

    from occtrack.tracker import Tracker, TrackerConfig
    tracker = Tracker(TrackerConfig(occlusion="measurement-wise", image_size=(1920, 1080)))
    for boxes, scores in frames:             # boxes (M, 4) left, top, width, height
        tracks = tracker.step(boxes, scores)  # tracks.ids, tracks.boxes, tracks.existence

Each `step` is one tracked frame, dt = frame_step / fps seconds after the previous one. Track
ids are given when an object is first reported (existence above `report_existence`) and stay
with it for as long as it keeps its label; an id is never reused.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from occtrack.config import TrackerConfig
from occtrack.filters.gmpmb import GaussianMixturePMB
from occtrack.io.mot import MotTable
from occtrack.models.box import edges_from_ltwh, ltwh_from_states
from occtrack.occlusion.base import OcclusionModel
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry
from occtrack.occlusion.boxes import box_occlusion
from occtrack.progress import progress
from occtrack.tracker.camera import estimate_shift


@dataclass(frozen=True)
class Tracks:
    """The objects reported at one frame: ids (n,), boxes (n, 4) left, top, width, height,
    existence (n,), velocities (n, 2) of the box centres in px / s, and detection_index (n,):
    the detection each object took this frame (its box is then that detection's, as a
    detector-driven tracker reports it), -1 for an object reported without one (coasting:
    the filter's estimate)."""

    ids: np.ndarray
    boxes: np.ndarray
    existence: np.ndarray
    velocities: np.ndarray
    detection_index: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)

    def moved(self, seconds: float) -> Tracks:
        """The same tracks with boxes carried `seconds` further along their velocities (for
        frames that are not tracked: no detection taken)."""
        shift = np.concatenate([self.velocities * seconds, np.zeros((len(self), 2))], axis=1)
        return Tracks(self.ids, self.boxes + shift, self.existence, self.velocities,
                      np.full(len(self), -1, dtype=np.int64))


@dataclass(frozen=True)
class TrackResult:
    """Every reported box of a run, one row each, ready for `occtrack.io.mot.write_mot`."""

    frame: np.ndarray
    id: np.ndarray
    box: np.ndarray
    existence: np.ndarray
    frames: int
    seconds_tracking: float = 0.0

    @property
    def num_tracks(self) -> int:
        return len(np.unique(self.id))


class Tracker:
    """Gaussian-mixture PMB box tracker; occlusion model from `config.occlusion` unless one
    is passed (any object with `terms(ctx) -> OcclusionTerms`)."""

    def __init__(self, config: TrackerConfig | None = None,
                 occlusion: OcclusionModel | None = None):
        self.config = config or TrackerConfig()
        c = self.config
        if occlusion is None:
            geometry = BoxOcclusionGeometry(c.occlusion_gain, *c.occlusion_ramp)
            occlusion = box_occlusion(c.occlusion, geometry, c.occluder_min_existence)
        self.occlusion = occlusion
        self.filter = GaussianMixturePMB(c, occlusion)
        L = len(self.filter.slot_used)  # per label slot, growing with the filter's
        self._reported_serial = np.full(L, -1, dtype=np.int64)
        self._report_id = np.zeros(L, dtype=np.int64)
        self._next_id = 1
        self._boxes = np.zeros((0, 4))
        self._previous = None

    def step(self, boxes: np.ndarray, scores: np.ndarray | None = None,
             camera_motion: np.ndarray | None = None) -> Tracks:
        """Track one frame's detections: boxes (M, 4) left, top, width, height in px, scores
        (M,) detector confidences (1 when None). `camera_motion`, a 2 x 3 affine matrix,
        maps the previous tracked frame's image points to this one's (its rotation and shear
        are ignored: the state holds boxes); without it the camera's shift is estimated from
        the detections (`camera_motion = "detections"`) or taken as none."""
        boxes = np.asarray(boxes, dtype=float)
        if boxes.size == 0:
            boxes = boxes.reshape(0, 4)
        if boxes.ndim != 2 or boxes.shape[1] != 4:
            raise ValueError(f"boxes must have shape (M, 4), not {boxes.shape}")
        if not np.isfinite(boxes).all():
            raise ValueError("boxes contain NaN or infinity")
        if (boxes[:, 2:] < 0).any():
            raise ValueError("boxes have a negative width or height")
        scores = np.ones(len(boxes)) if scores is None else np.asarray(scores, dtype=float)
        if scores.shape != (len(boxes),) or not np.isfinite(scores).all():
            raise ValueError("scores must be M finite numbers, one per box")
        boxes = boxes.copy()
        boxes[:, 2:] = np.maximum(boxes[:, 2:], 1.0)
        camera = None
        if camera_motion is not None:
            affine = np.asarray(camera_motion, dtype=float)
            if affine.shape != (2, 3) or not np.isfinite(affine).all():
                raise ValueError("camera_motion must be a finite 2 x 3 affine matrix")
            camera = (np.diag(affine[:, :2]).copy(), affine[:, 2].copy())
        elif self.config.camera_motion == "detections" and self._previous is not None:
            shift = estimate_shift(self._previous, boxes)
            if shift is not None:
                camera = (np.ones(2), shift)
        self.filter.step(edges_from_ltwh(boxes), scores, camera)
        self._boxes = boxes
        self._previous = boxes
        return self.tracks()

    def tracks(self) -> Tracks:
        """The objects reported now, by id: existence above `report_existence`, and either
        detected at this step or unseen for at most `report_coast_time` with the centre known
        to within `report_centre_std` box heights (a coasting estimate drifts, and a box
        shown where nobody is costs more than one left out)."""
        f, c = self.filter, self.config
        grow = len(f.slot_used) - len(self._report_id)
        if grow > 0:
            self._reported_serial = np.append(self._reported_serial, np.full(grow, -1))
            self._report_id = np.append(self._report_id, np.zeros(grow, dtype=np.int64))
        r, means, centre_std = f.object_moments()
        took = f.slot_detection
        height = np.maximum(2.0 * means[:, 1, 2], 1.0)
        trusted = (took >= 0) | ((f.slot_coast <= c.report_coast_time + 1e-9)
                                 & (centre_std.max(axis=1) < c.report_centre_std * height))
        shown = np.flatnonzero(f.slot_used & (r > c.report_existence) & trusted)
        fresh = shown[self._reported_serial[shown] != f.slot_serial[shown]]
        self._report_id[fresh] = self._next_id + np.arange(len(fresh))
        self._reported_serial[fresh] = f.slot_serial[fresh]
        self._next_id += len(fresh)
        ids = self._report_id[shown]
        order = np.argsort(ids)
        shown = shown[order]
        boxes = ltwh_from_states(means[shown])
        index = took[shown]
        detected = index >= 0
        boxes[detected] = self._boxes[index[detected]]
        return Tracks(ids[order], boxes, r[shown], means[shown, :, 1].copy(), index)

    def run(self, detections: MotTable | Iterable[np.ndarray], num_frames: int | None = None,
            quiet: bool = True, desc: str = "tracking") -> TrackResult:
        """Track a whole sequence, reporting at every frame.

        `detections` is a MotTable (frames 1..num_frames) or one array per frame, (M, 4) boxes
        or (M, 5) boxes and scores. Every `frame_step`-th frame is tracked, starting with the
        first; in between, the last tracks are carried along their velocities."""
        frames = list(_frames(detections, num_frames))
        c = self.config
        rows_frame, rows_id, rows_box, rows_r = [], [], [], []
        tracks = None
        start = time.perf_counter()
        for index, (boxes, scores) in enumerate(progress(frames, len(frames), desc, quiet)):
            offset = index % c.frame_step
            if offset == 0:
                tracks = self.step(boxes, scores)
                shown = tracks
            else:
                shown = tracks.moved(offset / c.fps)
            rows_frame.append(np.full(len(shown), index + 1))
            rows_id.append(shown.ids)
            rows_box.append(shown.boxes)
            rows_r.append(shown.existence)
        seconds = time.perf_counter() - start
        if not frames:
            return TrackResult(np.zeros(0, int), np.zeros(0, int), np.zeros((0, 4)),
                               np.zeros(0), 0, seconds)
        return TrackResult(np.concatenate(rows_frame), np.concatenate(rows_id),
                           np.concatenate(rows_box), np.concatenate(rows_r), len(frames),
                           seconds)


def _frames(detections, num_frames: int | None) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    if isinstance(detections, MotTable):
        for rows in detections.frame_slices(num_frames):
            yield detections.box[rows], detections.score[rows]
        return
    for index, frame in enumerate(detections):
        if num_frames is not None and index >= num_frames:
            return
        arr = np.asarray(frame, dtype=float)
        if arr.size == 0:
            arr = arr.reshape(0, 4)
        if arr.ndim != 2 or arr.shape[1] not in (4, 5):
            raise ValueError(f"frame {index + 1}: detections must be (M, 4) or (M, 5), "
                             f"not {arr.shape}")
        yield arr[:, :4], (arr[:, 4] if arr.shape[1] == 5 else None)
