"""Evaluation: hand-computed metrics, both protocols, TrackEval and motmetrics run directly,
and the `occtrack eval` command."""

from __future__ import annotations

import contextlib
import io
import json
import os
from pathlib import Path

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.io.mot import read_mot
from occtrack.metrics.clear import clear_mot, clear_mot_motmetrics, iou_distances
from occtrack.metrics.evaluate import KEYS, evaluate, gospa_per_frame
from occtrack.metrics.protocols import scored_frames

# Two pedestrians, three frames. Result: 10 follows pedestrian 1 for two frames, 20 follows
# pedestrian 2 shifted by 2 px (IoU 8/12), 30 is a false box in frame 2, and in frame 3 track 20
# jumps onto pedestrian 1 while pedestrian 2 is not reported.
GT = """\
1,1,0,0,10,10,1,1,1
1,2,100,0,10,10,1,1,1
2,1,2,0,10,10,1,1,1
2,2,100,0,10,10,1,1,1
3,1,4,0,10,10,1,1,1
3,2,100,0,10,10,1,1,1
"""
RESULT = """\
1,10,0,0,10,10,1,-1,-1,-1
1,20,102,0,10,10,1,-1,-1,-1
2,10,2,0,10,10,1,-1,-1,-1
2,20,102,0,10,10,1,-1,-1,-1
2,30,300,0,10,10,1,-1,-1,-1
3,20,4,0,10,10,1,-1,-1,-1
"""

# One frame with every kind of ground truth: a pedestrian (1), a static person (2, class 7)
# and a person on a vehicle (6, class 2) with flag 1, a distractor (3, class 8), an unconsidered
# pedestrian (4, flag 0) and an occluder (5, class 11). The result puts a box on each, one far
# away (17) and one beside the distractor at IoU 1/3 (18).
DISTRACTOR_GT = """\
1,1,0,0,10,10,1,1,1
1,2,100,0,10,10,1,7,1
1,3,200,0,10,10,0,8,1
1,4,300,0,10,10,0,1,1
1,5,400,0,10,10,0,11,1
1,6,500,0,10,10,1,2,1
"""
DISTRACTOR_RESULT = """\
1,11,0,0,10,10,1,-1,-1,-1
1,12,100,0,10,10,1,-1,-1,-1
1,13,200,0,10,10,1,-1,-1,-1
1,14,300,0,10,10,1,-1,-1,-1
1,15,400,0,10,10,1,-1,-1,-1
1,16,500,0,10,10,1,-1,-1,-1
1,17,900,0,10,10,1,-1,-1,-1
1,18,205,0,10,10,1,-1,-1,-1
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(text.encode())
    return path


def tables(tmp_path, gt=GT, result=RESULT):
    return (read_mot(write(tmp_path, "gt.txt", gt), "gt"),
            read_mot(write(tmp_path, "result.txt", result), "result"))


def approx(values: dict) -> dict:
    return {k: pytest.approx(v, rel=1e-12, abs=1e-12) if isinstance(v, float) else v
            for k, v in values.items()}


def test_hand_computed_mot17(tmp_path):
    gt, result = tables(tmp_path)
    # TP 5 (IoU 1, 2/3, 1, 2/3, 1), FP 1 (track 30), FN 1 (pedestrian 2 in frame 3), IDSW 1
    # (pedestrian 1: track 10 then 20). IDTP 4 (1-10 and 2-20 for two frames each).
    values = evaluate(gt, result, "mot17")
    assert 0 < values.pop("hota") < 1  # equal to TrackEval's: see the tests below
    assert values == approx({
        "mota": 1 - 3 / 6, "motp": (3 + 4 / 3) / 5, "idf1": 8 / 12,
        "mostly_tracked": 1, "mostly_lost": 0, "fp": 1, "fn": 1, "id_switches": 1,
        "gospa": 1 / 3 + (1 / 3 + 1 / 2) + 1 / 2, "cardinality_error": 0.0})
    np.testing.assert_allclose(gospa_per_frame(gt, result, "mot17"), [1 / 3, 5 / 6, 1 / 2])


def test_hand_computed_paper_roles_swapped_any_pair(tmp_path):
    gt, result = tables(tmp_path)
    # Objects are the six result boxes, hypotheses the ground truth. Frame 3: track 20 keeps its
    # pedestrian 2 although the boxes do not overlap (distance 1 <= 1), so no switch; the
    # unmatched pedestrian 1 is a false positive, track 30 in frame 2 a miss.
    # MOTA 1 - (1 + 0 + 1) / 6; MOTP (0 + 1/3 + 0 + 1/3 + 1) / 5; tracks 10 and 20 mostly
    # tracked, 30 mostly lost; IDTP 5 of 6 + 6 boxes.
    assert evaluate(gt, result, "paper") == approx({
        "mota": 2 / 3, "motp": 1 / 3, "idf1": 10 / 12, "hota": None,
        "mostly_tracked": 2, "mostly_lost": 1, "fp": 1, "fn": 1, "id_switches": 0,
        "gospa": 5 / 3, "cardinality_error": 0.0})
    np.testing.assert_allclose(gospa_per_frame(gt, result, "paper"), [1 / 3, 5 / 6, 1 / 2])


def test_distractor_classes_under_both_protocols(tmp_path):
    gt, result = tables(tmp_path, DISTRACTOR_GT, DISTRACTOR_RESULT)
    # mot17: boxes on classes 7, 8 and 2 are removed; the ones on the unconsidered pedestrian,
    # the occluder, far away and beside the distractor (IoU 1/3 < 0.5) stay as false positives.
    frames = scored_frames(gt, result, "mot17")
    assert gt.id[frames.truth_rows[0]].tolist() == [1]
    assert result.id[frames.estimate_rows[0]].tolist() == [11, 14, 15, 17, 18]
    mot17 = evaluate(gt, result, "mot17")
    assert {k: mot17[k] for k in ("mota", "fp", "fn", "mostly_tracked", "id_switches")} == {
        "mota": -3.0, "fp": 4, "fn": 0, "mostly_tracked": 1, "id_switches": 0}
    assert mot17["gospa"] == pytest.approx(4 * 0.5)
    assert mot17["cardinality_error"] == pytest.approx(5 / 1 - 1)
    # paper: truth is flag 1 and class 1, 2 or 7 (ids 1, 2, 6); all eight result boxes count.
    frames = scored_frames(gt, result, "paper")
    assert gt.id[frames.truth_rows[0]].tolist() == [1, 2, 6]
    assert len(frames.estimate_rows[0]) == 8
    assert evaluate(gt, result, "paper") == approx({
        "mota": 1 - 5 / 8, "motp": 0.0, "idf1": 6 / 11, "hota": None,
        "mostly_tracked": 3, "mostly_lost": 5, "fp": 0, "fn": 5, "id_switches": 0,
        "gospa": 5 * 0.5, "cardinality_error": 8 / 3 - 1})


def random_sequence(rng: np.random.Generator, frames: int = 40):
    """Ground truth with walking pedestrians, a few distractors and flag-0 rows; a result with
    noisy boxes, dropped boxes, swapped ids, false boxes and boxes on distractors."""
    gt_rows, res_rows = [], []
    starts = rng.uniform(0, 300, (12, 2))
    velocity = rng.normal(0, 3, (12, 2))
    classes = np.array([1] * 8 + [7, 8, 2, 1])
    flags = np.array([1] * 8 + [0, 0, 1, 0])
    for f in range(1, frames + 1):
        for k in range(12):
            if rng.random() < 0.1:
                continue
            left, top = starts[k] + f * velocity[k]
            gt_rows.append((f, k + 1, left, top, 20, 40, flags[k], classes[k], 1))
            if rng.random() < 0.75:
                track = k + 1 + (100 if (k % 4 == 0 and f > frames // 2) else 0)
                noisy = np.array([left, top]) + rng.normal(0, 4, 2)
                res_rows.append((f, track, *noisy, 20 * rng.uniform(0.8, 1.2), 40, 1, -1, -1))
        for extra in range(rng.poisson(1.0)):
            res_rows.append((f, 500 + extra, *rng.uniform(0, 300, 2), 20, 40, 1, -1, -1))
    fmt = "{:d},{:d},{!r},{!r},{!r},{!r},{:d},{:d},{:d}\n"
    gt = "".join(fmt.format(r[0], r[1], float(r[2]), float(r[3]), float(r[4]), float(r[5]),
                            int(r[6]), int(r[7]), int(r[8])) for r in gt_rows)
    res = "".join(fmt.format(r[0], r[1], float(r[2]), float(r[3]), float(r[4]), float(r[5]),
                             int(r[6]), int(r[7]), int(r[8])) for r in res_rows)
    return gt, res


def run_trackeval(folder: Path, gt_text: str, result_text: str, num_frames: int,
                  write_files: bool = False) -> dict:
    """TrackEval's own Evaluator on a MOTChallenge folder layout, nothing of occtrack's (its
    run_mot_challenge.py metrics: HOTA, CLEAR, Identity); `write_files` lets it write its
    summary and detailed files under folder/out/T. Returns its results of the sequence."""
    import trackeval

    write(folder, "gt/SEQ/gt/gt.txt", gt_text)
    write(folder, "gt/SEQ/seqinfo.ini", f"[Sequence]\nname=SEQ\nseqLength={num_frames}\n")
    write(folder, "trackers/T/data/SEQ.txt", result_text)
    evaluator = trackeval.Evaluator({
        "PRINT_RESULTS": False, "PRINT_CONFIG": False, "TIME_PROGRESS": False,
        "OUTPUT_SUMMARY": write_files, "OUTPUT_DETAILED": write_files, "PLOT_CURVES": False,
        "LOG_ON_ERROR": None})
    dataset = trackeval.datasets.MotChallenge2DBox({
        "GT_FOLDER": str(folder / "gt"), "TRACKERS_FOLDER": str(folder / "trackers"),
        "OUTPUT_FOLDER": str(folder / "out"), "SEQ_INFO": {"SEQ": None},
        "SKIP_SPLIT_FOL": True, "TRACKERS_TO_EVAL": ["T"], "PRINT_CONFIG": False})
    metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
               trackeval.metrics.Identity({"PRINT_CONFIG": False})]
    with contextlib.redirect_stdout(io.StringIO()):
        results, _ = evaluator.evaluate([dataset], metrics)
    return results["MotChallenge2DBox"]["T"]["SEQ"]["pedestrian"]


def trackeval_directly(folder: Path, gt_text: str, result_text: str, num_frames: int) -> dict:
    """TrackEval's scores, in `evaluate`'s keys."""
    r = run_trackeval(folder, gt_text, result_text, num_frames)
    clear = r["CLEAR"]
    return {"mota": clear["MOTA"], "motp": clear["MOTP"], "idf1": r["Identity"]["IDF1"],
            "hota": np.mean(r["HOTA"]["HOTA"]), "mostly_tracked": clear["MT"],
            "mostly_lost": clear["ML"], "fp": clear["CLR_FP"], "fn": clear["CLR_FN"],
            "id_switches": clear["IDSW"]}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mot17_equals_trackeval_run_directly(tmp_path, seed):
    gt_text, result_text = random_sequence(np.random.default_rng(seed))
    expected = trackeval_directly(tmp_path / "te", gt_text, result_text, 40)
    gt, result = tables(tmp_path, gt_text, result_text)
    ours = evaluate(gt, result, "mot17", num_frames=40)
    assert {k: ours[k] for k in expected} == expected
    assert not (tmp_path / "te" / "out").exists()


def test_hand_made_pairs_equal_trackeval_run_directly(tmp_path):
    for name, (g, r) in {"a": (GT, RESULT), "b": (DISTRACTOR_GT, DISTRACTOR_RESULT)}.items():
        gt, result = tables(tmp_path / name, g, r)
        ours = evaluate(gt, result, "mot17")
        expected = trackeval_directly(tmp_path / name / "te", g, r, gt.num_frames)
        assert {k: ours[k] for k in expected} == expected


def random_clear_problem(rng: np.random.Generator, any_pair: bool):
    objects, hypotheses, distances = [], [], []
    for _ in range(30):
        o = rng.choice(12, rng.integers(0, 7), replace=False)
        h = rng.choice(9, rng.integers(0, 7), replace=False)
        pos_o, pos_h = rng.uniform(0, 60, (len(o), 2)), rng.uniform(0, 60, (len(h), 2))
        boxes_o = np.column_stack([pos_o, np.full((len(o), 2), 20.0)])
        boxes_h = np.column_stack([pos_h, np.full((len(h), 2), 20.0)])
        distances.append(iou_distances(boxes_o, boxes_h, 1.0 if any_pair else 0.5))
        objects.append(o)
        hypotheses.append(h)
    return objects, hypotheses, distances


@pytest.mark.parametrize("any_pair", [True, False])
def test_clear_port_equals_motmetrics(any_pair):
    rng = np.random.default_rng(5 + any_pair)
    for _ in range(6):
        problem = random_clear_problem(rng, any_pair)
        assert clear_mot(*problem) == clear_mot_motmetrics(*problem)


def test_paper_equals_motmetrics_run_as_the_authors_script(tmp_path):
    gt_text, result_text = random_sequence(np.random.default_rng(9))
    gt, result = tables(tmp_path, gt_text, result_text)
    frames = scored_frames(gt, result, "paper")
    objects = [result.id[r] for r in frames.estimate_rows]
    hypotheses = [gt.id[r] for r in frames.truth_rows]
    distances = [iou_distances(result.box[e], gt.box[t], 1.0)
                 for e, t in zip(frames.estimate_rows, frames.truth_rows, strict=True)]
    reference = clear_mot_motmetrics(objects, hypotheses, distances)
    ours = evaluate(gt, result, "paper")
    assert ours["mota"] == reference.mota and ours["motp"] == reference.motp
    assert ours["idf1"] == reference.idf1
    assert (ours["fp"], ours["fn"]) == (reference.idfp, reference.idfn)
    assert (ours["mostly_tracked"], ours["mostly_lost"], ours["id_switches"]) == (
        reference.mostly_tracked, reference.mostly_lost, reference.num_switches)


def test_gospa_per_frame_sums_to_the_total(tmp_path):
    gt_text, result_text = random_sequence(np.random.default_rng(4))
    gt, result = tables(tmp_path, gt_text, result_text)
    for protocol in ("paper", "mot17"):
        per_frame = gospa_per_frame(gt, result, protocol, num_frames=45)
        assert per_frame.shape == (45,) and (per_frame[40:] == 0).all()
        assert per_frame.sum() == pytest.approx(evaluate(gt, result, protocol, 45)["gospa"])


def test_empty_result(tmp_path):
    gt, result = tables(tmp_path, GT, "")
    mot17 = evaluate(gt, result, "mot17")
    assert (mot17["mota"], mot17["fn"], mot17["fp"], mot17["mostly_lost"]) == (0.0, 6, 0, 2)
    assert mot17["gospa"] == pytest.approx(6 * 0.5)
    assert mot17["cardinality_error"] == -1.0
    paper = evaluate(gt, result, "paper")
    assert paper["mota"] is None and paper["fp"] == 6 and paper["fn"] == 0


@pytest.mark.parametrize("gt,message", [
    ("", "ground truth has no rows, so the metrics are undefined"),
    # a distractor (class 8) and an unconsidered pedestrian (flag 0): neither protocol scores
    ("1,3,200,0,10,10,0,8,1\n1,4,0,0,10,10,0,1,1\n",
     "none of the ground truth's 2 rows is a box the {protocol} protocol scores"),
])
def test_ground_truth_with_nothing_to_score_is_undefined_not_zero(tmp_path, capsys, gt,
                                                                  message):
    gt_table, result = tables(tmp_path, gt, RESULT)
    for protocol in ("paper", "mot17"):
        expected = message.format(protocol=protocol)
        with pytest.raises(OcctrackError, match=expected) as err:
            evaluate(gt_table, result, protocol, num_frames=3)
        assert str(err.value).startswith(f"{tmp_path / 'gt.txt'}: ")
        for json_flag in ((), ("--json",)):
            code, out, err_text = run_cli(capsys, tmp_path / "gt.txt", tmp_path / "result.txt",
                                          "--protocol", protocol, *json_flag)
            assert code == 1 and out == ""
            assert err_text.startswith(f"occtrack eval: error: {tmp_path / 'gt.txt'}: "
                                       f"{expected}")
            assert err_text.count("\n") == 1 and "scored box" in err_text


@pytest.mark.parametrize("result,message", [
    ("1,10,0,0,10,10,1\n1,10,5,0,10,10,1\n", "result has id 10 twice in frame 1"),
    ("1,-1,0,0,10,10,0.9\n", "negative id -1 in frame 1 (a detection file?"),
    ("9,10,0,0,10,10,1\n", "result has frame 9 but the sequence has 3 frames"),
])
def test_bad_results_are_refused(tmp_path, result, message):
    gt, result = tables(tmp_path, GT, result)
    for protocol in ("paper", "mot17"):
        with pytest.raises(OcctrackError, match=message.replace("(", r"\(")):
            evaluate(gt, result, protocol, num_frames=3)


def test_ground_truth_without_classes_is_refused(tmp_path):
    gt, result = tables(tmp_path, "1,1,0,0,10,10\n", RESULT)
    with pytest.raises(OcctrackError, match="class -1 in frame 1"):
        evaluate(gt, result, "mot17")


def test_unknown_protocol(tmp_path):
    gt, result = tables(tmp_path)
    with pytest.raises(OcctrackError, match="unknown protocol 'mot16'"):
        evaluate(gt, result, "mot16")


# --- the command ---------------------------------------------------------------------------

def run_cli(capsys, *argv):
    code = main(["eval", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_table_and_json(tmp_path, capsys):
    gt = write(tmp_path, "gt.txt", GT)
    result = write(tmp_path, "result.txt", RESULT)
    code, out, err = run_cli(capsys, gt, result)
    assert code == 0 and err == ""
    assert "protocol mot17" in out and "MOTA" in out and "0.5000" in out
    assert "scored 3 frames, 6 true boxes, 6 result boxes" in out
    for protocol in ("paper", "mot17"):
        code, out, _ = run_cli(capsys, gt, result, "--protocol", protocol, "--json")
        values = json.loads(out)
        assert code == 0 and list(values) == list(KEYS)
        assert all(v is None or type(v) in (int, float) for v in values.values())
        assert (values["hota"] is None) == (protocol == "paper")
        assert values == approx(evaluate(read_mot(gt, "gt"), read_mot(result, "result"),
                                         protocol))


def test_cli_reads_files_from_other_trackers(tmp_path, capsys):
    gt = write(tmp_path, "gt.txt", GT)
    clean = write(tmp_path, "clean.txt", RESULT)
    messy_text = "".join(
        f"{f}.0,{i}.0,{rest},-1,-1,-1,0.5,extra\r\n"
        for f, i, rest in (line.split(",", 2) for line in RESULT.replace(",-1,-1,-1", "")
                           .splitlines()))
    messy = write(tmp_path, "messy.txt", messy_text)
    assert messy.read_bytes().count(b"\r\n") == 6
    for protocol in ("paper", "mot17"):
        expected = run_cli(capsys, gt, clean, "--protocol", protocol, "--json")[1]
        assert run_cli(capsys, gt, messy, "--protocol", protocol, "--json")[1] == expected


def test_cli_seqinfo_length_and_errors(tmp_path, capsys):
    gt = write(tmp_path, "SEQ/gt/gt.txt", GT)
    write(tmp_path, "SEQ/seqinfo.ini", "[Sequence]\nname=SEQ\nimWidth=640\nimHeight=480\n"
                                       "seqLength=2\nframeRate=30\n")
    result = write(tmp_path, "result.txt", RESULT)
    code, _, err = run_cli(capsys, gt, result)
    assert code == 1
    assert err.startswith("occtrack eval: error: ") and "frame 3 but the sequence has 2" in err
    assert err.count("\n") == 1

    code, _, err = run_cli(capsys, gt, tmp_path / "missing.txt")
    assert code == 1 and err == f"occtrack eval: error: {tmp_path / 'missing.txt'}: no such file\n"

    bad = write(tmp_path, "bad.txt", "1,10,0,0,10,10,1\n2,10,0,zero,10,10,1\n")
    code, _, err = run_cli(capsys, gt, bad)
    assert code == 1 and f"{bad}:2: column 4 is not a number" in err

    code, _, err = run_cli(capsys, gt, result, "--frames", "0")
    assert code == 1 and "--frames must be at least 1" in err

    with pytest.raises(SystemExit) as exit_:
        run_cli(capsys, gt, result, "--protocol", "mot16")
    assert exit_.value.code == 2


def test_cli_help_says_how_each_protocol_scores(capsys):
    with pytest.raises(SystemExit):
        main(["eval", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for phrase in ("ANY pair may match, even two boxes that do not overlap",
                   "RESULT boxes as its objects and the GROUND TRUTH as its hypotheses",
                   "LOWER is better", "HIGHER is better", "TrackEval's own numbers",
                   "mot17 pedestrian set (class 1, flag 1)", "c = 1, p = 1, alpha = 2"):
        assert phrase in text


def test_mot17_04_ground_truth_against_itself(capsys, mot17_04_gt):
    code, out, err = run_cli(capsys, mot17_04_gt, mot17_04_gt, "--json")
    values = json.loads(out)
    assert code == 0 and "not scored" in err
    assert (values["mota"], values["idf1"], values["hota"], values["motp"]) == (1.0, 1.0, 1.0,
                                                                                1.0)
    assert (values["fp"], values["fn"], values["id_switches"], values["mostly_tracked"]) == (
        0, 0, 0, 83)
    assert values["gospa"] == 0.0 and values["cardinality_error"] == 0.0
    gt = read_mot(mot17_04_gt, "gt")
    paper = evaluate(gt, gt, "paper", num_frames=1050)
    assert (paper["mota"], paper["motp"], paper["idf1"], paper["gospa"]) == (1.0, 0.0, 1.0, 0.0)


def test_no_files_written_outside_tmp(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    gt = write(tmp_path, "gt.txt", GT)
    result = write(tmp_path, "result.txt", RESULT)
    before = sorted(os.listdir(tmp_path))
    assert run_cli(capsys, gt, result)[0] == 0
    assert sorted(os.listdir(tmp_path)) == before


# --- TrackEval's own output files ------------------------------------------------------------


def trackeval_files_directly(folder: Path, gt_text: str, result_text: str,
                             num_frames: int) -> dict[str, bytes]:
    """The summary and detailed files TrackEval's Evaluator writes itself (its
    run_mot_challenge.py metrics: HOTA, CLEAR, Identity, and Count, which it adds)."""
    run_trackeval(folder, gt_text, result_text, num_frames, write_files=True)
    out = folder / "out" / "T"
    return {name: (out / name).read_bytes()
            for name in ("pedestrian_summary.txt", "pedestrian_detailed.csv")}


@pytest.mark.parametrize("seed", [0, 1])
def test_out_dir_files_equal_trackevals_own(tmp_path, capsys, seed):
    gt_text, result_text = random_sequence(np.random.default_rng(seed))
    expected = trackeval_files_directly(tmp_path / "te", gt_text, result_text, 40)
    gt = write(tmp_path, "ours/SEQ/gt/gt.txt", gt_text)
    write(tmp_path, "ours/SEQ/seqinfo.ini", "[Sequence]\nname=SEQ\nimDir=img1\nframeRate=30\n"
          "seqLength=40\nimWidth=640\nimHeight=480\nimExt=.jpg\n")
    result = write(tmp_path, "result.txt", result_text)
    out = tmp_path / "scores"
    code, text, err = run_cli(capsys, gt, result, "--out-dir", out)
    assert code == 0 and err == "" and "pedestrian_summary.txt" in text
    for name, content in expected.items():
        assert (out / name).read_bytes() == content
    header, values = expected["pedestrian_summary.txt"].decode().split("\r\n")[:2]
    for field in ("HOTA", "DetA", "AssA", "LocA", "IDF1", "IDP", "IDR", "Frag", "MOTA"):
        assert field in header.split(" ")
    # the files exist now: replaced only with --force; '-' prints the summary alone
    assert run_cli(capsys, gt, result, "--out-dir", out)[0] == 1
    assert run_cli(capsys, gt, result, "--out-dir", out, "--force")[0] == 0
    code, text, err = run_cli(capsys, gt, result, "--out-dir", "-")
    assert code == 0 and text.encode() == expected["pedestrian_summary.txt"]


def test_out_dir_needs_mot17_and_a_folder(tmp_path, capsys):
    gt = write(tmp_path, "gt.txt", GT)
    result = write(tmp_path, "result.txt", RESULT)
    code, _, err = run_cli(capsys, gt, result, "--protocol", "paper", "--out-dir", tmp_path)
    assert code == 1 and "mot17" in err
    code, _, err = run_cli(capsys, gt, result, "--out-dir", result)
    assert code == 1 and "folder" in err
    code, _, err = run_cli(capsys, gt, result, "--out-dir", "-", "--json")
    assert code == 1 and "standard output" in err
