"""The kitti protocol of `occtrack eval`: TrackEval's own file-reading run beside it on real
KITTI sequences (every number equal), a hand-made case with known answers for each of KITTI's
preprocessing rules, the errors it names by file and line, `--calibration`, and the sequence
length found in the layout."""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.metrics.trackeval_kitti import CLASSES, read_seqmap, sequence_length

UNKNOWN_3D = "-1 -1 -1 -1000 -1000 -1000 -10"


def row(frame, ident, kind, box, truncated=0, occluded=0, score=None) -> str:
    """One KITTI row: 17 columns, or 18 with a score."""
    x1, y1, x2, y2 = box
    text = (f"{frame} {ident} {kind} {truncated} {occluded} -10 {x1:.2f} {y1:.2f} {x2:.2f} "
            f"{y2:.2f} {UNKNOWN_3D}")
    return text if score is None else f"{text} {score:.4f}"


def write(path: Path, rows) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{r}\n" for r in rows), encoding="utf-8")
    return path


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main(["eval", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv) -> dict:
    code, out, err = run(capsys, *argv, "--json")
    assert code == 0, err
    return json.loads(out)


def one_error(capsys, *argv) -> str:
    """The one error line of a refused `occtrack eval`, without its prefix."""
    code, out, err = run(capsys, *argv)
    assert code == 1 and out == ""
    assert err.startswith("occtrack eval: error: ") and err.endswith("\n"), err
    assert err.count("\n") == 1, err
    return err[len("occtrack eval: error: "):-1]


# --- TrackEval's own run on real sequences ---------------------------------------------------

TRACKED = ("0000", "0017")  # results made by `occtrack track` from the RRC detections
PERTURBED = ("0004",)  # results made from the ground truth by hand
SEQUENCES = tuple(sorted(TRACKED + PERTURBED))


def perturbed_result(labels: Path, seed: int) -> list[str]:
    """A result made from a label file: Car and Pedestrian rows with a score, some dropped,
    some boxes jittered, two ids swapped from mid-sequence on; Van rows reported as cars
    (distractors), Cyclist rows reported as such (not scored), boxes on DontCare regions, false
    boxes of all heights, and a few rows with id -1 (dropped by TrackEval's reader)."""
    rng = np.random.default_rng(seed)
    rows = [line.split() for line in labels.read_text().splitlines() if line.strip()]
    last = max(int(r[0]) for r in rows)
    tracks = sorted({int(r[1]) for r in rows if r[2] in ("Car", "Pedestrian")})
    swap = {tracks[0]: tracks[1], tracks[1]: tracks[0], tracks[2]: tracks[3],
            tracks[3]: tracks[2]}
    out = []
    for k, r in enumerate(rows):
        frame, ident, kind = int(r[0]), int(r[1]), r[2]
        box = np.array(r[6:10], float)
        if kind == "DontCare":
            if rng.random() < 0.5:
                continue
            ident, kind = 100_000 + k, "Car"
        elif kind in ("Car", "Pedestrian", "Van", "Cyclist"):
            if rng.random() < 0.1:
                continue
            if rng.random() < 0.3:
                box = box + rng.uniform(-8, 8, 4)
                box = np.array([min(box[0], box[2]), min(box[1], box[3]),
                                max(box[0], box[2]), max(box[1], box[3])])
            if frame >= last // 2:
                ident = swap.get(ident, ident)
            kind = "Car" if kind == "Van" else kind
        else:
            continue
        out.append(row(frame, ident, kind, box, -1, -1, rng.uniform(0, 1)))
    for frame in range(0, last + 1, 7):  # false boxes, 10..60 px tall: some too small to count
        x, y, h = rng.uniform(0, 1100), rng.uniform(0, 300), rng.uniform(10, 60)
        out.append(row(frame, 200_000 + frame, ("Car", "Pedestrian")[frame % 2],
                       (x, y, x + 1.5 * h, y + h), -1, -1, rng.uniform(0, 1)))
    for frame in range(3, last + 1, 40):  # no identity: TrackEval's reader drops these rows
        out.append(row(frame, -1, "Car", (500, 150, 600, 220), -1, -1, 0.5))
    rng.shuffle(out)
    return out


def trackeval_run(gt_folder: Path, trackers: Path, output: Path) -> dict:
    """TrackEval's own evaluator on its own folder layout: {sequence or COMBINED_SEQ: {class:
    results}}."""
    import trackeval

    with contextlib.redirect_stdout(io.StringIO()):
        evaluator = trackeval.Evaluator({
            "USE_PARALLEL": False, "BREAK_ON_ERROR": True, "LOG_ON_ERROR": False,
            "PRINT_RESULTS": False, "PRINT_ONLY_COMBINED": False, "PRINT_CONFIG": False,
            "TIME_PROGRESS": False, "DISPLAY_LESS_PROGRESS": True, "OUTPUT_SUMMARY": False,
            "OUTPUT_EMPTY_CLASSES": False, "OUTPUT_DETAILED": False, "PLOT_CURVES": False})
        dataset = trackeval.datasets.Kitti2DBox({
            "GT_FOLDER": str(gt_folder), "TRACKERS_FOLDER": str(trackers),
            "OUTPUT_FOLDER": str(output), "TRACKERS_TO_EVAL": ["x"],
            "CLASSES_TO_EVAL": list(CLASSES), "SPLIT_TO_EVAL": "training",
            "PRINT_CONFIG": False})
        metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
                   trackeval.metrics.Identity({"PRINT_CONFIG": False})]
        out, messages = evaluator.evaluate([dataset], metrics)
    assert messages["Kitti2DBox"]["x"] == "Success", messages
    return out["Kitti2DBox"]["x"]


@pytest.fixture(scope="module")
def real_run(kitti_root, tmp_path_factory):
    """(occtrack's --json report on the folders, TrackEval's results, the GT folder, the result
    folder): three real sequences in a KITTI folder built here (label_02/ copied, a seqmap
    naming them for occtrack and TrackEval), results in a TrackEval tracker folder."""
    root = tmp_path_factory.mktemp("kitti_real")
    gt_folder, results = root / "gt", root / "trackers" / "x" / "data"
    (gt_folder / "label_02").mkdir(parents=True)
    results.mkdir(parents=True)
    lengths = read_seqmap(kitti_root / "evaluate_tracking.seqmap")
    seqmap = "".join(f"{name} empty 000000 {lengths[name]:06d}\n" for name in SEQUENCES)
    (gt_folder / "evaluate_tracking.seqmap").write_text(seqmap)
    (gt_folder / "evaluate_tracking.seqmap.training").write_text(seqmap)
    for name in SEQUENCES:
        shutil.copy(kitti_root / "label_02" / f"{name}.txt", gt_folder / "label_02")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for name in TRACKED:
            code = main(["track", str(kitti_root / "det_02" / "rrc" / f"{name}.txt"), "-o",
                         str(results / f"{name}.txt"), "--quiet"])
            assert code == 0
    for seed, name in enumerate(PERTURBED):
        write(results / f"{name}.txt", perturbed_result(gt_folder / "label_02" / f"{name}.txt",
                                                        seed))
    theirs = trackeval_run(gt_folder, root / "trackers", root / "trackeval_output")
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer), contextlib.redirect_stderr(io.StringIO()):
        code = main(["eval", str(gt_folder), str(results), "--protocol", "kitti", "--json",
                     "--calibration"])
    assert code == 0
    return json.loads(buffer.getvalue()), theirs, gt_folder, results


def trackeval_values(results: dict) -> dict:
    """TrackEval's numbers under occtrack's keys, taken from its arrays here."""
    hota, clear, identity = results["HOTA"], results["CLEAR"], results["Identity"]
    return {"hota": float(np.mean(hota["HOTA"])), "deta": float(np.mean(hota["DetA"])),
            "assa": float(np.mean(hota["AssA"])), "loca": float(np.mean(hota["LocA"])),
            "mota": float(clear["MOTA"]), "motp": float(clear["MOTP"]),
            "idf1": float(identity["IDF1"]), "fp": int(clear["CLR_FP"]),
            "fn": int(clear["CLR_FN"]), "id_switches": int(clear["IDSW"]),
            "mostly_tracked": int(clear["MT"]), "mostly_lost": int(clear["ML"])}


@pytest.mark.parametrize("cls", CLASSES)
@pytest.mark.parametrize("seq", [*SEQUENCES, "COMBINED_SEQ"])
def test_equal_to_trackeval_own_run(real_run, seq, cls):
    ours, theirs, _, _ = real_run
    entry = ours["classes"][cls]
    got = entry["combined"] if seq == "COMBINED_SEQ" else entry["sequences"][seq]
    expected = trackeval_values(theirs[seq][cls])
    assert set(got) == set(expected)
    for key, value in expected.items():
        assert got[key] == value, (key, got[key], value)  # every digit, not approximately
        assert type(got[key]) is type(value), key


def test_real_run_is_not_trivial(real_run):
    """The equality above is between numbers that say something: both classes have hits,
    misses, false boxes and switches, and every sequence was scored."""
    ours, theirs, _, _ = real_run
    assert list(ours["classes"]) == list(CLASSES)
    for cls in CLASSES:
        assert list(ours["classes"][cls]["sequences"]) == list(SEQUENCES)
        combined = ours["classes"][cls]["combined"]
        assert 0.1 < combined["hota"] < 0.95 and 0 < combined["mota"] < 1
        assert min(combined["fp"], combined["fn"], combined["id_switches"]) > 0
    # 0017 has no scored car: HOTA 0 whatever the result, but its false cars still count
    car_0017 = ours["classes"]["car"]["sequences"]["0017"]
    assert car_0017["hota"] == 0 and car_0017["fp"] > 0


def test_calibration_counts_the_scored_boxes_of_each_class(real_run):
    """Per class the calibration table holds exactly the result boxes the protocol scores
    (TrackEval's true positives and false positives over every sequence)."""
    ours, theirs, _, _ = real_run
    for cls in CLASSES:
        table = ours["classes"][cls]["calibration"]
        scored = sum(int(theirs[seq][cls]["CLEAR"]["CLR_TP"] + theirs[seq][cls]["CLEAR"]["CLR_FP"])
                     for seq in SEQUENCES)
        assert sum(table["boxes"]) == scored > 0
        assert table["bins"] == len(table["boxes"]) == 10
        assert 0 <= table["ece"] <= 1


def test_sequence_length_from_the_layout(kitti_root, real_run, tmp_path):
    assert sequence_length(kitti_root / "label_02" / "0000.txt") == 154  # seqinfo/0000.ini
    assert sequence_length(kitti_root / "det_02" / "rrc" / "0017.txt") == 145
    _, _, gt_folder, results = real_run
    assert not (gt_folder / "seqinfo").exists()
    assert sequence_length(gt_folder / "label_02" / "0004.txt") == 314  # the seqmap
    assert sequence_length(results / "0004.txt") is None  # not in a KITTI layout
    shutil.copy(kitti_root / "label_02" / "0000.txt", tmp_path / "0000.txt")
    assert sequence_length(tmp_path / "0000.txt") is None


def test_sequence_length_prefers_seqinfo_to_the_seqmap(tmp_path):
    root = tmp_path / "kitti"
    labels = write(root / "label_02" / "0003.txt", [row(0, 1, "Car", (0, 0, 50, 50))])
    detections = write(root / "det_02" / "mine" / "0003.txt",
                       [row(0, -1, "Car", (0, 0, 50, 50), score=0.5)])
    assert sequence_length(labels) is None  # neither seqinfo nor seqmap
    (root / "evaluate_tracking.seqmap").write_text("0001 empty 000000 000004\n"
                                                   "0003 empty 000000 000009\n")
    assert sequence_length(labels) == sequence_length(detections) == 9
    write(root / "seqinfo" / "0001.ini", ["[Sequence]", "seqLength=3"])  # another sequence's
    assert sequence_length(labels) == 9
    write(root / "seqinfo" / "0003.ini", ["[Sequence]", "name=0003", "frameRate=10",
                                          "seqLength=7", "imWidth=1242", "imHeight=375"])
    assert sequence_length(labels) == sequence_length(detections) == 7
    (root / "seqinfo" / "0003.ini").unlink()
    assert sequence_length(labels) == 9


# --- a hand-made case with known answers ------------------------------------------------------

CAR_A = [(100, 100, 200, 160), (110, 100, 210, 160), (120, 100, 220, 160)]  # per frame
CAR_B = [(400, 120, 480, 180), (400, 120, 480, 180), (400, 120, 480, 180)]
VAN = (700, 100, 800, 170)
DONTCARE = (900, 50, 1100, 250)
TRUNCATED = (0, 150, 60, 250)
FAR = (1000, 300, 1040, 340)  # nothing there; 40 px tall
TWO_CARS = [row(t, i, "Car", box) for t in range(3) for i, box in ((1, CAR_A[t]), (2, CAR_B[t]))]
TINY_GT = [*TWO_CARS, row(1, 7, "Van", VAN), row(1, -1, "DontCare", DONTCARE),
           row(2, 8, "Car", TRUNCATED, truncated=1)]


def two_cars(score=0.9) -> list[str]:
    return [f"{r} {score:.4f}" for r in TWO_CARS]


def car_scores(capsys, tmp_path, gt_rows, result_rows, *options) -> dict:
    gt = write(tmp_path / "gt" / "0000.txt", gt_rows)
    result = write(tmp_path / "result" / "0000.txt", result_rows)
    report = run_json(capsys, gt, result, "--classes", "car", *options)
    assert report["protocol"] == "kitti" and list(report["classes"]) == ["car"]
    entry = report["classes"]["car"]
    assert list(entry["sequences"]) == ["0000"]
    assert entry["combined"] == entry["sequences"]["0000"]
    return entry["combined"]


def test_tiny_perfect_result(capsys, tmp_path):
    # no --protocol: a KITTI ground-truth file picks kitti by itself
    values = car_scores(capsys, tmp_path, TINY_GT, two_cars())
    assert values["mota"] == 1 and values["idf1"] == 1 and values["motp"] == 1
    assert values["hota"] == pytest.approx(1, abs=1e-12)
    assert values["deta"] == pytest.approx(1, abs=1e-12)
    assert values["assa"] == pytest.approx(1, abs=1e-12)
    assert values["loca"] == pytest.approx(1, abs=1e-12)
    # the truncated car (truncation 1) is not missed, the van not either
    assert (values["fp"], values["fn"], values["id_switches"]) == (0, 0, 0)
    assert (values["mostly_tracked"], values["mostly_lost"]) == (2, 0)


def test_tiny_swapped_ids_and_a_miss(capsys, tmp_path):
    # frame 2: the two cars' ids swapped (two switches), frame 1: car 2 not reported
    rows = [row(0, 1, "Car", CAR_A[0]), row(0, 2, "Car", CAR_B[0]), row(1, 1, "Car", CAR_A[1]),
            row(2, 2, "Car", CAR_A[2]), row(2, 1, "Car", CAR_B[2])]
    values = car_scores(capsys, tmp_path, TINY_GT, [f"{r} 0.5" for r in rows],
                        "--protocol", "kitti")
    assert (values["fp"], values["fn"], values["id_switches"]) == (0, 1, 2)
    assert values["mota"] == pytest.approx(1 - 3 / 6)
    assert values["idf1"] == pytest.approx(2 * 3 / (6 + 5))  # IDTP 3: car 1 - id 1 twice, 2 - 2
    assert 0 < values["hota"] < 1


@pytest.mark.parametrize("extra, gt_change, fp", [
    # a car box on the van is removed (van: car's distractor); on a truck it is a false box
    (row(1, 9, "Car", VAN, score=0.5), None, 0),
    (row(1, 9, "Car", VAN, score=0.5), ("Van", "Truck"), 1),
    # an unmatched box inside the DontCare region is not counted; one far away is
    (row(1, 9, "Car", (950, 100, 1050, 200), score=0.5), None, 0),
    (row(0, 9, "Car", (950, 100, 1050, 200), score=0.5), None, 1),  # no DontCare in frame 0
    (row(1, 9, "Car", FAR, score=0.5), None, 1),
    # an unmatched box 20 px tall is not counted, one 30 px tall is
    (row(1, 9, "Car", (1000, 300, 1040, 320), score=0.5), None, 0),
    (row(1, 9, "Car", (1000, 300, 1040, 330), score=0.5), None, 1),
    # a box on the truncated car is removed; with the car untruncated it is a hit
    (row(2, 9, "Car", TRUNCATED, score=0.5), None, 0),
    # a pedestrian box is not a car's false box
    (row(1, 9, "Pedestrian", FAR, score=0.5), None, 0),
], ids=["van", "truck", "dontcare", "dontcare-other-frame", "far", "20px", "30px",
        "truncated", "pedestrian"])
def test_tiny_preprocessing(capsys, tmp_path, extra, gt_change, fp):
    gt = TINY_GT if gt_change is None else [r.replace(*gt_change) for r in TINY_GT]
    values = car_scores(capsys, tmp_path, gt, [*two_cars(), extra])
    assert (values["fp"], values["fn"]) == (fp, 0)
    assert values["mota"] == pytest.approx(1 - fp / 6)


def test_tiny_truncated_car_counts_once_untruncated(capsys, tmp_path):
    # the same car with truncation 0 is scored: missed without a box, a hit with one
    gt = [r.replace(" Car 1 ", " Car 0 ") for r in TINY_GT]
    assert gt != TINY_GT
    missed = car_scores(capsys, tmp_path, gt, two_cars())
    assert (missed["fp"], missed["fn"]) == (0, 1)
    hit = car_scores(capsys, tmp_path, gt, [*two_cars(), row(2, 9, "Car", TRUNCATED, score=0.5)])
    assert (hit["fp"], hit["fn"], hit["mota"]) == (0, 0, 1)


def test_tiny_calibration_table(capsys, tmp_path):
    # six right boxes at 0.95; a false box at 0.15; boxes the protocol removes (on the van, in
    # DontCare, 20 px tall) and a pedestrian box must not appear in the car table
    result = [*two_cars(0.95), row(1, 9, "Car", FAR, score=0.15),
              row(1, 10, "Car", VAN, score=0.55), row(1, 11, "Car", (950, 100, 1050, 200),
                                                      score=0.65),
              row(2, 12, "Car", (1000, 300, 1040, 320), score=0.75),
              row(0, 13, "Pedestrian", FAR, score=0.35)]
    gt = write(tmp_path / "gt.txt", TINY_GT)
    res = write(tmp_path / "res.txt", result)
    report = run_json(capsys, gt, res, "--calibration")
    car = report["classes"]["car"]
    assert car["combined"]["fp"] == 1
    table = car["calibration"]
    assert table["boxes"] == [0, 1, 0, 0, 0, 0, 0, 0, 0, 6]
    assert table["right"][1] == 0 and table["right"][9] == 1
    assert table["confidence"][1] == pytest.approx(0.15)
    assert table["confidence"][9] == pytest.approx(0.95)
    assert table["ece"] == pytest.approx((6 * 0.05 + 0.15) / 7, abs=1e-6)
    pedestrian = report["classes"]["pedestrian"]["calibration"]
    assert pedestrian["boxes"] == [0, 0, 0, 1, 0, 0, 0, 0, 0, 0]
    assert pedestrian["right"][3] == 0


@pytest.mark.parametrize("score", ["1.5", "-0.1"])
def test_calibration_refuses_a_score_outside_0_1(capsys, tmp_path, score):
    gt = write(tmp_path / "gt.txt", TINY_GT)
    rows = two_cars()
    rows[3] = f"{TWO_CARS[3]} {score}"
    res = write(tmp_path / "res.txt", rows)
    message = one_error(capsys, gt, res, "--calibration", "--json")
    assert message.startswith(f"{res}:4: score (column 18) {score}")
    assert "[0, 1]" in message
    assert run_json(capsys, gt, res)["classes"]["car"]["combined"]["fp"] == 0  # scored without


# --- errors -----------------------------------------------------------------------------------

def test_result_frame_past_the_sequence(capsys, tmp_path):
    gt = write(tmp_path / "gt.txt", TINY_GT)
    res = write(tmp_path / "res.txt", [*two_cars(), row(3, 1, "Car", CAR_A[2], score=0.5)])
    message = one_error(capsys, gt, res, "--frames", "3")
    assert message.startswith(f"{res}:7: frame 3 is past the sequence's 3 frames"), message
    assert run_json(capsys, gt, res)["classes"]["car"]["combined"]["fp"] == 1  # 4 frames


def test_result_frame_past_the_layout_length(capsys, tmp_path):
    root = tmp_path / "kitti"
    gt = write(root / "label_02" / "0000.txt", TINY_GT)
    (root / "evaluate_tracking.seqmap").write_text("0000 empty 000000 000003\n")
    results = tmp_path / "results"
    write(results / "0000.txt", [row(3, 1, "Car", CAR_A[2], score=0.5), *two_cars()])
    for argv in ((gt, results / "0000.txt"), (root, results)):
        message = one_error(capsys, *argv)
        assert message.startswith(f"{results / '0000.txt'}:1: frame 3 is past the sequence's "
                                  f"3 frames"), message


def test_one_id_twice_in_a_frame(capsys, tmp_path):
    gt = write(tmp_path / "gt.txt", TINY_GT)
    rows = two_cars()
    rows.insert(4, row(1, 1, "Car", FAR, score=0.5))  # line 5; car 1 is on line 3
    res = write(tmp_path / "res.txt", rows)
    message = one_error(capsys, gt, res)
    expected = f"{res}:5: id 1 appears twice among the Car boxes of frame 1"
    assert message.startswith(expected), message
    assert "lines 3 and 5" in message


def test_one_id_on_a_car_and_a_pedestrian_is_scored_as_trackeval_does(capsys, tmp_path):
    people = [row(t, 5, "Pedestrian", (600, 100, 640, 200)) for t in range(3)]
    gt = write(tmp_path / "gt.txt", [*TINY_GT, *people])
    result = [*two_cars(), *(f"{r.replace(' 5 ', ' 1 ')} 0.9" for r in people)]
    res = write(tmp_path / "res.txt", result)
    report = run_json(capsys, gt, res)
    for cls in CLASSES:
        assert report["classes"][cls]["combined"]["mota"] == 1


def test_classes_refused(capsys, tmp_path):
    gt = write(tmp_path / "gt.txt", TINY_GT)
    res = write(tmp_path / "res.txt", two_cars())
    message = one_error(capsys, gt, res, "--classes", "cyclist")
    assert "car and pedestrian" in message and "'cyclist'" in message
    message = one_error(capsys, gt, res, "--classes", "car,Cyclist")
    assert "'cyclist'" in message
    assert "nothing" in one_error(capsys, gt, res, "--classes", ",")
    assert list(run_json(capsys, gt, res, "--classes", "Pedestrian")["classes"]) == [
        "pedestrian"]


def test_out_dir_refused_under_kitti(capsys, tmp_path):
    gt = write(tmp_path / "gt.txt", TINY_GT)
    res = write(tmp_path / "res.txt", two_cars())
    message = one_error(capsys, gt, res, "--out-dir", tmp_path / "scores")
    assert "--out-dir" in message and "kitti" in message
    assert not (tmp_path / "scores").exists()


def test_gt_folder_with_a_result_file_refused(capsys, tmp_path):
    root = tmp_path / "kitti"
    write(root / "label_02" / "0000.txt", TINY_GT)
    res = write(tmp_path / "res.txt", two_cars())
    message = one_error(capsys, root, res, "--protocol", "kitti")
    assert message.startswith(f"{res}: give two files or two folders"), message
    message = one_error(capsys, root / "label_02" / "0000.txt", tmp_path, "--protocol", "kitti")
    assert "give two files or two folders" in message


def test_missing_result_file_in_folder_mode(capsys, tmp_path):
    root = tmp_path / "kitti"
    write(root / "label_02" / "0000.txt", TINY_GT)
    write(root / "label_02" / "0001.txt", TINY_GT)
    results = tmp_path / "results"
    write(results / "0000.txt", two_cars())
    message = one_error(capsys, root, results)
    assert message == f"{results / '0001.txt'}: no file for sequence 0001"
    write(results / "0001.txt", two_cars())
    report = run_json(capsys, root, results)
    assert list(report["classes"]["car"]["sequences"]) == ["0000", "0001"]
    assert report["classes"]["car"]["combined"]["fn"] == 0
