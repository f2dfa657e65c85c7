"""The public API a detector pipeline calls: `from occtrack import Tracker, TrackerConfig`,
`Tracker.update` in every box format, timestamps, classes, the detection each track took,
occlusion flags, and clear errors for bad input."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest

import occtrack
from occtrack import Tracker, TrackerConfig, Tracks
from occtrack.io.mot import MotTable
from occtrack.tracker.boxes import check_classes, check_time, checked_frame, from_ltwh, to_ltwh


def walkers(frames: int = 40, speed: float = 150.0, fps: float = 30.0) -> list[np.ndarray]:
    """Two people 300 px apart walking right at `speed` px / s, ltwh."""
    return [np.array([[300.0 + speed * k / fps, 400.0, 40.0, 120.0],
                      [900.0 + speed * k / fps, 380.0, 44.0, 130.0]]) for k in range(frames)]


def test_import_occtrack_is_light_and_exports_the_api():
    code = ("import sys, occtrack; heavy = [m for m in ('numpy', 'scipy', 'occtrack.tracker') "
            "if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
    assert {"Tracker", "TrackerConfig", "Tracks"} <= set(dir(occtrack))
    assert occtrack.Tracker is Tracker and isinstance(occtrack.__version__, str)
    with pytest.raises(AttributeError):
        occtrack.NoSuchThing  # noqa: B018


def test_py_typed_ships_with_the_package():
    from importlib.resources import files

    assert files("occtrack").joinpath("py.typed").is_file()


@pytest.mark.parametrize("box_format", ["xyxy", "ltwh", "cxcywh"])
def test_update_in_any_box_format_matches_step(box_format):
    """update in any format tracks exactly as step does in ltwh, returns boxes in the format
    it was given, and a detected track's box is the caller's own box, bit for bit."""
    config = TrackerConfig(image_size=(1280, 720), fps=30)
    by_step, by_update = Tracker(config), Tracker(config)
    for k, ltwh in enumerate(walkers()):
        boxes = from_ltwh(ltwh, box_format)
        a = by_step.step(ltwh, np.full(2, 0.9))
        b = by_update.update(boxes, np.full(2, 0.9), timestamp=10.0 + k / 30,
                             box_format=box_format)
        assert isinstance(b, Tracks) and b.box_format == box_format
        assert np.array_equal(a.ids, b.ids)
        assert np.array_equal(a.detection_index, b.detection_index)
        assert np.allclose(to_ltwh(b.boxes, box_format), a.boxes, atol=1e-9)
        took = b.detection_index >= 0
        assert np.array_equal(b.boxes[took], boxes[b.detection_index[took]])
    assert b.ids.tolist() == [1, 2] and (b.detection_index == [0, 1]).all()
    assert b.classes.tolist() == [0, 0] and not b.occluded.any()


def test_timestamps_give_the_true_time_step_over_dropped_frames():
    """Frames arrive at 30 fps with two of every three dropped after the first ten: with
    timestamps the velocity stays 150 px/s; without them each call is taken as 1/30 s and the
    tracker believes the walkers triple their speed."""
    config = TrackerConfig(image_size=(1280, 720), fps=30)
    kept = list(range(10)) + list(range(10, 60, 3))
    frames = walkers(60)
    timed, untimed = Tracker(config), Tracker(config)
    for k in kept:
        a = timed.update(frames[k], box_format="ltwh", timestamp=k / 30)
        b = untimed.update(frames[k], box_format="ltwh")
    assert a.ids.tolist() == [1, 2] and (a.detection_index >= 0).all()
    assert a.velocities[:, 0] == pytest.approx([150.0, 150.0], rel=0.1)
    assert (b.velocities[:, 0] > 300.0).all()
    assert timed.filter.dt == pytest.approx(3 / 30)


def test_the_filter_builds_its_motion_for_each_time_step():
    tracker = Tracker(TrackerConfig(fps=30))
    tracker.update([[10, 10, 50, 130]], timestamp=0.0)
    tracker.update([[12, 10, 52, 130]], timestamp=0.25)
    f = tracker.filter
    assert f.motion.dt == 0.25 and f.coast_motion.dt == 0.25
    assert f.survival_inside == pytest.approx(np.exp(-tracker.config.death_rate * 0.25))
    tracker.update([[14, 10, 54, 130]])  # no timestamp: 1 / fps after the last
    assert f.dt == pytest.approx(1 / 30) and tracker._timestamp == pytest.approx(0.25 + 1 / 30)
    with pytest.raises(ValueError, match="increase"):
        tracker.update([[14, 10, 54, 130]], timestamp=0.2)


def test_a_class_never_switches_and_classes_are_kept_apart():
    """A person (class 0) and a bicycle (class 1) occupy the same box; a car (class 2) later
    takes the person's place. Each track keeps the class it was born with and only ever takes
    detections of that class."""
    tracker = Tracker(TrackerConfig(image_size=(1280, 720), fps=30))
    box = [500.0, 300.0, 60.0, 160.0]
    seen: dict[int, set[int]] = {}
    for k in range(40):
        classes = [0, 1] if k < 20 else [2, 1]
        boxes = np.array([box, box]) + [[2.0 * k, 0, 0, 0]]
        tracks = tracker.update(boxes, [0.9, 0.8], classes, box_format="ltwh")
        for i, c, j in zip(tracks.ids, tracks.classes, tracks.detection_index, strict=True):
            seen.setdefault(int(i), set()).add(int(c))
            if j >= 0:
                assert classes[j] == c
    assert all(len(c) == 1 for c in seen.values())
    assert {c for cs in seen.values() for c in cs} == {0, 1, 2}
    assert sorted(tracks.classes.tolist()) == [1, 2]


@pytest.mark.parametrize("occlusion", ["measurement-wise", "object-wise", "none"])
def test_a_walker_hidden_behind_another_is_reported_occluded(occlusion):
    """A person passes behind one standing nearer the camera and is not detected there: the
    track coasts, flagged occluded by the occlusion models and never without occlusion."""
    tracker = Tracker(TrackerConfig(occlusion=occlusion, image_size=(1280, 720), fps=30))
    front = [600.0, 300.0, 60.0, 180.0]
    flags = []
    for k in range(45):
        x = 400.0 + 5 * k
        hidden = abs(x + 28 - 630) < 40
        boxes = [front] if hidden else [front, [x, 290.0, 56.0, 170.0]]
        tracks = tracker.update(boxes, [0.9] * len(boxes), box_format="ltwh", timestamp=k / 30)
        assert not tracks.occluded[tracks.detection_index >= 0].any()
        if hidden:
            flags.extend(tracks.occluded[tracks.coasting].tolist())
    assert len(flags) >= 5
    if occlusion == "none":
        assert not any(flags)
    else:
        assert sum(flags) >= 5


def test_update_rejects_bad_input_with_clear_messages():
    tracker = Tracker()
    cases = [
        (dict(boxes="det.txt"), "string"),
        (dict(boxes=[["a", "b", "c", "d"]]), "numbers"),
        (dict(boxes=np.zeros((3, 5))), r"shape \(M, 4\)"),
        (dict(boxes=[[1, 2, np.nan, 4]]), "NaN"),
        (dict(boxes=[[10, 10, 5, 20]]), "x2 < x1"),
        (dict(boxes=[[10, 10, 10, 30], [10, 10, 5, 20]]),  # the first box only zero wide
         r"^box 1 \[10\.0, 10\.0, 5\.0, 20\.0\] has x2 < x1"),
        (dict(boxes=[[10, 10, 5, 20]], box_format="xywh"), "box_format"),
        (dict(boxes=[[10, 10, 20, 20]], scores=[0.5, 0.6]), "scores"),
        (dict(boxes=[[10, 10, 20, 20]], classes=[0.5]), "whole numbers"),
        (dict(boxes=[[10, 10, 20, 20]], classes=[[1]]), "classes"),
        (dict(boxes=[[10, 10, 20, 20]], timestamp="now"), "timestamp"),
        (dict(boxes=[[10, 10, 20, 20]], timestamp=float("nan")), "finite"),
        (dict(boxes=[[10, 10, 20, 20]], timestamp=True), "timestamp"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError, match=message):
            tracker.update(**kwargs)
    with pytest.raises(ValueError, match=r"boxes must have shape \(M, 4\) .* not \(1,\)$"):
        tracker.update([5.0])
    assert tracker.filter.steps == 0  # nothing was tracked by a refused call
    assert len(tracker.update(np.zeros((0, 4)))) == 0 and len(tracker.update([])) == 0
    with pytest.raises(ValueError, match="TrackerConfig"):
        Tracker({"fps": 30})


def test_the_fast_check_of_a_frame_agrees_with_the_full_one_or_defers_to_it():
    """Float64 arrays of finite boxes and scores take the fast path: the same copy the full
    checks give, sizes below 1 px raised to 1, the caller's array untouched; anything else
    (NaN, a negative size, lists, float32, a shape mismatch) gives None, so that the full
    checks run and name the problem."""
    rng = np.random.default_rng(0)
    boxes = np.column_stack([rng.uniform(0, 600, (20, 2)), rng.uniform(0, 3, (20, 2))])
    boxes[0, 2:] = [0.0, -0.0]
    scores = rng.random(20)
    given = boxes.copy()
    full = to_ltwh(boxes, "ltwh")
    full[:, 2:] = np.maximum(full[:, 2:], 1.0)
    fast = checked_frame(boxes, scores)
    assert fast is not boxes and np.array_equal(fast, full) and np.array_equal(boxes, given)
    assert checked_frame(np.zeros((0, 4)), np.zeros(0)).shape == (0, 4)
    for bad_boxes, bad_scores in ((np.where(boxes == boxes[3, 1], np.nan, boxes), scores),
                                  (boxes, np.where(scores == scores[5], np.inf, scores)),
                                  (boxes * [1, 1, 1, -1], scores), (boxes.tolist(), scores),
                                  (boxes.astype(np.float32), scores), (boxes, scores[:-1])):
        assert checked_frame(bad_boxes, bad_scores) is None
    with pytest.raises(ValueError, match="negative width or height"):
        Tracker(TrackerConfig(image_size=(640, 480), fps=30)).step(boxes * [1, 1, 1, -1], scores)
    # both paths track alike, tiny boxes included: a list (the full checks) and the array
    people = np.column_stack([rng.uniform(0, 600, (10, 2)), np.tile([40.0, 100.0], (10, 1))])
    frame, conf = np.r_[boxes, people], np.r_[scores, np.full(10, 0.9)]
    by_list, by_array = Tracker(), Tracker()
    for t in range(6):
        moved = frame + [3.0 * t, 0.0, 0.0, 0.0]
        a, b = by_list.step(moved.tolist(), conf.tolist()), by_array.step(moved, conf)
        assert a.ids.tolist() == b.ids.tolist() and np.array_equal(a.boxes, b.boxes)
        n = by_array.filter.n
        assert by_list.filter.n == n
        assert np.array_equal(by_list.filter.mean[:n], by_array.filter.mean[:n])
        assert np.array_equal(by_list.filter.mass[:n], by_array.filter.mass[:n])
    assert len(b) >= 8


def test_run_refuses_a_file_name_instead_of_iterating_its_characters(tmp_path):
    tracker = Tracker()
    for name in ("det.txt", tmp_path / "det.txt", b"det.txt"):
        with pytest.raises(ValueError, match="file name"):
            tracker.run(name)
    with pytest.raises(ValueError, match="MotTable"):
        tracker.run(42)
    with pytest.raises(ValueError, match=r"^frame 2: detections must be an array of numbers "
                                         r"\(M, 4\) or \(M, 5\), not the string '1,2,3,4'$"):
        tracker.run([np.zeros((0, 4)), "1,2,3,4"])
    with pytest.raises(ValueError, match=r"not the string '(x){40}'$"):  # its start only
        tracker.run(["x" * 60])
    with pytest.raises(ValueError, match=r"^frame 1: detections must be \(M, 4\) or \(M, 5\),"
                                         r" not \(2, 3\)$"):
        tracker.run([np.zeros((2, 3))])


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_run_shows_its_progress_with_the_frame_count_on_a_terminal_when_asked(monkeypatch):
    """The bar counts frames out of the total: a list's length, a MotTable's frames (not its
    rows), num_frames when given; a stream of unknown length is only counted. Quiet by
    default (a library call), and never a bar off a terminal."""
    frames = [np.array([[300.0 + 5 * k, 400.0, 40.0, 120.0]] * 2) for k in range(4)]
    table = MotTable(np.repeat(np.arange(1, 5), 2), np.full(8, -1), np.concatenate(frames),
                     np.ones(8), np.full(8, -1), np.full(8, -1.0))

    def shown(detections, **kwargs) -> str:
        stderr = Terminal()
        monkeypatch.setattr("sys.stderr", stderr)
        Tracker().run(detections, **kwargs)
        return stderr.getvalue()

    assert shown(frames) == ""
    assert "tracking:" in shown(frames, quiet=False) and "0/4" in shown(frames, quiet=False)
    assert "0/4" in shown(table, quiet=False) and "/8" not in shown(table, quiet=False)
    assert "0/3" in shown(table, num_frames=3, quiet=False)
    stream = shown(iter(frames), quiet=False, desc="scoring")
    assert "scoring: 0it" in stream and "tracking" not in stream and "0/" not in stream
    monkeypatch.setattr("sys.stderr", io.StringIO())
    Tracker().run(frames, quiet=False)
    assert sys.stderr.getvalue() == ""


def test_run_reports_coasting_and_occluded_rows():
    frames = [np.array([[300.0 + 5 * k, 400.0, 40.0, 120.0]]) if k < 20 or k > 24
              else np.zeros((0, 4)) for k in range(30)]
    result = Tracker(TrackerConfig(fps=30)).run(frames)
    assert len(result.coasting) == len(result.frame) == len(result.occluded)
    gap = (result.frame >= 21) & (result.frame <= 25)
    assert result.coasting[gap].all() and not result.coasting[result.frame < 21].any()


def test_run_takes_the_scores_of_five_column_frames():
    """(M, 5) frames carry scores to `step`: `run` gives the rows a loop of `step` with those
    scores gives, and a low score changes them (a weak box is more likely clutter)."""
    frames = [np.array([[300.0 + 5 * k, 400.0, 40.0, 120.0, 0.9],
                        [900.0, 300.0 + 2 * k, 40.0, 110.0, 0.1]]) for k in range(12)]
    result = Tracker().run(frames)
    looped, existence = Tracker(), []
    for frame in frames:
        existence.extend(looped.step(frame[:, :4], frame[:, 4]).existence)
    np.testing.assert_array_equal(result.existence, existence)
    sure = Tracker().run([frame[:, :4] for frame in frames])
    assert not np.array_equal(sure.existence, result.existence)
    assert result.frames == 12 and result.seconds_tracking > 0


@pytest.mark.parametrize("frames", [[], [np.zeros((0, 4))] * 3])
def test_run_of_nothing_gives_typed_empty_columns(frames):
    """No frame, or frames with no detection: every column empty with the dtype and width of a
    full result, the frame count and a tracking time."""
    result = Tracker().run(frames)
    assert result.frames == len(frames) and 0.0 <= result.seconds_tracking < 60.0
    for column, dtype, shape in ((result.frame, np.int64, (0,)), (result.id, np.int64, (0,)),
                                 (result.box, np.float64, (0, 4)),
                                 (result.existence, np.float64, (0,)),
                                 (result.coasting, np.bool_, (0,)),
                                 (result.occluded, np.bool_, (0,))):
        assert column.dtype == dtype and column.shape == shape


def test_run_stops_at_num_frames():
    frames = [np.array([[300.0 + 5 * k, 400.0, 40.0, 120.0]]) for k in range(10)]
    result = Tracker().run(frames, num_frames=6)
    assert result.frames == 6 and result.frame.max() == 6
    assert Tracker().run(iter(frames), num_frames=6).frame.tolist() == result.frame.tolist()


def test_boxes_thinner_than_a_pixel_are_taken_as_one_pixel_wide():
    """Zero and sub-pixel sizes are not negative: both check paths (a list, an array) accept
    them, in ltwh and in xyxy, and track them alike (raised to 1 px: the fast check's test)."""
    boxes = [[100.0, 100.0, 0.0, 80.0], [300.0, 100.0, 0.5, 0.0], [500.0, 100.0, 40.0, 90.0]]
    np.testing.assert_array_equal(to_ltwh(boxes, "ltwh"), boxes)
    corners = [[100.0, 100.0, 100.0, 180.0], [300.0, 100.0, 300.5, 100.0]]
    np.testing.assert_array_equal(to_ltwh(corners, "xyxy"), boxes[:2])
    # every object tracked is reported (a box a pixel wide overlaps its person unsurely)
    by_list, by_array = (Tracker(TrackerConfig(report_min_confidence=0.0)) for _ in range(2))
    for _ in range(3):
        a, b = by_list.step(boxes, [0.9] * 3), by_array.step(np.array(boxes), np.full(3, 0.9))
        assert a.ids.tolist() == b.ids.tolist() and np.array_equal(a.boxes, b.boxes)
    n = by_list.filter.n
    np.testing.assert_array_equal(by_list.filter.mean[:n], by_array.filter.mean[:n])
    assert len(a) == 3


def test_classes_and_times_at_the_boundary():
    """Whole-number floats (YOLO's classes) become int64 ids, up to 2**62 in size (beyond it a
    float is no longer a safe id); times come as any real scalar, a 0-d array included."""
    assert check_classes([0.0, 200.0, -3.0], 3).tolist() == [0, 200, -3]
    assert check_classes([0.0, 200.0, -3.0], 3).dtype == np.int64
    assert check_classes([2.0**62 - 2.0**10], 1).tolist() == [2**62 - 2**10]
    for big in (2.0**62, -(2.0**62), 2.0**63):
        with pytest.raises(ValueError, match="whole numbers"):
            check_classes([big], 1)
    # an integer array is taken as it is (as floats, ids past 2**53 would round)
    ids = np.array([2**53 + 1, -7, 3], dtype=np.int64)
    assert check_classes(ids, 3).tolist() == [2**53 + 1, -7, 3]
    assert check_classes(np.array([5], dtype=np.uint8), 1).dtype == np.int64
    with pytest.raises(ValueError, match="whole numbers"):
        check_classes(np.array([2**62], dtype=np.int64), 1)
    with pytest.raises(ValueError, match="one per box"):
        check_classes(np.zeros(2, dtype=np.int64), 3)
    assert check_time(np.array(0.25), "dt") == 0.25 and check_time(np.float32(0.5), "dt") == 0.5
    with pytest.raises(ValueError, match="dt must be a number of seconds"):
        check_time(np.array([0.25, 0.5]), "dt")


def test_from_ltwh_gives_floats_in_every_format():
    for box_format, expected in (("xyxy", [1.0, 2.0, 4.0, 6.0]), ("ltwh", [1.0, 2.0, 3.0, 4.0]),
                                 ("cxcywh", [2.5, 4.0, 3.0, 4.0])):
        out = from_ltwh([[1, 2, 3, 4]], box_format)
        assert out.dtype == np.float64 and out.tolist() == [expected]


def test_tracks_in_another_format_keep_every_other_field():
    """`step`'s own tracks (ltwh; `update` converts with in_format itself) in another format:
    only the boxes change."""
    tracker = Tracker()
    for k in range(3):
        tracks = tracker.step(np.array([[100.0 + 6 * k, 100.0, 40.0, 120.0]]), np.array([0.9]))
    other = tracks.in_format("cxcywh")
    assert other.box_format == "cxcywh" and other.boxes.tolist() == [[132.0, 160.0, 40.0, 120.0]]
    assert tracks.velocities.shape == (1, 2) and tracks.velocities[0, 0] > 0
    for name in ("ids", "existence", "velocities", "detection_index", "classes", "occluded"):
        np.testing.assert_array_equal(getattr(other, name), getattr(tracks, name))
    assert tracks.in_format("ltwh") is tracks


def test_reset_starts_over():
    tracker = Tracker()
    for k in range(5):
        tracks = tracker.update([[100 + k, 100, 140 + k, 220]], timestamp=k / 30)
    assert tracks.ids.tolist() == [1]
    tracker.reset()
    assert tracker.filter.steps == 0
    tracker.update([[900, 100, 940, 220]], timestamp=0.0)  # time may start again
    tracks = tracker.update([[901, 100, 941, 220]], timestamp=1 / 30)  # (a first sight says .49)
    assert tracks.ids.tolist() == [1] and tracks.boxes.tolist() == [[901, 100, 941, 220]]


def _people(shift=(0.0, 0.0), zoom=1.0):
    """Three people standing still (left, top, width, height), as a camera that moved by
    `shift` (and zoomed by `zoom`) sees them."""
    boxes = np.array([[100.0, 400.0, 40.0, 100.0], [700.0, 420.0, 44.0, 110.0],
                      [1300.0, 380.0, 38.0, 96.0]])
    return np.c_[boxes[:, :2] * zoom + shift, boxes[:, 2:] * zoom]


@pytest.mark.parametrize("how", ["given", "estimated", "none"])
def test_camera_motion_given_estimated_or_none(how):
    """People standing still while the camera pans by 60 px in one frame: with the pan given
    (a 2 x 3 affine) or estimated from the detections each track takes its person's shifted
    box and stays at rest; with `camera_motion = "none"` and nothing given, the jump is too
    far for a person standing still and the tracks coast where they were (under the Gaussian
    edge likelihood: the heavy tail, tests/test_edge_tail.py, reaches .6 box heights)."""
    config = TrackerConfig(camera_motion="none" if how != "estimated" else "detections",
                           tail_weight=0.0 if how == "none" else TrackerConfig.tail_weight)
    tracker = Tracker(config)
    for _ in range(8):
        tracker.step(_people())
    motion = [[1.0, 0.0, 60.0], [0.0, 1.0, -20.0]] if how == "given" else None
    tracks = tracker.step(_people((60.0, -20.0)), camera_motion=motion)
    assert len(tracks) == 3 and tracks.ids.tolist() == [1, 2, 3]
    if how == "none":
        assert tracks.detection_index.tolist() == [-1, -1, -1]
        np.testing.assert_allclose(tracks.boxes, _people(), atol=2.0)
    else:
        assert tracks.detection_index.tolist() == [0, 1, 2]
        np.testing.assert_array_equal(tracks.boxes, _people((60.0, -20.0)))
        assert np.abs(tracks.velocities).max() < 1.0  # px / s


def test_a_given_zoom_scales_the_states():
    """The affine's diagonal scales the states: after a 2x zoom (about the origin) the
    people's boxes are twice as large and still at rest."""
    tracker = Tracker(TrackerConfig(camera_motion="none"))
    for _ in range(8):
        tracker.step(_people())
    tracks = tracker.step(_people(zoom=2.0), camera_motion=[[2.0, 0, 0], [0, 2.0, 0]])
    assert np.abs(tracks.velocities).max() < 5.0  # px / s
    zoomed = _people(zoom=2.0)
    # (the third now lies past the image's right border, x > 1920, where the detector placed
    # it: those edges are measured, `extrapolated_edges`, and the box reported as detected)
    np.testing.assert_allclose(tracks.boxes, zoomed)


def test_a_box_cut_by_the_image_border_is_reported_with_the_states_outer_edge():
    """A person walking out at the right border: the detector clips the box at x = 1920, the
    filter leaves that edge unmeasured, and the reported box takes the state's right edge past
    the border (the true box runs on, as MOTChallenge's ground truth does) with the
    detection's other three edges; a person inside the image is reported as detected."""
    tracker = Tracker(TrackerConfig(camera_motion="none"))
    inside = np.array([600.0, 400.0, 80.0, 200.0])
    for t in range(34):  # the last one 22 px inside the image
        left = 1700.0 + 6.0 * t
        walker = np.array([left, 420.0, min(80.0, 1920.0 - left), 200.0])
        tracks = tracker.step(np.stack([inside, walker]))
    assert tracks.detection_index.tolist() == [0, 1]
    np.testing.assert_array_equal(tracks.boxes[0], inside)
    left = 1700.0 + 6.0 * 33
    np.testing.assert_array_equal(tracks.boxes[1, [0, 1, 3]], [left, 420.0, 200.0])
    right = left + tracks.boxes[1, 2]  # the walker's true right edge: left + 80 = 1978
    assert 1960.0 < right < 2000.0


def test_update_reports_the_cut_box_as_step_does():
    """`update` hands back the caller's own box where the detection is the box, and the
    state's outer edge where the border cuts it, as `step` does."""
    by_step, by_update = (Tracker(TrackerConfig(camera_motion="none")) for _ in range(2))
    inside = np.array([600.0, 400.0, 80.0, 200.0])
    for t in range(34):
        left = 1700.0 + 6.0 * t
        walker = np.array([left, 420.0, min(80.0, 1920.0 - left), 200.0])
        ltwh = np.stack([inside, walker])
        a = by_step.step(ltwh)
        b = by_update.update(from_ltwh(ltwh, "xyxy"))
    np.testing.assert_allclose(to_ltwh(b.boxes, "xyxy"), a.boxes, atol=1e-9)
    assert a.boxes[1, 0] + a.boxes[1, 2] > 1960.0
    np.testing.assert_array_equal(b.boxes[0], from_ltwh(inside[None], "xyxy")[0])


@pytest.mark.parametrize("motion", [np.eye(2), np.zeros((2, 4)), [[1, 0, np.nan], [0, 1, 0]]])
def test_camera_motion_must_be_a_finite_2_by_3_matrix(motion):
    with pytest.raises(ValueError, match="camera_motion must be a finite 2 x 3 affine matrix"):
        Tracker().step(_people(), camera_motion=motion)


@pytest.mark.parametrize("words", ["shift", [["a", "b", "c"], ["d", "e", "f"]]])
def test_camera_motion_that_is_not_numbers_is_named(words):
    with pytest.raises(ValueError, match=r"^camera_motion must be an array of numbers \(a 2 x 3 "
                                         r"affine matrix\), not "):
        Tracker().step(_people(), camera_motion=words)


def test_the_occlusion_settings_reach_the_occlusion_model():
    config = TrackerConfig(occlusion="object-wise", occlusion_gain=3.0,
                           occlusion_ramp=(-0.2, 0.5), occluder_min_existence=0.3)
    model = Tracker(config).filter.occlusion
    assert (model.geometry.gain, model.geometry.ramp_zero, model.geometry.ramp_one) == (
        3.0, -0.2, 0.5)
    assert model.min_existence == 0.3


@pytest.mark.parametrize("box_format", ["xyxy", "ltwh", "cxcywh"])
def test_moved_tracks_carry_every_corner_along_the_velocity(box_format):
    """`Tracks.moved`: corners (xyxy) or the left-top point / centre move by v t, sizes stay;
    nothing is taken from a detection; the rest is kept."""
    boxes = np.array([[10.0, 20.0, 50.0, 120.0], [300.0, 40.0, 340.0, 150.0]])
    tracks = Tracks(np.array([4, 9]), boxes, np.array([0.9, 0.8]),
                    np.array([[30.0, -10.0], [0.0, 6.0]]), np.array([0, -1]),
                    np.array([0, 2]), np.array([False, True]), np.array([0.85, 0.5]),
                    box_format)
    moved = tracks.moved(0.5)
    step = np.array([[15.0, -5.0], [0.0, 3.0]])
    expected = boxes + np.c_[step, step if box_format == "xyxy" else np.zeros((2, 2))]
    np.testing.assert_array_equal(moved.boxes, expected)
    assert moved.detection_index.tolist() == [-1, -1] and moved.detection_index.dtype == np.int64
    assert moved.ids.tolist() == [4, 9] and moved.classes.tolist() == [0, 2]
    assert moved.occluded.tolist() == [False, True] and moved.box_format == box_format
    np.testing.assert_array_equal(moved.velocities, tracks.velocities)
    np.testing.assert_array_equal(moved.existence, tracks.existence)
    np.testing.assert_array_equal(moved.confidence, tracks.confidence)


def test_update_returns_the_callers_own_boxes_for_detected_tracks():
    """A track that took a detection returns that detection's row as given, not its round
    trip through left, top, width, height (which moves a centre by a rounding)."""
    boxes = np.array([[81.7, 400.7, 33.7, 103.9], [300.1, 500.3, 45.7, 110.3]])
    assert not np.array_equal(from_ltwh(to_ltwh(boxes, "cxcywh"), "cxcywh"), boxes)
    tracker = Tracker()
    for _ in range(4):
        tracks = tracker.update(boxes, box_format="cxcywh")
    assert sorted(tracks.detection_index.tolist()) == [0, 1]
    np.testing.assert_array_equal(tracks.boxes, boxes[tracks.detection_index])
