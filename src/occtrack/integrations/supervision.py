"""occtrack in a supervision pipeline: `sv.Detections` in, `sv.Detections` with `tracker_id`
out, like Roboflow `trackers`' `ByteTrackTracker.update` (needs the optional extra:
`pip install "occtrack[supervision]"`).

    import supervision as sv
    from occtrack.integrations.supervision import OcctrackTracker

    tracker = OcctrackTracker(frame_rate=30)
    for frame in sv.get_video_frames_generator("video.mp4"):
        detections = sv.Detections.from_ultralytics(model(frame)[0])
        detections = tracker.update(detections, frame=frame)   # detections.tracker_id

Every detection comes back, in its order, with the id of the track that took it, or -1 when
none did (a track not yet confirmed, or a detection taken for clutter). A detection a track took
gets the track's calibrated confidence (`Tracks.confidence`: the probability that the box is a
real object at that place), the others keep the detector's; the detector's own score stays in
`data["detector_confidence"]` when it was given. Tracks are kept apart
by `class_id`. With `include_coasting=True` the tracks reported without a detection this frame
(coasting, e.g. hidden behind someone) are appended as extra rows with their estimated boxes;
`data["occluded"]` then marks those whose miss is put down to occlusion and
`data["coasting"]` every appended row.
"""

from __future__ import annotations

import dataclasses

import numpy as np

try:
    import supervision as sv
except ImportError as err:  # pragma: no cover - exercised without the extra
    raise ImportError('occtrack.integrations.supervision needs supervision, from the optional '
                      '"supervision" extra: pip install "occtrack[supervision]"') from err

from occtrack.config import TrackerConfig
from occtrack.tracker.tracker import Tracker, Tracks

__all__ = ["OcctrackTracker"]


class OcctrackTracker:
    """occtrack's occlusion-aware PMB tracker behind supervision's tracker interface.

    Args:
        config: tracker settings; default `TrackerConfig()` with `frame_rate`, and the image
            size taken from the first frame given to `update` (else 1920 x 1080).
        frame_rate: frames per second, used when `update` gets no timestamps.
        include_coasting: also return the tracks reported without a detection this frame.
        **settings: any other `TrackerConfig` field, e.g. `occlusion="object-wise"`.
    """

    def __init__(self, config: TrackerConfig | None = None, *, frame_rate: float | None = None,
                 include_coasting: bool = False, **settings) -> None:
        if config is not None and not isinstance(config, TrackerConfig):
            raise ValueError(f"config must be a TrackerConfig, not {type(config).__name__}")
        config = config or TrackerConfig()
        if frame_rate is not None:
            settings["fps"] = frame_rate
        self._size_given = "image_size" in settings
        self.config = config.replace(**settings) if settings else config
        self.include_coasting = include_coasting
        self.tracker: Tracker | None = None
        self.tracks: Tracks | None = None  # occtrack's own output of the last update

    def reset(self) -> None:
        """Forget every track; the next `update` starts again (ids from 1)."""
        self.tracker = None
        self.tracks = None

    def update(self, detections: sv.Detections, frame: np.ndarray | None = None,
               timestamp: float | None = None) -> sv.Detections:
        """Track one frame. `detections.xyxy` are the boxes, `confidence` the scores (1 when
        None) and `class_id` the classes (one class when None); `frame` (H, W, ...) gives the
        image size on the first call; `timestamp` is the frame's time in seconds (default:
        1 / frame_rate after the previous one). Returns a copy of `detections` with
        `tracker_id` set (-1: taken by no reported track), plus the coasting tracks when
        `include_coasting`."""
        if not isinstance(detections, sv.Detections):
            raise ValueError(f"detections must be sv.Detections, not "
                             f"{type(detections).__name__}")
        if self.tracker is None:
            config = self.config
            if frame is not None and not self._size_given:
                shape = np.shape(frame)
                if len(shape) < 2:
                    raise ValueError(f"frame must be an image (H, W[, C]), not shape {shape}")
                config = config.replace(image_size=(float(shape[1]), float(shape[0])))
            self.tracker = Tracker(config)
        tracks = self.tracker.update(detections.xyxy, detections.confidence,
                                     detections.class_id, timestamp, box_format="xyxy")
        self.tracks = tracks
        took = tracks.detection_index >= 0
        tracker_id = np.full(len(detections), -1, dtype=int)
        tracker_id[tracks.detection_index[took]] = tracks.ids[took]
        data = dict(detections.data)
        confidence = detections.confidence
        if confidence is not None:
            data["detector_confidence"] = np.asarray(confidence).copy()
            confidence = np.asarray(confidence, dtype=float).copy()
            confidence[tracks.detection_index[took]] = tracks.confidence[took]
        result = dataclasses.replace(detections, tracker_id=tracker_id, confidence=confidence,
                                     data=data, metadata=dict(detections.metadata))
        if not self.include_coasting:
            return result
        return _with_coasting(result, tracks)


def _filler(values: np.ndarray, k: int) -> np.ndarray:
    """k rows of 'no value' shaped and typed like `values` rows."""
    arr = np.asarray(values)
    fill = {"f": np.nan, "c": np.nan, "i": -1, "u": 0, "b": False, "U": "", "S": b""}.get(
        arr.dtype.kind)
    return np.full((k, *arr.shape[1:]), fill, dtype=arr.dtype if fill is not None else object)


def _with_coasting(result: sv.Detections, tracks: Tracks) -> sv.Detections:
    coast = tracks.coasting
    k = int(coast.sum())
    n = len(result)
    data = dict(result.data)
    data["coasting"] = np.zeros(n, dtype=bool)
    data["occluded"] = np.zeros(n, dtype=bool)
    result = dataclasses.replace(result, data=data)
    if not k:
        return result
    extra_data = {key: _filler(value, k) for key, value in result.data.items()}
    extra_data["coasting"] = np.ones(k, dtype=bool)
    extra_data["occluded"] = tracks.occluded[coast].copy()
    mask = None
    if result.mask is not None:
        mask = np.zeros((k, *np.shape(result.mask)[1:3]), dtype=bool)
    extra = sv.Detections(
        xyxy=tracks.boxes[coast].astype(float),
        mask=mask,
        confidence=None if result.confidence is None else tracks.confidence[coast].copy(),
        class_id=None if result.class_id is None else tracks.classes[coast].copy(),
        tracker_id=tracks.ids[coast].copy(), data=extra_data)
    if n == 0:
        return dataclasses.replace(extra, metadata=dict(result.metadata))
    return sv.Detections.merge([result, extra])
