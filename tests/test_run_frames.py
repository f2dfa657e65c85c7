"""`Tracker.run_frames` is `Tracker.run` a frame at a time (issue 38: `occtrack track` streams
its result through it), and the streamed file is byte for byte what `write_mot` writes from
`run`'s result."""

from __future__ import annotations

import numpy as np

from occtrack.cli import main
from occtrack.io.mot import read_detections, write_mot
from occtrack.tracker import Tracker, TrackerConfig


def _detections(path):
    rng = np.random.default_rng(5)
    rows = []
    for f in range(1, 121):
        for i in range(6):
            if rng.random() < 0.1:  # misses
                continue
            x = 100 + 150 * i + 2 * f + rng.normal(0, 1)
            rows.append(f"{f},-1,{x:.2f},{200 + 30 * i:.2f},40,100,{rng.uniform(0.3, 1):.3f}\n")
        if f % 9 == 0:
            rows.append(f"{f},-1,{rng.uniform(0, 1200):.2f},600,40,100,0.35\n")
    path.write_text("".join(rows))
    return path


def test_run_is_run_frames_gathered(tmp_path):
    det, _ = read_detections(_detections(tmp_path / "det.txt"), (1280, 720))
    config = TrackerConfig(image_size=(1280, 720), fps=30, frame_step=2)
    whole = Tracker(config).run(det, 125)
    reports = list(Tracker(config).run_frames(det, 125))
    assert [r.frame for r in reports] == list(range(1, 126)) and whole.frames == 125
    np.testing.assert_array_equal(whole.frame, np.concatenate(
        [np.full(len(r.tracks), r.frame) for r in reports]))
    for name, column in (("id", "ids"), ("box", "boxes"), ("confidence", "confidence"),
                         ("coasting", "coasting"), ("classes", "classes")):
        np.testing.assert_array_equal(getattr(whole, name), np.concatenate(
            [getattr(r.tracks, column) for r in reports]), err_msg=name)
    np.testing.assert_array_equal(whole.detection_row,
                                  np.concatenate([r.detection_row for r in reports]))
    assert whole.num_tracks > 5


def test_the_streamed_result_is_write_mots_file(tmp_path):
    path = _detections(tmp_path / "det.txt")
    assert main(["track", str(path), "-o", str(tmp_path / "streamed.txt"), "--image-size",
                 "1280x720", "--fps", "30", "--quiet"]) == 0
    det, _ = read_detections(path, (1280, 720))
    result = Tracker(TrackerConfig(image_size=(1280, 720), fps=30)).run(det, det.num_frames)
    write_mot(tmp_path / "whole.txt", result.frame, result.id, result.box, result.confidence)
    streamed = (tmp_path / "streamed.txt").read_bytes()
    assert streamed == (tmp_path / "whole.txt").read_bytes() and streamed.count(b"\n") > 500
