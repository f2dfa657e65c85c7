"""The norfair baseline: interpolation between tracked frames, and norfair itself when its own
environment exists already (tests never install it)."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.baselines.norfair_baseline import (
    NorfairConfig,
    find_norfair_python,
    interpolate,
    run_norfair,
    track_norfair,
)
from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable, read_mot
from occtrack.metrics.gospa import iou


def test_interpolate_fills_frames_between_consecutive_tracked_frames_only():
    tracked = np.array([1, 3, 5])
    frame = np.array([1, 3, 5, 1, 5, 3, 5])
    ids = np.array([1, 1, 1, 2, 2, 3, 3])
    box = np.array([[0, 0, 10, 10], [2, 0, 10, 10], [6, 0, 10, 10],
                    [0, 0, 5, 5], [9, 9, 5, 5],
                    [0, 0, 4, 8], [0, 4, 8, 8]], dtype=float)
    f, i, b = interpolate(frame, ids, box, tracked)
    rows = {(int(a), int(c)): tuple(d) for a, c, d in zip(f, i, b, strict=True)}
    assert len(rows) == len(f) == 7 + 3
    assert rows[(2, 1)] == (1, 0, 10, 10)
    assert rows[(4, 1)] == (4, 0, 10, 10)
    assert rows[(4, 3)] == (0, 2, 6, 8)
    assert (2, 2) not in rows and (3, 2) not in rows and (4, 2) not in rows


def test_bad_settings_are_occtrack_errors():
    with pytest.raises(OcctrackError, match="filter"):
        NorfairConfig(filter="unscented")
    with pytest.raises(OcctrackError, match="initialization_delay"):
        NorfairConfig(hit_counter_max=4, initialization_delay=4)


def walkers(n_frames=40) -> MotTable:
    """Two people walking towards each other on separate rows: one detection each a frame."""
    f = np.repeat(np.arange(1, n_frames + 1), 2)
    x = np.where(np.arange(2 * n_frames) % 2 == 0, 100 + 3.0 * f, 900 - 3.0 * f)
    y = np.where(np.arange(2 * n_frames) % 2 == 0, 100.0, 600.0)
    box = np.column_stack([x, y, np.full(2 * n_frames, 60.0), np.full(2 * n_frames, 150.0)])
    n = len(f)
    return MotTable(frame=f, id=-np.ones(n, dtype=np.int64), box=box, score=np.full(n, 0.9),
                    cls=-np.ones(n, dtype=np.int64), visibility=-np.ones(n))


needs_norfair = pytest.mark.skipif(find_norfair_python() is None,
                                   reason="norfair's environment is not set up (first use of "
                                          "the baseline installs it)")


@needs_norfair
def test_norfair_follows_two_walkers_repeatably():
    det = walkers()
    tracks = track_norfair(det, num_frames=40, quiet=True)
    again = track_norfair(det, num_frames=40, quiet=True)
    assert np.array_equal(tracks.frame, again.frame) and np.array_equal(tracks.id, again.id)
    assert np.array_equal(tracks.box, again.box)
    assert len(np.unique(tracks.id)) == 2
    late = tracks.frame >= 10
    assert np.all(np.bincount(tracks.frame[late])[10:] == 2)
    for frame in range(10, 41):
        d, t = det.box[det.frame == frame], tracks.box[tracks.frame == frame]
        assert iou(d, t).max(axis=1).min() > 0.8


@needs_norfair
def test_frame_step_reports_every_frame_and_writes_a_result_file(tmp_path):
    det_file, result = tmp_path / "det.txt", tmp_path / "result.txt"
    det = walkers()
    with open(det_file, "w") as fh:
        for k in range(len(det)):
            l, t, w, h = det.box[k]
            fh.write(f"{det.frame[k]},-1,{l},{t},{w},{h},{det.score[k]}\n")
    tracks = run_norfair(det_file, result, frame_step=2, quiet=True)
    first = tracks.frame.min()
    assert np.array_equal(np.unique(tracks.frame), np.arange(first, 41))
    assert len(read_mot(result, "result")) == len(tracks)
    with pytest.raises(OcctrackError, match="exists already"):
        run_norfair(det_file, result, quiet=True)
