"""`occtrack track` on KITTI tracking files: the image size and frame rate from KITTI's layout,
one run for every class with each track keeping its class, KITTI's result format with frames
as they came and the 3D columns of the detection a box took, and one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.io.kitti import TYPES, UNKNOWN_3D, read_kitti
from occtrack.io.mot import first_duplicate

CAR, PEDESTRIAN = TYPES.index("Car"), TYPES.index("Pedestrian")
BOX_TOL = 0.005 + 1e-6  # result boxes have 2 decimals
REAL_TOL = 0.0000005 + 1e-9  # alpha and the 3D columns 6
BORDER = 1.0  # TrackerConfig.border_margin: an edge this close to the border is the image's
FRAMES_0000 = 154  # seqinfo/0000.ini


def track(det, out, *args):
    return main(["track", str(det), "-o", str(out), "--quiet", *args])


def one_error_line(capsys, start: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith(start), err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


def row(frame, kind="Car", box=(10, 20, 50, 80), score=0.9, alpha=-10, box3d=UNKNOWN_3D):
    cells = [frame, -1, kind, -1, -1, alpha, *box, *box3d, score]
    return " ".join(str(c) for c in cells)


def assert_a_kitti_result(result, types, frames):
    """Properties every KITTI result of `occtrack track` has."""
    assert len(result) > 0
    assert set(result.type.tolist()) <= set(types)
    assert result.frame.min() >= 0 and result.frame.max() < frames
    assert (result.id >= 1).all()
    assert first_duplicate(result.frame, result.id) is None  # ids unique within a frame
    for ident in np.unique(result.id):  # a track keeps its class for life
        assert len(np.unique(result.type[result.id == ident])) == 1, ident
    assert ((result.score >= 0) & (result.score <= 1)).all()
    assert (result.truncated == -1).all() and (result.occluded == -1).all()
    key = list(zip(result.frame.tolist(), result.id.tolist(), strict=True))
    assert key == sorted(key)


def matches(result, det, shift=0):
    """Per result row: whether a detection of the same type in frame + shift has its 2D box
    (to the written 2 decimals)."""
    out = np.zeros(len(result), bool)
    for i in range(len(result)):
        same = (det.frame == result.frame[i] + shift) & (det.type == result.type[i])
        out[i] = np.any(np.all(np.abs(det.box[same] - result.box[i]) <= BOX_TOL, axis=1))
    return out


@pytest.fixture(scope="module")
def rrc(kitti_root, tmp_path_factory):
    """RRC's detections of 0000 tracked (image size and frame rate from seqinfo/0000.ini)."""
    det = kitti_root / "det_02" / "rrc" / "0000.txt"
    out = tmp_path_factory.mktemp("rrc") / "r.txt"
    assert track(det, out) == 0
    return det, out


def test_a_real_detection_file_becomes_a_kitti_result(rrc):
    det_path, out = rrc
    det, result = read_kitti(det_path), read_kitti(out)
    assert_a_kitti_result(result, (CAR, PEDESTRIAN), FRAMES_0000)
    assert set(result.type.tolist()) == {CAR, PEDESTRIAN}  # both classes in one run
    # 2D detections carry no 3D columns, and nor does the result
    np.testing.assert_array_equal(result.box3d, np.tile(UNKNOWN_3D, (len(result), 1)))
    assert (result.alpha == -10).all()
    # frames are numbered as they came (0-based): most reported boxes are a detection's box
    # in the same frame, none in the frame before or after
    same = matches(result, det)
    assert same.mean() > 0.6
    assert matches(result, det, -1).sum() < same.sum() / 10
    assert matches(result, det, 1).sum() < same.sum() / 10
    assert result.frame.min() == det.frame.min() == 0


def test_classes_picks_the_types(kitti_root, tmp_path, capsys):
    det = kitti_root / "det_02" / "rrc" / "0000.txt"
    out = tmp_path / "car.txt"
    assert track(det, out, "--classes", "Car") == 0
    err = capsys.readouterr().err
    assert err == (f"occtrack track: warning: {det}: skipped 303 rows of classes not asked for "
                   f"(Pedestrian)\n")
    result = read_kitti(out)
    assert_a_kitti_result(result, (CAR,), FRAMES_0000)
    assert matches(result, read_kitti(det)).mean() > 0.6
    assert track(det, tmp_path / "ped.txt", "--classes", "pedestrian") == 0
    assert set(read_kitti(tmp_path / "ped.txt").type.tolist()) == {PEDESTRIAN}


def test_the_same_input_gives_the_same_bytes(rrc, tmp_path, capsys):
    det, out = rrc
    again = tmp_path / "again.txt"
    assert track(det, again) == 0
    assert again.read_bytes() == out.read_bytes()
    assert track(det, "-") == 0  # standard output: the same rows
    assert capsys.readouterr().out == out.read_text()


@pytest.fixture(scope="module")
def pointrcnn(kitti_root, tmp_path_factory):
    """PointRCNN's Car detections of 0000 tracked (raw logits mapped from -10..10)."""
    det = kitti_root / "det_02" / "pointrcnn" / "0000.txt"
    out = tmp_path_factory.mktemp("pointrcnn") / "r.txt"
    assert track(det, out, "--score-range=-10,10", "--lenient", "--classes", "Car") == 0
    return read_kitti(det), read_kitti(out)


def test_boxes_taken_from_detections_carry_their_3d_columns(pointrcnn):
    det, result = pointrcnn
    assert_a_kitti_result(result, (CAR,), FRAMES_0000)
    known = result.box3d[:, 3] != -1000
    assert known.sum() > len(result) / 2
    # a box reported without a detection has KITTI's unknowns
    np.testing.assert_array_equal(result.box3d[~known], np.tile(UNKNOWN_3D, ((~known).sum(), 1)))
    assert (result.alpha[~known] == -10).all()
    width, height = 1242, 375  # seqinfo/0000.ini
    low = np.array([BORDER, BORDER])
    high = np.array([width - BORDER, height - BORDER])
    exact = 0
    for i in np.flatnonzero(known):
        same = ((det.frame == result.frame[i]) & (det.type == CAR)
                & np.all(np.abs(det.box3d - result.box3d[i]) <= REAL_TOL, axis=1)
                & (np.abs(det.alpha - result.alpha[i]) <= REAL_TOL))
        assert same.sum() == 1, (result.frame[i], result.box3d[i])
        x1y1, x2y2 = det.box[same][0, :2], det.box[same][0, 2:]
        r1, r2 = result.box[i, :2], result.box[i, 2:]
        # the detection's own box, but where it is clipped at the image border the tracker
        # may report the edge farther out (Tracks.boxes)
        ok1 = (np.abs(r1 - x1y1) <= BOX_TOL) | ((x1y1 <= low) & (r1 < x1y1))
        ok2 = (np.abs(r2 - x2y2) <= BOX_TOL) | ((x2y2 >= high) & (r2 > x2y2))
        assert ok1.all() and ok2.all(), (result.frame[i], result.box[i], det.box[same])
        exact += np.all(np.abs(result.box[i] - det.box[same][0]) <= BOX_TOL)
    assert exact > 0.8 * known.sum()


def test_boxes_taken_from_detections_in_the_image_stay_in_it(pointrcnn):
    det, result = pointrcnn
    width, height = 1242, 375  # seqinfo/0000.ini
    assert det.box[:, :2].min() >= 0 and det.box[:, 2].max() <= width
    assert det.box[:, 3].max() <= height  # PointRCNN's boxes all lie in the image
    took = result.box3d[:, 3] != -1000
    box = result.box[took]
    outside = ((box[:, 0] < 0) | (box[:, 1] < 0) | (box[:, 2] > width)
               | (box[:, 3] > height))
    assert outside.sum() == 0, box[outside][:5]


def test_frames_and_3d_columns_follow_the_rows_in_any_order(tmp_path):
    """A shuffled file, starting at frame 3, with DontCare rows, a class not asked for and a
    row that --lenient skips: every box that took a detection carries that detection's own
    3D columns (x = the frame, y = the object) and is reported in that detection's frame."""
    lines = []
    for frame in range(3, 15):
        car = (100 + 4 * frame, 100, 160 + 4 * frame, 140)
        ped = (400 - 3 * frame, 200, 430 - 3 * frame, 290)
        lines.append(row(frame, "Car", car, 0.9, -0.5, (1.5, 1.6, 4.0, frame, 0, 20, 0.25)))
        lines.append(row(frame, "Pedestrian", ped, 0.8, -1.5, (1.7, 0.6, 0.9, frame, 1, 9, 1)))
        lines.append(row(frame, "Cyclist", (10, 10, 40, 90), 0.95, -2.5,
                         (1.7, 0.6, 1.8, frame, 2, 7, 0)))
        lines.append(row(frame, "DontCare", (500, 10, 600, 50), 1))
    lines.append(row(5, "Car", (700, 10, 750, 60), 0.9, -3.5, (1, 1, 1, 5, 3, 5, 0)))
    order = np.random.default_rng(7).permutation(len(lines))
    det = tmp_path / "det.txt"
    det.write_text("\n".join(lines[i] for i in order) + "\n")
    out = tmp_path / "r.txt"
    code = track(det, out, "--image-size", "640x480", "--fps", "10", "--lenient",
                 "--classes", "Car,Pedestrian")
    assert code == 0
    result = read_kitti(out)
    assert_a_kitti_result(result, (CAR, PEDESTRIAN), 15)
    assert set(result.type.tolist()) == {CAR, PEDESTRIAN}
    assert 3 <= result.frame.min() <= 4  # reported from its first or second detection
    known = result.box3d[:, 3] != -1000
    assert known.sum() > 0.8 * len(result)
    np.testing.assert_array_equal(result.box3d[known, 3], result.frame[known])
    np.testing.assert_array_equal(result.box3d[known, 4], np.where(
        result.type[known] == CAR, 0, 1))
    np.testing.assert_array_equal(result.alpha[known], np.where(
        result.type[known] == CAR, -0.5, -1.5))
    for i in np.flatnonzero(known):
        f = result.frame[i]
        expected = ((100 + 4 * f, 100, 160 + 4 * f, 140) if result.type[i] == CAR
                    else (400 - 3 * f, 200, 430 - 3 * f, 290))
        assert np.abs(result.box[i] - expected).max() <= BOX_TOL


# -- errors ---------------------------------------------------------------------------------


def test_image_size_unknown_outside_a_layout(tmp_path, capsys):
    det = tmp_path / "0000.txt"
    det.write_text(row(0) + "\n" + row(1) + "\n")
    out = tmp_path / "r.txt"
    for fmt in ("kitti", "auto"):
        assert track(det, out, "--format", fmt, "--fps", "10") == 1
        err = one_error_line(capsys, f"occtrack track: error: {det}: image size unknown: pass "
                                     f"--image-size WxH")
        assert "seqinfo/NNNN.ini" in err
    assert track(det, out, "--format", "kitti", "--image-size", "1242x375") == 1
    one_error_line(capsys, f"occtrack track: error: {det}: fps unknown: pass --fps HZ")
    assert not out.exists()
    assert track(det, out, "--format", "kitti", "--image-size", "1242x375", "--fps", "10") == 0


@pytest.mark.parametrize("line,message", [
    (row(1, box=(50, 20, 10, 80)), "negative box size"),
    (row(1, score="nan"), "column 18 is nan"),
    (row(1.5), "frame 1.5 is not a whole number"),
    (row(-1), "frame -1 is out of range"),
    ("1 -1 Car -1 -1 -10 10 20 50 80", "expected 17 columns"),
    (row(1, kind="7"), "column 3 should be a KITTI type name"),
    (row(1, score=57), "score 57 is outside [0, 1]"),
])
def test_a_bad_row_is_one_line_naming_file_and_line(tmp_path, capsys, line, message):
    det = tmp_path / "det.txt"
    det.write_text(f"{row(0)}\n{row(1, box=(12, 20, 52, 80))}\n{line}\n{row(2)}\n")
    out = tmp_path / "r.txt"
    assert track(det, out, "--image-size", "640x480", "--fps", "10") == 1
    err = one_error_line(capsys, f"occtrack track: error: {det}:3: ")
    assert message in err
    assert not out.exists()


def test_a_frame_past_the_sequence_is_named(tmp_path, capsys):
    root = tmp_path / "kitti"
    (root / "det_02" / "mine").mkdir(parents=True)
    (root / "seqinfo").mkdir()
    (root / "seqinfo" / "0001.ini").write_text(
        "[Sequence]\nname=0001\nframeRate=10\nseqLength=5\nimWidth=640\nimHeight=480\n")
    det = root / "det_02" / "mine" / "0001.txt"
    det.write_text("\n".join(row(f) for f in (0, 1, 2, 5, 3)) + "\n")
    out = tmp_path / "r.txt"
    assert track(det, out) == 1
    one_error_line(capsys, f"occtrack track: error: {det}:4: frame 5 is past the sequence's 5 "
                           f"frames (0..4, seqinfo)")
    det.write_text("\n".join(row(f) for f in (0, 1, 2, 4, 3)) + "\n")
    assert track(det, out) == 0  # the size and rate from seqinfo/0001.ini
    result = read_kitti(out)
    assert_a_kitti_result(result, (CAR,), 5)


def test_classes_on_a_motchallenge_file_is_an_error(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n2,-1,12,10,30,90,0.8\n")
    out = tmp_path / "r.txt"
    assert track(det, out, "--image-size", "640x480", "--fps", "30", "--classes", "Car") == 1
    one_error_line(capsys, f"occtrack track: error: {det}: --classes picks KITTI types")
    assert not out.exists()
    assert track(det, out, "--image-size", "640x480", "--fps", "30") == 0
    assert out.read_text().splitlines()[0].count(",") == 9  # a MOTChallenge file stays one


@pytest.mark.parametrize("classes,message", [
    ("Bus", "--classes: unknown class 'Bus'"),
    ("DontCare", "--classes: unknown class 'DontCare'"),
])
def test_unknown_classes_are_one_line(tmp_path, capsys, classes, message):
    det = tmp_path / "det.txt"
    det.write_text(row(0) + "\n")
    out = tmp_path / "r.txt"
    assert track(det, out, "--image-size", "640x480", "--fps", "10", "--classes", classes) == 1
    assert message in one_error_line(capsys, "occtrack track: error: ")
    assert not out.exists()


def test_negative_score_range_as_a_separate_argument(tmp_path):
    det = tmp_path / "det.txt"
    det.write_text(row(0, score=-2.5) + "\n" + row(1, score=3) + "\n")
    try:
        code = track(det, tmp_path / "r.txt", "--image-size", "640x480", "--fps", "10",
                     "--score-range", "-10,10")
    except SystemExit as exit_:  # argparse's usage error
        code = exit_.code
    assert code == 0
    assert len(read_kitti(tmp_path / "r.txt")) > 0
