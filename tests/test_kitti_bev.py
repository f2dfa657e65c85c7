"""The kitti-bev protocol of `occtrack eval`: KITTI 3D results scored on the ground plane with
TrackEval's HOTA, CLEAR and Identity and the similarity max(0, 1 - d / 2 m). Hand-made
sequences with answers worked out by hand (a perfect result, every centre 1 m off, ids swapped
halfway, distractors, two sequences combined), the errors named by file and line, and a run on
real KITTI sequences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.kitti import read_kitti
from occtrack.metrics import kitti_bev
from occtrack.metrics.hota_points import point_hota
from occtrack.metrics.trackeval_mot17 import sequence_results
from test_eval_kitti import one_error, run, run_json, write

FRAMES = 10
ALPHAS = 19  # TrackEval's HOTA thresholds 0.05 .. 0.95
MATCHED_AT_HALF = 10  # thresholds <= 0.5: a pair 1 m apart (similarity 0.5) counts at these


def row3d(frame, ident, kind, x, z, truncated=0, occluded=0, score=0.9) -> str:
    """One KITTI row with a 3D box centred at (x, z) on the ground plane (the 2D box and the
    box's size are placeholders); score=None writes 17 columns, as a label file has."""
    text = (f"{frame} {ident} {kind} {truncated} {occluded} -1.5 100.00 100.00 200.00 200.00 "
            f"1.5 1.6 3.9 {x!r} 1.5 {z!r} 0.0")
    return text if score is None else f"{text} {score}"


def objects() -> list[tuple]:
    """(id, type, x, z at frame t) of the true objects, far apart (tens of metres)."""
    return [(1, "Car", lambda t: 0.5 * t, lambda t: 10.0),
            (2, "Car", lambda t: 20.0, lambda t: 30.0 - 0.25 * t),
            (3, "Pedestrian", lambda t: -15.0, lambda t: 8.0 + 0.125 * t)]


def truth_rows(extra=()) -> list[str]:
    rows = [row3d(t, i, kind, x(t), z(t), score=None)
            for t in range(FRAMES) for i, kind, x, z in objects()]
    rows += [f"{t} -1 DontCare -1 -1 -10 5.00 5.00 50.00 50.00 -1000 -1000 -1000 -10 -1 -1 -1"
             for t in range(FRAMES)]
    return rows + list(extra)


def result_rows(shift=0.0, swap_from=None, extra=()) -> list[str]:
    """The truth as a result, every centre `shift` m to the right; from frame `swap_from` on
    the two cars' ids swapped."""
    rows = []
    for t in range(FRAMES):
        for i, kind, x, z in objects():
            if swap_from is not None and t >= swap_from and kind == "Car":
                i = 3 - i
            rows.append(row3d(t, i, kind, x(t) + shift, z(t)))
    return rows + list(extra)


def score(capsys, folder: Path, truth, result, *args) -> dict:
    """`occtrack eval --protocol kitti-bev --json` on the rows given, as sequence 0000."""
    gt = write(folder / "gt" / "0000.txt", truth)
    res = write(folder / "res" / "0000.txt", result)
    return run_json(capsys, gt, res, "--protocol", "kitti-bev", *args)


def values(report, cls="car", seq="0000") -> dict:
    return report["classes"][cls]["sequences"][seq]


def test_the_truth_as_result_scores_one(tmp_path, capsys):
    report = score(capsys, tmp_path, truth_rows(), result_rows())
    assert report["protocol"] == "kitti-bev" and report["distance"] == 2.0
    assert list(report["classes"]) == ["car", "pedestrian"]
    for cls in ("car", "pedestrian"):
        got = values(report, cls)
        for key in ("hota", "deta", "assa", "loca", "mota", "idf1", "motp"):
            assert got[key] == pytest.approx(1.0, abs=1e-12), key
        assert (got["fp"], got["fn"], got["id_switches"]) == (0, 0, 0)
    assert values(report, "car")["mostly_tracked"] == 2
    assert values(report, "pedestrian")["mostly_tracked"] == 1


def test_one_metre_off_matches_at_half_the_thresholds(tmp_path, capsys):
    """Similarity 1 - 1/2 = 0.5: a pair at the thresholds 0.05 .. 0.5 (10 of 19), none above.
    Where matched, DetA = AssA = 1 and LocA = 0.5; where not, DetA = AssA = 0 and TrackEval
    makes LocA 1 (no match to localise). CLEAR and Identity match at similarity 0.5."""
    report = score(capsys, tmp_path, truth_rows(), result_rows(shift=1.0))
    for cls in ("car", "pedestrian"):
        got = values(report, cls)
        assert got["deta"] == pytest.approx(MATCHED_AT_HALF / ALPHAS, abs=1e-12)
        assert got["assa"] == pytest.approx(MATCHED_AT_HALF / ALPHAS, abs=1e-12)
        assert got["hota"] == pytest.approx(MATCHED_AT_HALF / ALPHAS, abs=1e-12)
        loca = (MATCHED_AT_HALF * 0.5 + (ALPHAS - MATCHED_AT_HALF) * 1.0) / ALPHAS
        assert got["loca"] == pytest.approx(loca, abs=1e-12)
        assert got["mota"] == 1.0 and got["idf1"] == 1.0
        assert got["motp"] == pytest.approx(0.5, abs=1e-12)
    # LocA per threshold: 0.5 wherever the pairs count
    gt, res = read_kitti(tmp_path / "gt" / "0000.txt"), read_kitti(tmp_path / "res" / "0000.txt")
    hota = sequence_results(kitti_bev.scored_frames(gt, res, FRAMES)["car"].trackeval)["HOTA"]
    assert np.allclose(hota["LocA"][:MATCHED_AT_HALF], 0.5, rtol=0, atol=1e-12)
    assert np.array_equal(hota["HOTA_TP"][MATCHED_AT_HALF:], np.zeros(ALPHAS - MATCHED_AT_HALF))


def test_ids_swapped_halfway(tmp_path, capsys):
    """Two cars, ids swapped from frame 5: each true track switches once (IDSW 2). Each true id
    shares 5 of its 10 frames with each result id, so each of the 4 pairs has
    A = 5 / (10 + 10 - 5) = 1/3 and AssA = 1/3; IDF1 matches 5 + 5 of 20 boxes: 0.5."""
    report = score(capsys, tmp_path, truth_rows(), result_rows(swap_from=5))
    car = values(report, "car")
    assert car["id_switches"] == 2
    assert car["deta"] == pytest.approx(1.0, abs=1e-12)
    assert car["assa"] == pytest.approx(1 / 3, abs=1e-12)
    assert car["hota"] == pytest.approx(np.sqrt(1 / 3), abs=1e-12)
    assert car["mota"] == pytest.approx(1 - 2 / 20, abs=1e-12)
    assert car["idf1"] == pytest.approx(0.5, abs=1e-12)
    assert values(report, "pedestrian")["hota"] == pytest.approx(1.0, abs=1e-12)


def test_matches_to_distractors_are_not_false(tmp_path, capsys):
    """A van, a sitting person and a truncated car in the truth; result rows of the class
    within 1 m of them are removed (not false), a car 1.5 m from the van is false, and the
    van does not shield a pedestrian: distractors are a class's own."""
    truth = truth_rows([row3d(t, kind_id, kind, x, 50.0, truncated, score=None)
                        for t in range(FRAMES)
                        for kind_id, kind, x, truncated in ((10, "Van", 5.0, 0),
                                                            (11, "Person_sitting", -5.0, 0),
                                                            (12, "Car", 15.0, 1))])
    near = [row3d(t, 100 + k, kind, x + 0.75, 50.0) for t in range(FRAMES)
            for k, (kind, x) in enumerate((("Car", 5.0), ("Pedestrian", -5.0), ("Car", 15.0)))]
    far = [row3d(t, 200, "Car", 6.5, 50.0) for t in range(FRAMES)]
    other = [row3d(t, 300, "Pedestrian", 5.25, 50.0) for t in range(FRAMES)]
    clean = score(capsys, tmp_path / "a", truth, result_rows())
    shielded = score(capsys, tmp_path / "b", truth, result_rows(extra=near))
    assert shielded["classes"] == clean["classes"]
    for cls in ("car", "pedestrian"):
        assert values(shielded, cls)["hota"] == pytest.approx(1.0, abs=1e-12)
    unshielded = score(capsys, tmp_path / "c", truth, result_rows(extra=near + far + other))
    assert values(unshielded, "car")["fp"] == FRAMES
    assert values(unshielded, "pedestrian")["fp"] == FRAMES
    assert values(unshielded, "car")["fn"] == values(unshielded, "pedestrian")["fn"] == 0


def test_one_assignment_over_the_class_and_its_distractors(tmp_path, capsys):
    """A true car at x = 0 and a van at 1.5 m; result cars at 0.2 and 0.7. The one Hungarian
    assignment Kitti2DBox makes gives 0.2 to the car and 0.7 to the van (similarity
    0.9 + 0.6 beats 0.65 + 0, the van 1.3 m from 0.2), so 0.7 is removed though it is nearer
    the car than the van: no false row, and CLEAR's match is 0.2 m off."""
    truth = [row3d(t, 1, "Car", 0.0, 10.0, score=None) for t in range(FRAMES)]
    truth += [row3d(t, 2, "Van", 1.5, 10.0, score=None) for t in range(FRAMES)]
    result = [row3d(t, i, "Car", x, 10.0) for t in range(FRAMES) for i, x in ((1, 0.2),
                                                                             (2, 0.7))]
    car = values(score(capsys, tmp_path, truth, result, "--classes", "car"), "car")
    assert (car["fp"], car["fn"], car["id_switches"]) == (0, 0, 0)
    assert car["motp"] == pytest.approx(1 - 0.2 / 2, abs=1e-12)


def test_true_rows_without_3d_are_left_out_with_a_note(tmp_path, capsys):
    missing = [f"{t} 9 Car 0 0 -10 300.00 100.00 400.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10"
               for t in range(FRAMES)]
    gt = write(tmp_path / "gt.txt", truth_rows(missing))
    res = write(tmp_path / "res.txt", result_rows())
    code, out, err = run(capsys, gt, res, "--protocol", "kitti-bev", "--json")
    assert code == 0
    first = len(truth_rows()) + 1
    assert f"{FRAMES} true rows without a 3D box, first at line {first}, not scored" in err
    assert values(run_json(capsys, gt, res, "--protocol", "kitti-bev"), "car", "gt")[
        "hota"] == pytest.approx(1.0, abs=1e-12)


def test_a_result_row_without_3d_is_refused_with_file_and_line(tmp_path, capsys):
    bad = "4 7 Car -1 -1 -10 300.00 100.00 400.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.5"
    rows = result_rows()
    rows.insert(6, bad)
    gt = write(tmp_path / "gt.txt", truth_rows())
    res = write(tmp_path / "res.txt", rows)
    with pytest.raises(OcctrackError) as caught:
        kitti_bev.evaluate([("0000", gt, res)])
    assert (caught.value.path, caught.value.line) == (str(res), 7)
    message = one_error(capsys, gt, res, "--protocol", "kitti-bev")
    assert message.startswith(f"{res}:7: Car row without a 3D box")
    assert "--protocol kitti" in message
    # a class not scored may be 2D only; so may every row under --classes pedestrian
    rows[6] = bad.replace(" Car ", " Cyclist ")
    write(res, rows)
    assert run_json(capsys, gt, res, "--protocol", "kitti-bev")["classes"]["car"]
    rows[6] = bad
    write(res, rows)
    assert run_json(capsys, gt, res, "--protocol", "kitti-bev", "--classes", "pedestrian")


def test_cli_errors_are_one_line(tmp_path, capsys):
    gt = write(tmp_path / "gt.txt", truth_rows())
    res = write(tmp_path / "res.txt", result_rows())
    assert "--out-dir" in one_error(capsys, gt, res, "--protocol", "kitti-bev", "--out-dir",
                                    tmp_path / "out")
    assert "car and pedestrian" in one_error(capsys, gt, res, "--protocol", "kitti-bev",
                                             "--classes", "van")
    late = write(tmp_path / "late.txt", [*result_rows(), row3d(12, 1, "Car", 0.0, 10.0)])
    assert one_error(capsys, gt, late, "--protocol", "kitti-bev", "--frames", "10").startswith(
        f"{late}:{len(result_rows()) + 1}: frame 12 is past")
    assert "--classes picks KITTI's classes; use --protocol kitti or kitti-bev" in one_error(
        capsys, gt, res, "--protocol", "mot17", "--classes", "car")


def test_two_sequences_combined_as_trackeval_combines_them(tmp_path, capsys):
    """0000 perfect, 0001 every centre 1 m off, the same boxes: above threshold 0.5 only
    0000's n pairs count against 0001's n misses and n false rows (DetA 1/3, AssA 1); at and
    below it every pair counts (LocA (1 + 0.5) / 2)."""
    gt, res = tmp_path / "kitti" / "label_02", tmp_path / "results"
    for name in ("0000", "0001"):
        write(gt / f"{name}.txt", truth_rows())
    write(res / "0000.txt", result_rows())
    write(res / "0001.txt", result_rows(shift=1.0))
    report = run_json(capsys, tmp_path / "kitti", res, "--protocol", "kitti-bev")
    high = ALPHAS - MATCHED_AT_HALF
    for cls in ("car", "pedestrian"):
        entry = report["classes"][cls]
        assert list(entry["sequences"]) == ["0000", "0001"]
        combined = entry["combined"]
        assert combined["deta"] == pytest.approx((MATCHED_AT_HALF + high / 3) / ALPHAS,
                                                 abs=1e-12)
        assert combined["assa"] == pytest.approx(1.0, abs=1e-12)
        assert combined["hota"] == pytest.approx(
            (MATCHED_AT_HALF + high * np.sqrt(1 / 3)) / ALPHAS, abs=1e-12)
        assert combined["loca"] == pytest.approx((MATCHED_AT_HALF * 0.75 + high) / ALPHAS,
                                                 abs=1e-12)
        for key in ("fp", "fn", "id_switches"):
            assert combined[key] == sum(s[key] for s in entry["sequences"].values())
    code, out, _ = run(capsys, tmp_path / "kitti", res, "--protocol", "kitti-bev")
    assert code == 0
    assert out.startswith("protocol kitti-bev: KITTI 3D tracking on the ground plane")
    assert "COMBINED" in out and "\ncar\n" in out and "\npedestrian\n" in out


def test_calibration_counts_a_row_right_within_one_metre(tmp_path, capsys):
    gt = write(tmp_path / "gt.txt", truth_rows())
    far = [row3d(t, 50, "Car", 40.0, 40.0, score=0.05) for t in range(FRAMES)]
    res = write(tmp_path / "res.txt", result_rows(shift=0.9, extra=far))
    report = run_json(capsys, gt, res, "--protocol", "kitti-bev", "--calibration")
    table = report["classes"]["car"]["calibration"]
    assert table["boxes"][0] == FRAMES and table["right"][0] == 0.0
    assert table["boxes"][9] == 2 * FRAMES and table["right"][9] == 1.0


def test_scores_are_trackevals_hota_on_the_ground_steps(tmp_path):
    """The HOTA reported is `point_hota` on the preprocessed steps (one HOTA, not two)."""
    gt = read_kitti(write(tmp_path / "gt.txt", truth_rows()))
    res = read_kitti(write(tmp_path / "res.txt", result_rows(shift=0.3, swap_from=4)))
    report = kitti_bev.evaluate([("x", Path(gt.path), Path(res.path))])
    for cls in ("car", "pedestrian"):
        steps, _, _ = kitti_bev.ground_steps(gt, res, FRAMES, cls)
        expected = point_hota(steps, kitti_bev.DISTANCE)
        got = report["classes"][cls]["sequences"]["x"]
        assert (got["hota"], got["deta"], got["assa"], got["loca"]) == (
            expected.hota, expected.deta, expected.assa, expected.loca)


# --- real KITTI sequences ----------------------------------------------------------------------

REAL = ("0000", "0004")


def labels_as_result(labels: Path) -> list[str]:
    rows = [line.split() for line in labels.read_text().splitlines() if line.strip()]
    return [" ".join([*r[:17], "1.0"]) for r in rows if r[2] in ("Car", "Pedestrian")]


def detections_as_result(detections: Path) -> list[str]:
    """A detector's rows made a (poor) tracker's: each row its own id."""
    rows = [line.split() for line in detections.read_text().splitlines() if line.strip()]
    return [" ".join([r[0], str(k), *r[2:]]) for k, r in enumerate(rows)]


def test_real_sequences(kitti_root, tmp_path, capsys):
    """On real labels: the labels as a result score 1; PointRCNN's 3D detections, each row
    its own id, miss few scored cars and put their centres within tens of cm (LocA), but
    carry no identity (AssA, ID switches); the numbers are point_hota's on the same steps."""
    perfect, detected = tmp_path / "perfect", tmp_path / "detected"
    for name in REAL:
        write(perfect / f"{name}.txt", labels_as_result(kitti_root / "label_02" / f"{name}.txt"))
        write(detected / f"{name}.txt",
              detections_as_result(kitti_root / "det_02" / "pointrcnn" / f"{name}.txt"))
    pairs = [(n, kitti_root / "label_02" / f"{n}.txt", perfect / f"{n}.txt") for n in REAL]
    report = kitti_bev.evaluate(pairs)
    for cls in ("car", "pedestrian"):
        for got in (*report["classes"][cls]["sequences"].values(),
                    report["classes"][cls]["combined"]):
            assert got["hota"] == pytest.approx(1.0, abs=1e-12)
            assert (got["fp"], got["fn"], got["id_switches"]) == (0, 0, 0)
    for name in REAL:
        gt_path, res_path = kitti_root / "label_02" / f"{name}.txt", detected / f"{name}.txt"
        got = run_json(capsys, gt_path, res_path, "--protocol", "kitti-bev")
        car = got["classes"]["car"]["sequences"][name]
        gt, res = read_kitti(gt_path), read_kitti(res_path)
        steps, _, _ = kitti_bev.ground_steps(gt, res, max(gt.num_frames, res.num_frames), "car")
        true_cars = sum(len(step[0]) for step in steps)
        assert true_cars > 200
        assert car["fn"] < 0.15 * true_cars and car["loca"] > 0.85, car
        assert car["assa"] < 0.2 and car["id_switches"] > 100, car
        assert car["hota"] == point_hota(steps, kitti_bev.DISTANCE).hota
