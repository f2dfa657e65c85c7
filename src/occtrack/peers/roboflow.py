"""Roboflow `trackers` 2.6.1: one function per box-only tracker, MotTable in, MotTable out."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.peers.rows import check_length, check_run, empty_table, result_table

INSTALL_HINT = 'install them with: pip install "occtrack[peers]"'


def available() -> bool:
    """Whether `trackers` (and `supervision`, which it brings) can be imported."""
    return all(importlib.util.find_spec(name) is not None
               for name in ("trackers", "supervision"))


def load():
    """Import `supervision` and `trackers` (about a second the first time), or say how to
    install them."""
    try:
        import supervision
        import trackers
    except ImportError as err:
        raise OcctrackError(f"the peer trackers need the `trackers` package ({err}); "
                            f"{INSTALL_HINT}") from None
    return supervision, trackers


def _run(tracker, det: MotTable, num_frames: int) -> MotTable:
    """Feed frames 1..num_frames to a `trackers` tracker; keep the confirmed tracks' rows."""
    sv, _ = load()
    check_length(det, num_frames)
    corners = np.concatenate([det.box[:, :2], det.box[:, :2] + det.box[:, 2:]], axis=1)
    score = det.score.astype(float)
    out_frame, out_id, out_xyxy, out_score = [], [], [], []
    for frame, rows in enumerate(det.frame_slices(num_frames), start=1):
        if len(rows):
            detections = sv.Detections(xyxy=corners[rows], confidence=score[rows])
        else:
            detections = sv.Detections.empty()
        tracked = tracker.update(detections)
        if tracked.tracker_id is None or not len(tracked):
            continue
        confirmed = tracked.tracker_id >= 0
        out_frame.append(np.full(int(confirmed.sum()), frame))
        out_id.append(tracked.tracker_id[confirmed] + 1)
        out_xyxy.append(tracked.xyxy[confirmed])
        out_score.append(tracked.confidence[confirmed] if tracked.confidence is not None
                         else np.ones(int(confirmed.sum())))
    if not out_frame:
        return empty_table()
    xyxy = np.concatenate(out_xyxy).reshape(-1, 4)
    box = np.concatenate([xyxy[:, :2], xyxy[:, 2:] - xyxy[:, :2]], axis=1)
    return result_table(np.concatenate(out_frame), np.concatenate(out_id), box,
                        np.concatenate(out_score))


def sort(det: MotTable, num_frames: int, fps: float) -> MotTable:
    """SORT (Bewley et al. 2016): Kalman filter and Hungarian IoU matching."""
    check_run(num_frames, fps)
    _, trackers = load()
    return _run(trackers.SORTTracker(frame_rate=fps), det, num_frames)


def bytetrack(det: MotTable, num_frames: int, fps: float) -> MotTable:
    """ByteTrack (Zhang et al. 2022): a second matching round for low-score detections."""
    check_run(num_frames, fps)
    _, trackers = load()
    return _run(trackers.ByteTrackTracker(frame_rate=fps), det, num_frames)


def ocsort(det: MotTable, num_frames: int, fps: float) -> MotTable:
    """OC-SORT (Cao et al. 2023): observation-centric re-update and direction consistency."""
    check_run(num_frames, fps)
    _, trackers = load()
    return _run(trackers.OCSORTTracker(frame_rate=fps), det, num_frames)


def botsort(det: MotTable, num_frames: int, fps: float) -> MotTable:
    """BoT-SORT (Aharon et al. 2022) without images, so without its camera-motion step."""
    check_run(num_frames, fps)
    _, trackers = load()
    return _run(trackers.BoTSORTTracker(frame_rate=fps), det, num_frames)


def cbiou(det: MotTable, num_frames: int, fps: float) -> MotTable:
    """C-BIoU (Yang et al. 2023): matching on buffered (enlarged) boxes."""
    check_run(num_frames, fps)
    _, trackers = load()
    return _run(trackers.CBIoUTracker(frame_rate=fps), det, num_frames)


PEERS: dict[str, Callable[[MotTable, int, float], MotTable]] = {
    "sort": sort, "bytetrack": bytetrack, "ocsort": ocsort, "botsort": botsort, "cbiou": cbiou,
}
"""Every peer by the name `occtrack benchmark --trackers` takes."""
