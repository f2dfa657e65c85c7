"""Property-based tests (hypothesis): readers never crash and never lose a row, written
results read back, detection order does not matter, and the tracker's invariants hold on any
sequence of frames."""

from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from occtrack.errors import OcctrackError  # noqa: E402
from occtrack.io.mot import read_mot, write_mot  # noqa: E402
from occtrack.tracker import Tracker, TrackerConfig  # noqa: E402

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(st.binary(max_size=300))
def test_any_bytes_parse_or_fail_clearly(tmp_path, data):
    path = tmp_path / "any.txt"
    path.write_bytes(data)
    for kind in ("det", "gt", "result"):
        try:
            table = read_mot(path, kind)
        except OcctrackError as err:
            assert str(err).startswith(str(path))
            continue
        lines = [line for line in data.decode("utf-8").splitlines()
                 if line.strip().lstrip("\ufeff")]
        assert len(table) == len(lines)


row = st.tuples(st.integers(1, 500), st.integers(-1, 10_000),
                st.floats(-1e4, 1e4, allow_nan=False), st.floats(-1e4, 1e4, allow_nan=False),
                st.floats(0, 1e4, allow_nan=False), st.floats(0, 1e4, allow_nan=False),
                st.floats(0, 1, allow_nan=False))


@SETTINGS
@given(st.lists(row, max_size=40))
def test_results_read_back_as_written(tmp_path, rows):
    path = tmp_path / "result.txt"
    frame = np.array([r[0] for r in rows], dtype=np.int64)
    ids = np.array([r[1] for r in rows], dtype=np.int64)
    box = np.array([r[2:6] for r in rows], dtype=float).reshape(-1, 4)
    score = np.array([r[6] for r in rows], dtype=float)
    write_mot(path, frame, ids, box, score, overwrite=True)
    table = read_mot(path, "result")
    order = np.lexsort((ids, frame))
    assert table.frame.tolist() == frame[order].tolist()
    assert table.id.tolist() == ids[order].tolist()
    np.testing.assert_allclose(table.box, box[order], atol=0.005 + 1e-9)
    np.testing.assert_allclose(table.score, score[order], atol=5e-5 + 1e-12)


def walkers(seed: int, people: int, frames: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    start = rng.uniform([100, 200], [1700, 800], (people, 2))
    velocity = rng.normal(0, 3, (people, 2))
    size = rng.uniform([30, 90], [60, 180], (people, 2))
    out = []
    for f in range(frames):
        seen = rng.random(people) < 0.9
        boxes = np.concatenate([start + velocity * f, size], axis=1)[seen]
        scores = rng.uniform(0.5, 1.0, len(boxes))
        out.append(np.concatenate([boxes, scores[:, None]], axis=1))
    return out


@settings(max_examples=8, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 8))
def test_detection_order_within_a_frame_changes_no_track(seed, people):
    frames = walkers(seed, people, 25)
    rng = np.random.default_rng(seed + 1)
    shuffled = [f[rng.permutation(len(f))] for f in frames]
    a = Tracker(TrackerConfig()).run(frames)
    b = Tracker(TrackerConfig()).run(shuffled)
    assert a.frame.tolist() == b.frame.tolist() and a.id.tolist() == b.id.tolist()
    np.testing.assert_allclose(a.box, b.box, atol=1e-6)


frame_kind = st.sampled_from(["empty", "crowd", "duplicate", "outside", "tiny", "normal"])


@settings(max_examples=15, deadline=None)
@given(st.lists(st.tuples(frame_kind, st.integers(0, 2**31 - 1)), min_size=1, max_size=30))
def test_tracker_invariants_on_any_frames(steps):
    tracker = Tracker(TrackerConfig(image_size=(640.0, 480.0), fps=15.0))
    for kind, seed in steps:
        rng = np.random.default_rng(seed)
        n = {"empty": 0, "crowd": 60, "duplicate": 6, "outside": 4, "tiny": 5, "normal": 5}[kind]
        boxes = np.concatenate([rng.uniform(0, [600, 400], (n, 2)),
                                rng.uniform(20, 120, (n, 2))], axis=1)
        if kind == "duplicate":
            boxes[3:] = boxes[:3]
        if kind == "outside":
            boxes[:, :2] += 5000.0
        if kind == "tiny":
            boxes[:, 2:] = rng.uniform(0.0, 2.0, (n, 2))
        tracks = tracker.step(boxes, rng.uniform(0, 1, n))
        assert np.isfinite(tracks.boxes).all() and np.isfinite(tracks.velocities).all()
        assert len(np.unique(tracks.ids)) == len(tracks.ids)
        assert ((tracks.existence >= 0) & (tracks.existence <= 1)).all()
        r = tracker.filter.existence()
        assert ((r >= 0) & (r <= 1 + 1e-12)).all()
        taken = tracks.detection_index[tracks.detection_index >= 0]
        assert len(np.unique(taken)) == len(taken) and (taken < n).all()
