"""`occtrack benchmark` on a KITTI folder of 3D detections: occtrack's models on the ground plane
(`track_kitti`, with the sequence's poses and calibration), the peers on the same detections'
2D boxes with the scores as probabilities, scored in the image (Kitti2DBox) and, for occtrack,
on the ground plane (kitti-bev); the 2D path left as it was.

Every layout is hand-made in tmp_path: one sequence of 20 frames (10 fps, 1242x375), one car
driving ahead of a camera that drives faster (world z = 20 + 0.5 f m, the camera at z = f m:
the car 20 - 0.5 f m ahead), labelled and detected exactly (the 2D box its 3D box projected
with a made-up P2), the detection score a logit (3.0), as PointRCNN writes it."""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from occtrack import peers
from occtrack.cli import main
from occtrack.experiments import benchmark_kitti
from occtrack.io import kitti_geometry
from occtrack.io.kitti import TYPES
from occtrack.metrics.trackeval_kitti import CLASSES
from occtrack.tracker.ground import ground_config, track_kitti

FRAMES = 20
SIZE = (1242, 375)
P2 = np.array([[720.0, 0.0, 620.0, 45.0], [0.0, 720.0, 180.0, 0.2], [0.0, 0.0, 1.0, 0.003]])
LOGIT = 3.0
PROBABILITY = float(1.0 / (1.0 + np.exp(-LOGIT)))  # as `detection_scores` computes it
MODELS = ("none", "object-wise", "measurement-wise")
TRACKERS = (*MODELS, "sort")
HEADLINE = ("hota", "mota", "idf1", "deta", "assa", "fp", "fn", "id_switches")
ALPHAS = 19  # TrackEval's HOTA thresholds 0.05 .. 0.95
AT_HALF = 10  # those a pair 1 m apart (similarity 1 - 1 / 2 = 0.5) is matched at
CAR = TYPES.index("Car")
needs_peers = pytest.mark.skipif(not peers.available(),
                                 reason="the peers need `pip install occtrack[peers]`")


def car_box(frame: int) -> np.ndarray:
    """The car's 3D box (h w l x y z rotation_y) in frame `frame`'s camera coordinates,
    heading along +z."""
    return np.array([1.5, 1.6, 4.0, 3.0, 1.7, 20.0 - 0.5 * frame, -math.pi / 2])


def make_layout(folder: Path, three_d: bool = True, score: float = LOGIT, shift: float = 0.0,
                calib: bool = True, poses: bool = True, gap: tuple[int, ...] = (),
                without_3d: tuple[int, ...] = (), detector: str = "lidar") -> Path:
    """A KITTI folder of the one sequence 0000: label_02/, det_02/`detector`/ (the car's
    exact boxes; `three_d` False writes KITTI's unknown 3D columns, `shift` moves the 3D
    centre sideways by that many metres, the frames in `gap` have no detection, those in
    `without_3d` a row without its 3D columns), seqinfo/, the seqmap, and on request calib/
    and poses/."""
    rows = {"label": [], "det": []}
    for f in range(FRAMES):
        box3d = car_box(f)
        x1, y1, x2, y2 = kitti_geometry.project_boxes(box3d[None], P2, SIZE)[0].tolist()
        h, w, l, x, y, z, ry = box3d.tolist()
        alpha = ry - math.atan2(x, z)
        two = f"{alpha!r} {x1!r} {y1!r} {x2!r} {y2!r}"
        rows["label"].append(f"{f} 0 Car 0 0 {two} {h} {w} {l} {x} {y} {z} {ry!r}")
        if f in gap:
            continue
        three = (f"{h} {w} {l} {x + shift} {y} {z} {ry!r}"
                 if three_d and f not in without_3d else "-1 -1 -1 -1000 -1000 -1000 -10")
        rows["det"].append(f"{f} -1 Car -1 -1 {two} {three} {score!r}")
    files = {"label_02/0000.txt": rows["label"], f"det_02/{detector}/0000.txt": rows["det"]}
    if calib:
        files["calib/0000.txt"] = ["P2: " + " ".join(repr(v) for v in P2.ravel().tolist()),
                                   "R0_rect: 1 0 0 0 1 0 0 0 1"]
    if poses:  # the camera drives 1 m a frame along its z axis
        files["poses/0000.txt"] = [f"1 0 0 0 0 1 0 0 0 0 1 {f}" for f in range(FRAMES)]
    files["seqinfo/0000.ini"] = ["[Sequence]", "name=0000", "frameRate=10",
                                 f"seqLength={FRAMES}", f"imWidth={SIZE[0]}",
                                 f"imHeight={SIZE[1]}"]
    files["evaluate_tracking.seqmap"] = [f"0000 empty 000000 {FRAMES:06d}"]
    for name, lines in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("".join(f"{line}\n" for line in lines), encoding="utf-8")
    return folder


def bench(layout: Path, out: Path, *extra: str, trackers=TRACKERS) -> tuple[dict, str, str]:
    """The benchmark's JSON, and what it printed on stdout and stderr."""
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        code = main(["benchmark", str(layout), "--sequential", "--trackers", ",".join(trackers),
                     "--json", str(out), *extra])
    assert code == 0, stderr.getvalue()
    return json.loads(out.read_text()), stdout.getvalue(), stderr.getvalue()


def error_of(capsys, *argv: str) -> str:
    """The one error line of a refused `occtrack benchmark`, without its prefix."""
    code = main(["benchmark", *argv])
    out, err = capsys.readouterr()
    assert code == 1, (out, err)
    prefix = "occtrack benchmark: error: "
    assert err.startswith(prefix) and err.count("\n") == 1 and "Traceback" not in err, err
    return err[len(prefix):-1]


def without_times(values: dict) -> dict:
    return {k: v for k, v in values.items() if k not in ("seconds", "frames_per_second")}


def reported_from(layout: Path, tracker: str = "none") -> int:
    """The first frame from which `tracker`'s result reports the car in every frame under one
    id, and nothing else (asserted)."""
    seq = benchmark_kitti.load_sequence(layout.resolve(), "lidar", "0000", three_d=True)
    result = benchmark_kitti.track(tracker, seq, CLASSES)
    assert len(np.unique(result.id)) == 1 and set(result.type.tolist()) == {CAR}
    first = int(result.frame.min())
    assert result.frame.tolist() == list(range(first, FRAMES))
    return first


@pytest.fixture(scope="module")
def layout(tmp_path_factory) -> Path:
    return make_layout(tmp_path_factory.mktemp("ground") / "kitti")


@pytest.fixture(scope="module")
def run(layout, tmp_path_factory):
    """The benchmark of the 3D layout under the three models and sort: JSON, tables, path."""
    if not peers.available():
        pytest.skip("the peers need `pip install occtrack[peers]`")
    out = tmp_path_factory.mktemp("out") / "ground.json"
    report, printed, _ = bench(layout, out, "--quiet")
    return report, printed, out


# --- 1. the report: three occtrack models on the ground plane, a peer in the image ---------


def test_3d_detections_are_found_by_content_and_the_json_adds_the_ground_plane(run):
    report, _, _ = run
    assert report["detections"] == "lidar" and report["detections_3d"] is True  # not its name
    assert report["trackers"] == list(TRACKERS)
    assert report["ground"]["protocol"] == "kitti-bev" and report["ground"]["distance"] == 2.0
    assert report["notes"] == []
    entry = report["sequences"]["0000"]
    assert entry["poses"] is True and entry["frames"] == FRAMES
    car = entry["classes"]["car"]
    assert car["truth"] == car["ground"]["truth"] == FRAMES
    assert list(car["trackers"]) == list(TRACKERS)  # the image's scores: every tracker
    assert list(car["ground"]["trackers"]) == list(TRACKERS)
    for where in (car["ground"], report["combined"]["classes"]["car"]["ground"],
                  report["mean"]["classes"]["car"]["ground"]):
        assert where["trackers"]["sort"] is None  # a peer has no 3D output
        for model in MODELS:
            assert 0 < where["trackers"][model]["hota"] <= 1
        if "calibration" in where:
            assert list(where["calibration"]) == list(MODELS)
    # the combined ground-plane scores of the one sequence are its own
    for model in MODELS:
        combined = report["combined"]["classes"]["car"]["ground"]["trackers"][model]
        for key in HEADLINE:
            assert combined[key] == pytest.approx(car["ground"]["trackers"][model][key],
                                                  abs=1e-12), (model, key)


def test_a_car_detected_exactly_is_scored_by_the_frames_it_is_reported(run, layout):
    """Every box taken from the exact detection, one id from frame k on (the tracker
    confirms the car within its first frames): per threshold TP = n - k, FN = k, FP = 0, so
    DetA = AssA = HOTA = (n - k) / n at every localisation threshold, LocA 1, in the image
    (IoU 1) and on the ground plane (distance 0) alike."""
    report, _, _ = run
    first = reported_from(layout)
    assert first <= 5  # confirmed within half a second
    expected = (FRAMES - first) / FRAMES
    car = report["sequences"]["0000"]["classes"]["car"]
    for values in (car["trackers"]["none"], car["ground"]["trackers"]["none"]):
        for key in ("hota", "deta", "assa"):
            assert values[key] == pytest.approx(expected, abs=1e-9), key
        assert values["loca"] == pytest.approx(1.0, abs=1e-9)
        assert (values["fp"], values["fn"], values["id_switches"]) == (0, first, 0)
        assert values["tracks"] == 1


def test_the_ground_plane_scores_the_3d_centre_the_image_cannot_see(tmp_path):
    """Detections whose 3D centres are 1 m to the side of the truth, their 2D boxes exact: the
    image's scores stay those of an exact car; on the ground plane every match has similarity
    1 - 1 / 2 = 0.5, so it counts at the 10 thresholds <= 0.5 of 19 and HOTA is 10 / 19 of
    the exact value; MOTP (CLEAR's mean similarity) is 0.5 and LocA, TrackEval's mean over the
    thresholds with 1 where nothing matched, (10 * 0.5 + 9) / 19; CLEAR (within 1 m) is
    unmoved."""
    folder = make_layout(tmp_path / "shifted", shift=1.0)
    report, _, _ = bench(folder, tmp_path / "s.json", "--quiet", trackers=("none",))
    first = reported_from(folder)
    exact = (FRAMES - first) / FRAMES
    car = report["sequences"]["0000"]["classes"]["car"]
    image, ground = car["trackers"]["none"], car["ground"]["trackers"]["none"]
    assert image["hota"] == pytest.approx(exact, abs=1e-9)
    assert ground["hota"] == pytest.approx(exact * AT_HALF / ALPHAS, abs=1e-9)
    assert ground["motp"] == pytest.approx(0.5, abs=1e-9)
    assert ground["loca"] == pytest.approx((AT_HALF * 0.5 + ALPHAS - AT_HALF) / ALPHAS,
                                           abs=1e-9)
    assert (ground["mota"], ground["fn"], ground["fp"]) == (pytest.approx(exact), first, 0)


def test_the_tables_add_a_ground_plane_table_with_a_dash_for_the_peer(run):
    report, printed, _ = run
    assert printed.startswith("Protocol kitti (TrackEval Kitti2DBox), detections lidar")
    assert "3D detections: occtrack's models track the 3D boxes on the ground plane" in printed
    for title in ("0000 car on the ground plane (20 true objects):",
                  "car, combined over 1 sequences, on the ground plane:",
                  "car, mean over sequences, on the ground plane:"):
        assert title in printed, title
        part = printed[printed.index(title):].split("\n\n")[0]
        assert re.search(r"^  sort( +-)+$", part, flags=re.M), part
        none = report["combined"]["classes"]["car"]["ground"]["trackers"]["none"]
        assert re.search(rf"^  none +{none['hota']:.3f} ", part, flags=re.M), part
    assert "0000 pedestrian" not in printed  # no true pedestrian: no table


def test_the_report_page_builds_from_the_3d_json(run, tmp_path, capsys):
    report, _, path = run
    page_path = tmp_path / "g.html"
    assert main(["report", str(path), "-o", str(page_path)]) == 0
    capsys.readouterr()
    page = page_path.read_text(encoding="utf-8")
    table = re.search(r'<table class="scores" id="car-combined-table">.*?</table>', page,
                      flags=re.S).group(0)
    for tracker in TRACKERS:
        row = re.search(rf"{re.escape(tracker)}</th>(.*?)</tr>", table).group(1)
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row)
        hota = report["combined"]["classes"]["car"]["trackers"][tracker]["hota"]
        assert cells[0] == f"{hota:.3f}", tracker
    # the ground plane's table beside it: occtrack's HOTA there, a dash for a peer
    ground = re.search(r'<table class="scores" id="car-combined-ground">.*?</table>', page,
                       flags=re.S).group(0)
    for tracker in TRACKERS:
        row = re.search(rf"{re.escape(tracker)}</th>(.*?)</tr>", ground).group(1)
        first = re.findall(r"<td[^>]*>(.*?)</td>", row)[0]
        values = report["combined"]["classes"]["car"]["ground"]["trackers"][tracker]
        assert first == ("&ndash;" if values is None else f"{values['hota']:.3f}"), tracker


# --- 2. what each tracker is given --------------------------------------------------------


def test_occtrack_runs_track_kitti_with_the_poses_and_calibration(tmp_path):
    """The benchmark's occtrack run is `track_kitti` with the sequence's poses and
    calibration: with the car unseen for frames 8-10 it coasts, and where it coasts the poses
    matter (without them the camera's own 1 m a frame is the car's motion)."""
    folder = make_layout(tmp_path / "gap", gap=(8, 9, 10))
    seq = benchmark_kitti.load_sequence(folder, "lidar", "0000", three_d=True)
    assert seq.three_d and seq.poses is not None and seq.poses.shape == (FRAMES, 3, 4)
    ours = benchmark_kitti.track("object-wise", seq, CLASSES)
    config = ground_config({"occlusion": "object-wise", "fps": 10, "image_size": SIZE})
    calibration = kitti_geometry.read_calib(folder / "calib" / "0000.txt")
    poses = kitti_geometry.read_poses(folder / "poses" / "0000.txt")
    det = seq.table.select(seq.table.type == CAR)
    direct = track_kitti(det, FRAMES, config, poses, calibration, SIZE)
    for column in ("frame", "id", "type", "box", "box3d", "score"):
        np.testing.assert_array_equal(getattr(ours, column), getattr(direct, column))
    coasting = np.isin(ours.frame, (8, 9, 10))
    assert coasting.any()
    still = track_kitti(det, FRAMES, config, None, calibration, SIZE)
    assert not np.array_equal(still.box3d[np.isin(still.frame, (8, 9, 10))],
                              ours.box3d[coasting])
    # the benchmark's `ground` options are track_kitti's
    online = benchmark_kitti.track("object-wise", seq, CLASSES, ground={"lookahead": 0.0})
    direct = track_kitti(det, FRAMES, config, poses, calibration, SIZE, lookahead=0.0)
    for column in ("frame", "id", "score"):
        np.testing.assert_array_equal(getattr(online, column), getattr(direct, column))
    with pytest.raises(ValueError, match="lookahead must be"):
        benchmark_kitti.track("object-wise", seq, CLASSES, ground={"lookahead": -1.0})


@needs_peers
def test_the_peers_get_the_same_2d_boxes_with_the_logits_as_probabilities(run, tmp_path):
    """sort on the 3D folder scores exactly as sort on a 2D folder of the same boxes whose
    scores are the logits through the logistic function."""
    report, _, _ = run
    flat = make_layout(tmp_path / "flat", three_d=False, score=PROBABILITY, calib=False,
                       poses=False)
    twin, _, _ = bench(flat, tmp_path / "f.json", "--quiet", trackers=("sort",))
    ours = report["sequences"]["0000"]["classes"]["car"]["trackers"]["sort"]
    theirs = twin["sequences"]["0000"]["classes"]["car"]["trackers"]["sort"]
    assert without_times(ours) == without_times(theirs)
    assert (report["sequences"]["0000"]["classes"]["car"]["calibration"]["sort"]
            == twin["sequences"]["0000"]["classes"]["car"]["calibration"]["sort"])


def test_the_scores_become_probabilities_for_every_tracker(layout):
    seq = benchmark_kitti.load_sequence(layout.resolve(), "lidar", "0000", three_d=True)
    assert np.all(seq.det.score == PROBABILITY) and np.all(seq.table.score == PROBABILITY)
    raw = benchmark_kitti.load_sequence(layout.resolve(), "lidar", "0000")
    assert not raw.three_d and np.all(raw.det.score == LOGIT)  # read as written


# --- 3. the sequence's files ------------------------------------------------------------------


def test_a_missing_calibration_is_one_error_naming_the_file(tmp_path, capsys):
    folder = make_layout(tmp_path / "nocalib", calib=False)
    out = tmp_path / "x.json"
    message = error_of(capsys, str(folder), "--sequential", "--trackers", "none", "--json",
                       str(out))
    missing = folder.resolve() / "calib" / "0000.txt"
    assert message.startswith(f"{missing}: sequence 0000 has no calib/0000.txt: its 3D "
                              f"detections need the camera's calibration"), message
    assert not out.exists()


def test_without_poses_the_camera_is_still_with_one_note(tmp_path):
    folder = make_layout(tmp_path / "noposes", poses=False)
    report, _, err = bench(folder, tmp_path / "p.json", trackers=("none",))
    note = ("no poses/NNNN.txt for 0000: the camera is taken as still there (its own motion "
            "falls to the tracker's noise)")
    assert report["notes"] == [note]
    assert report["sequences"]["0000"]["poses"] is False
    assert err.count("note:") == 1 and f"occtrack benchmark: note: {note}" in err
    quiet, _, err = bench(folder, tmp_path / "q.json", "--quiet", trackers=("none",))
    assert quiet["notes"] == [note] and err == ""


def test_a_bad_pose_file_is_named(tmp_path, capsys):
    folder = make_layout(tmp_path / "short")
    poses = folder / "poses" / "0000.txt"
    poses.write_text("".join(poses.read_text().splitlines(keepends=True)[:5]))
    message = error_of(capsys, str(folder), "--sequential", "--trackers", "none")
    assert message.startswith(f"{poses.resolve()}: 5 poses, but the detections reach frame "
                              f"{FRAMES - 1}"), message


# --- 4. the 2D path ---------------------------------------------------------------------------


def test_2d_detections_take_the_2d_path_unchanged(tmp_path, capsys):
    """A folder of 2D boxes (x y z = -1000, RRC's way) needs no calibration or poses, and
    its report is the 2D one (no ground plane anywhere); occtrack's scores are those of
    `occtrack track` then `occtrack eval --protocol kitti`."""
    folder = make_layout(tmp_path / "rrc", three_d=False, score=0.9, calib=False,
                         poses=False, detector="rrc")
    report, printed, err = bench(folder, tmp_path / "r.json", "--quiet", trackers=MODELS)
    assert report["detections_3d"] is False and report["notes"] == [] and err == ""
    assert set(report) == {"protocol", "layout", "folder", "detections", "detections_3d",
                           "trackers", "classes", "sequences", "combined", "mean", "notes"}
    assert "ground" not in json.dumps(report) and "ground plane" not in printed
    assert "poses" not in report["sequences"]["0000"]
    result = tmp_path / "r.txt"
    assert main(["track", str(folder / "det_02" / "rrc" / "0000.txt"), "-o", str(result),
                 "--occlusion", "none", "--quiet"]) == 0
    assert main(["eval", str(folder / "label_02" / "0000.txt"), str(result), "--protocol",
                 "kitti", "--json"]) == 0
    scored = json.loads(capsys.readouterr().out)
    ours = report["sequences"]["0000"]["classes"]["car"]["trackers"]["none"]
    for key in HEADLINE:
        assert ours[key] == scored["classes"]["car"]["sequences"]["0000"][key], key


def test_rows_without_3d_columns_among_3d_ones_make_the_folder_2d_with_a_note(tmp_path):
    folder = make_layout(tmp_path / "mixed", without_3d=(4,), calib=False)
    report, _, err = bench(folder, tmp_path / "m.json", trackers=("none",))
    det = folder.resolve() / "det_02" / "lidar" / "0000.txt"
    note = (f"1 of {FRAMES} detection rows have no 3D columns (x y z = -1000; first at {det} "
            f"line 5): the detections are tracked as 2D boxes")
    assert report["detections_3d"] is False and report["notes"] == [note]
    assert "ground" not in report and f"note: {note}" in err
