"""Issue 38, kind 1: numeric extremes are refused at the boundary with the value named, and
the filter is safe for whatever passes: frame rates a camera can have, boxes an image can hold,
gaps between frames a prediction can bridge (a longer one ends every track, with a warning)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occtrack.cli import main
from occtrack.config import MAX_FPS, MIN_FPS, TrackerConfig
from occtrack.tracker import Tracker


@pytest.mark.parametrize("fps", [1e-300, 1e-3, 1e5, 1e300])
def test_frame_rates_no_camera_has_are_refused_by_name(fps, tmp_path, capsys):
    with pytest.raises(ValueError, match=f"^fps must be between {MIN_FPS:g} and {MAX_FPS:g}"):
        TrackerConfig(fps=fps)
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,50,0.9\n")
    for command in ("track", "calibrate"):  # a bad option value: a usage error, as --fps 0 is
        files = [str(det)] if command == "track" else [str(det), str(det)]
        with pytest.raises(SystemExit) as stop:
            main([command, *files, "-o", str(tmp_path / "r.txt"), "--image-size", "640x480",
                  "--fps", repr(fps), "--quiet"])
        assert stop.value.code == 2
        assert (f"occtrack {command}: error: argument --fps: {fps!r} must be between "
                f"{MIN_FPS:g} and {MAX_FPS:g} frames a second") in capsys.readouterr().err
    assert not (tmp_path / "r.txt").exists()


@pytest.mark.parametrize("size", ["200000x480", "640x100001"])
def test_image_sizes_no_camera_has_are_a_bad_option_value(size, tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,50,0.9\n")
    with pytest.raises(SystemExit) as stop:
        main(["track", str(det), "-o", str(tmp_path / "r.txt"), "--image-size", size])
    assert stop.value.code == 2
    assert f"argument --image-size: {size}: an image side is at most 100000 px" in (
        capsys.readouterr().err)


@given(st.floats(MIN_FPS, MAX_FPS))
def test_every_frame_rate_in_range_is_taken(fps):
    assert TrackerConfig(fps=fps).fps == fps


def test_images_larger_than_any_are_refused():
    with pytest.raises(ValueError, match="image width must be at most 100000 px"):
        TrackerConfig(image_size=(1e308, 480))


@pytest.mark.parametrize("box", [[1e308, 10, 20, 50], [10, 10, 2e6, 50], [-1e7, 10, 20, 50]])
def test_a_box_beyond_any_image_is_named(box, tmp_path):
    tracker = Tracker(TrackerConfig(image_size=(640, 480), fps=30))
    with pytest.raises(ValueError, match=r"^box 1 .* has a coordinate beyond 1e\+06 px"):
        tracker.step(np.array([[10.0, 10, 20, 50], box]))
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,50,0.9\n1,-1," + ",".join(f"{v:g}" for v in box) + ",0.9\n")
    out = tmp_path / "r.txt"
    assert main(["track", str(det), "-o", str(out), "--image-size", "640x480", "--fps", "30",
                 "--quiet"]) == 1
    assert main(["track", str(det), "-o", str(out), "--image-size", "640x480", "--fps", "30",
                 "--quiet", "--lenient"]) == 0


def test_frames_closer_than_a_microsecond_are_refused():
    tracker = Tracker(TrackerConfig(image_size=(640, 480), fps=30))
    box = np.array([[10.0, 10, 40, 70]])
    tracker.update(box, timestamp=1.0)
    with pytest.raises(ValueError, match="dt must be at least 1e-06 s"):
        tracker.update(box, timestamp=1.0 + 1e-7)
    with pytest.raises(ValueError, match="timestamps must increase"):
        tracker.update(box, timestamp=1.0 + 1e-200)  # (1.0 itself in floating point)
    with pytest.raises(ValueError, match="dt must be at least 1e-06 s"):
        tracker.step(box, dt=1e-200)


def test_a_gap_of_1e160_seconds_is_a_restart_not_an_overflow():
    tracker = Tracker(TrackerConfig(image_size=(640, 480), fps=30))
    box = np.array([[100.0, 100, 140, 200]])
    for t in range(10):
        tracker.update(box, timestamp=t / 30)
    with pytest.warns(UserWarning, match="more than max_gap"):
        tracks = tracker.step(box, dt=1e160)
    assert len(tracks) == 0  # a newborn is not reported on its first frame
    assert tracker.step(box).ids.tolist() in ([], [2])


@pytest.mark.parametrize("gap", [1e6, 1e5])
def test_a_gap_beyond_max_gap_ends_every_track_with_a_warning(gap):
    """One object detected every frame, then a gap longer than max_gap (600 s): a warning,
    and the object is one new id afterwards (never an old one's), reported from its second
    frame on as any new object, with no crash and no box unrelated to it."""
    tracker = Tracker(TrackerConfig(image_size=(640, 480), fps=30))
    box = np.array([[100.0, 100, 140, 200]])  # x1 y1 x2 y2, update's default
    before = set()
    for t in range(30):
        before |= set(tracker.update(box, timestamp=t / 30).ids.tolist())
    assert len(before) == 1
    after = set()
    with pytest.warns(UserWarning, match="more than max_gap"):
        tracks = tracker.update(box, timestamp=1.0 + gap)
    after |= set(tracks.ids.tolist())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for t in range(1, 60):
            tracks = tracker.update(box, timestamp=1.0 + gap + t / 30)
            after |= set(tracks.ids.tolist())
            assert len(tracks) <= 1
            if len(tracks):
                np.testing.assert_allclose(tracks.boxes[0], [100, 100, 140, 200])
    assert len(after) == 1 and not after & before


def test_a_gap_under_max_gap_keeps_the_track():
    tracker = Tracker(TrackerConfig(image_size=(640, 480), fps=30))
    box = np.array([[100.0, 100, 140, 200]])
    for t in range(30):
        ids = tracker.update(box, timestamp=t / 30).ids
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        later = tracker.update(box, timestamp=1.0 + 0.5).ids
    assert ids.tolist() == later.tolist() == [1]


def test_a_gap_of_1e7_seconds_between_scans_is_a_restart(tmp_path, capsys):
    """The scan tracker ends every track after a gap beyond max_gap, as the box tracker does,
    where a 1e7 s prediction made the scan likelihood's matrix singular; ids go on."""
    scene = tmp_path / "scene"
    assert main(["simulate", "lidar", "-o", str(scene), "--scans", "40", "--quiet"]) == 0
    rows = (scene / "scans.csv").read_text().splitlines(keepends=True)
    shifted = []
    for row in rows:
        if row[0].isdigit():
            t, rest = row.split(",", 1)
            row = f"{float(t) + (1e7 if float(t) >= 2.0 else 0.0)!r},{rest}"
        shifted.append(row)
    (scene / "gap.csv").write_text("".join(shifted))
    capsys.readouterr()
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(scene / "gap.csv"), "-o", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err == ("occtrack track-scans: warning: 1e+07 s since the previous scan, more than "
                   "max_gap (600 s): every track ends and tracking starts afresh\n")
    table = np.genfromtxt(out, delimiter=",", names=True)
    before, after = table["id"][table["time"] < 2.0], table["id"][table["time"] >= 2.0]
    assert len(before) and len(after) and after.min() > before.max()
