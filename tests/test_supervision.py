"""`occtrack.integrations.supervision`: sv.Detections in, sv.Detections with tracker_id out."""

from __future__ import annotations

import numpy as np
import pytest

sv = pytest.importorskip("supervision", reason='needs pip install "occtrack[supervision]"')

from occtrack import TrackerConfig  # noqa: E402
from occtrack.integrations.supervision import OcctrackTracker  # noqa: E402


def fake_yolo(t: int, drop_first: bool = False) -> sv.Detections:
    """What `sv.Detections.from_ultralytics` gives for two people: float class ids become
    ints, corners in px, a per-detection data column."""
    xyxy = np.array([[100.0 + 5 * t, 200.0, 160.0 + 5 * t, 380.0],
                     [700.0, 210.0, 764.0, 400.0]])
    keep = slice(1, None) if drop_first else slice(None)
    return sv.Detections(xyxy=xyxy[keep], confidence=np.array([0.9, 0.8])[keep],
                         class_id=np.array([0, 0])[keep],
                         data={"class_name": np.array(["person", "person"])[keep]})


def test_every_detection_comes_back_in_order_with_its_tracker_id():
    tracker = OcctrackTracker(frame_rate=30)
    frame = np.zeros((480, 960, 3), np.uint8)
    for t in range(10):
        detections = fake_yolo(t)
        out = tracker.update(detections, frame=frame)
        assert np.array_equal(out.xyxy, detections.xyxy)
        assert detections.tracker_id is None  # the input is not changed
        assert out.data["class_name"].tolist() == ["person", "person"]
    assert out.tracker_id.tolist() == [1, 2]
    assert tracker.tracker.config.image_size == (960.0, 480.0)  # from the first frame
    assert tracker.tracks.detection_index.tolist() == [0, 1]


def test_untracked_detections_get_minus_one_and_empty_frames_work():
    tracker = OcctrackTracker(TrackerConfig(image_size=(960, 480)), occlusion="none")
    out = tracker.update(sv.Detections.empty())
    assert len(out) == 0 and out.tracker_id.tolist() == []
    tracker.update(fake_yolo(0))
    lone = sv.Detections(xyxy=np.array([[400.0, 100.0, 430.0, 190.0]]),
                         confidence=np.array([0.3]), class_id=np.array([0]))
    tracker.update(lone)
    assert tracker.tracker.config.occlusion == "none"


def test_coasting_tracks_are_appended_when_asked():
    tracker = OcctrackTracker(frame_rate=30, include_coasting=True)
    for t in range(12):
        out = tracker.update(fake_yolo(t, drop_first=t >= 10), timestamp=t / 30)
    assert sorted(out.tracker_id.tolist()) == [1, 2]
    assert out.data["coasting"].tolist() == [False, True]
    assert out.data["class_name"].tolist() == ["person", ""]
    assert 145.0 < out.xyxy[1, 0] < 156.0  # carried on from 145 (its velocity relaxing)
    assert out.class_id.tolist() == [0, 0]


def test_classes_are_kept_apart_and_bad_input_refused():
    tracker = OcctrackTracker(frame_rate=30)
    box = np.array([[300.0, 100.0, 360.0, 260.0]] * 2)
    for _ in range(6):
        out = tracker.update(sv.Detections(xyxy=box, confidence=np.array([0.9, 0.9]),
                                           class_id=np.array([0, 2])))
    assert sorted(out.tracker_id.tolist()) == [1, 2]
    assert tracker.tracks.classes.tolist() == [0, 2]
    with pytest.raises(ValueError, match="sv.Detections"):
        tracker.update(box)
    tracker.reset()
    assert tracker.tracker is None
