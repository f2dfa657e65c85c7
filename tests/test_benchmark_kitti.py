"""`occtrack benchmark` on a KITTI tracking folder: the JSON and tables per class, occtrack's
scores equal to `occtrack track` + `occtrack eval --protocol kitti`, the peers tracking class by
class, the layout's recognition and errors, `occtrack report` on the KITTI JSON, determinism.

Every layout here is built in tmp_path from symlinks to the real KITTI files (never copies):
0000 (154 frames, cars and pedestrians) and 0017 (145 frames, pedestrians only)."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

from occtrack import peers
from occtrack.cli import main
from occtrack.experiments import benchmark_kitti
from occtrack.metrics.reliability import reliability
from occtrack.metrics.trackeval_kitti import (
    CLASS_TYPE,
    CLASSES,
    read_seqmap,
    scored_frames,
    sequence_results,
    summary,
)
from sequences import write_sequence

SEQUENCES = ("0000", "0017")
TRACKERS = ("none", "object-wise", "sort")
FRACTIONS = ("hota", "idf1", "deta", "assa", "loca", "motp", "ece")
COUNTS = ("mostly_tracked", "mostly_lost", "fp", "fn", "id_switches", "tracks")
HEADLINE = ("hota", "mota", "idf1", "fp", "fn", "id_switches")
# scored true boxes (Kitti2DBox: truncation 0, occlusion <= 2), README.md of the KITTI folder
TRUTH = {"0000": {"car": 215, "pedestrian": 19}, "0017": {"car": 0, "pedestrian": 770}}
FRAMES = {"0000": 154, "0017": 145}
IMAGE = {"0000": [1242, 375], "0017": [1224, 370]}
needs_peers = pytest.mark.skipif(not peers.available(),
                                 reason="the peers need `pip install occtrack[peers]`")


def make_layout(kitti_root: Path, folder: Path, names=SEQUENCES, detectors=("rrc",),
                seqinfo=None, seqmap=True, det=True) -> Path:
    """A KITTI folder of symlinks to the real files of `names`: label_02/, det_02/D/ for each
    detector D (the RRC files), seqinfo/ for the sequences in `seqinfo` (default all), and a
    seqmap naming `names` with their real lengths."""
    lengths = read_seqmap(kitti_root / "evaluate_tracking.seqmap")
    for sub in ("label_02", "seqinfo"):
        (folder / sub).mkdir(parents=True)
    for name in names:
        (folder / "label_02" / f"{name}.txt").symlink_to(kitti_root / "label_02" / f"{name}.txt")
        if name in (names if seqinfo is None else seqinfo):
            (folder / "seqinfo" / f"{name}.ini").symlink_to(kitti_root / "seqinfo"
                                                            / f"{name}.ini")
        for detector in detectors if det else ():
            (folder / "det_02" / detector).mkdir(parents=True, exist_ok=True)
            (folder / "det_02" / detector / f"{name}.txt").symlink_to(
                kitti_root / "det_02" / "rrc" / f"{name}.txt")
    if seqmap:
        (folder / "evaluate_tracking.seqmap").write_text(
            "".join(f"{name} empty 000000 {lengths[name]:06d}\n" for name in names))
    return folder


def bench(layout: Path, out: Path, *extra: str, trackers=TRACKERS) -> dict:
    assert main(["benchmark", str(layout), "--sequential", "--trackers", ",".join(trackers),
                 "--json", str(out), "--quiet", *extra]) == 0
    return json.loads(out.read_text())


def error_of(capsys, command: str, *argv: str) -> str:
    """The one error line of a refused command, without its prefix."""
    code = main([command, *argv])
    out, err = capsys.readouterr()
    assert code == 1, (out, err)
    prefix = f"occtrack {command}: error: "
    assert err.startswith(prefix) and err.count("\n") == 1 and "Traceback" not in err, err
    return err[len(prefix):-1]


def without_times(report):
    """The report with the run times (which differ from run to run) left out."""
    if isinstance(report, dict):
        return {k: without_times(v) for k, v in report.items()
                if k not in ("seconds", "frames_per_second")}
    if isinstance(report, list):
        return [without_times(v) for v in report]
    return report


@pytest.fixture(scope="module")
def layout(kitti_root, tmp_path_factory) -> Path:
    return make_layout(kitti_root, tmp_path_factory.mktemp("kitti") / "layout")


@pytest.fixture(scope="module")
def run(layout, tmp_path_factory):
    """The benchmark on 0000 and 0017: the JSON written and the tables printed."""
    if not peers.available():
        pytest.skip("the peers need `pip install occtrack[peers]`")
    out = tmp_path_factory.mktemp("out") / "k.json"
    argv = ["benchmark", str(layout), "--sequential", "--trackers", ",".join(TRACKERS),
            "--json", str(out), "--quiet"]
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):  # the tables go to stdout: catch them
        assert main(argv) == 0
    return out, json.loads(out.read_text()), buffer.getvalue()


# --- 1. the JSON and the tables -----------------------------------------------------------


def test_json_shape_per_sequence_per_class(run, layout):
    _, report, _ = run
    assert report["protocol"] == "kitti" and report["layout"] == "kitti"
    assert report["detections"] == "rrc"
    assert report["folder"] == str(layout.resolve())
    assert report["trackers"] == list(TRACKERS)
    assert report["classes"] == list(CLASSES)
    assert list(report["sequences"]) == list(SEQUENCES)
    for name, entry in report["sequences"].items():
        assert entry["frames"] == FRAMES[name] and entry["fps"] == 10
        assert entry["image_size"] == IMAGE[name]
        assert list(entry["classes"]) == list(CLASSES)
        for cls, part in entry["classes"].items():
            assert part["truth"] == TRUTH[name][cls], (name, cls)
            assert list(part["trackers"]) == list(TRACKERS)
            assert list(part["calibration"]) == list(TRACKERS)
            for tracker, values in part["trackers"].items():
                where = (name, cls, tracker)
                for key in FRACTIONS:
                    assert 0 <= values[key] <= 1, (*where, key)
                assert values["mota"] <= 1
                for key in COUNTS:
                    assert isinstance(values[key], int) and values[key] >= 0, (*where, key)
                assert values["frames_per_second"] > 0 and values["seconds"] > 0
                table = part["calibration"][tracker]
                assert set(table) == {"ece", "bins", "boxes", "confidence", "right"}
                assert table["ece"] == round(values["ece"], 6)  # the table keeps 6 decimals
                assert sum(table["boxes"]) > 0 or not values["tracks"]
            if part["truth"]:  # a tracker finds some of the boxes RRC detects
                assert all(v["hota"] > 0.1 for v in part["trackers"].values()), (name, cls)
            else:  # TrackEval gives a sequence without a true box of the class HOTA 0
                assert all(v["hota"] == 0 for v in part["trackers"].values()), (name, cls)


def test_combined_and_mean_per_class(run):
    _, report, _ = run
    assert "COMBINED_SEQ" in report["combined"]["method"]
    assert list(report["combined"]["classes"]) == list(CLASSES)
    assert list(report["mean"]["classes"]) == list(CLASSES)
    for cls in CLASSES:
        combined = report["combined"]["classes"][cls]
        assert list(combined["trackers"]) == list(TRACKERS)
        assert list(combined["calibration"]) == list(TRACKERS)
        mean = report["mean"]["classes"][cls]["trackers"]
        scored = [name for name in SEQUENCES if TRUTH[name][cls]]
        for tracker in TRACKERS:
            values = combined["trackers"][tracker]
            per_seq = [report["sequences"][name]["classes"][cls]["trackers"][tracker]
                       for name in SEQUENCES]
            for key in ("fp", "fn", "id_switches", "tracks"):  # counts summed
                assert values[key] == sum(v[key] for v in per_seq), (cls, tracker, key)
            assert 0 <= values["ece"] <= 1 and 0 < values["hota"] <= 1
            assert combined["calibration"][tracker]["ece"] == round(values["ece"], 6)
            # the mean is over the sequences with a true box of the class only
            for key in ("hota", "idf1", "mota", "deta", "assa", "loca", "ece"):
                expected = np.mean([report["sequences"][name]["classes"][cls]["trackers"]
                                    [tracker][key] for name in scored])
                assert mean[tracker][key] == pytest.approx(expected, abs=1e-12), (cls, key)
    # 0000 is the only sequence with cars, so the car mean is 0000's car score
    car = report["mean"]["classes"]["car"]["trackers"]["sort"]
    assert car["hota"] == report["sequences"]["0000"]["classes"]["car"]["trackers"]["sort"][
        "hota"]


def test_printed_tables_name_each_class(run):
    _, report, printed = run
    assert "Protocol kitti (TrackEval Kitti2DBox), detections rrc" in printed
    assert "== car ==" in printed and "== pedestrian ==" in printed
    assert printed.index("== car ==") < printed.index("== pedestrian ==")
    for title in ("0000 car (1242x375, 10 fps, 154 frames, 215 true boxes)",
                  "0000 pedestrian (1242x375, 10 fps, 154 frames, 19 true boxes)",
                  "0017 pedestrian (1224x370, 10 fps, 145 frames, 770 true boxes)",
                  "car, combined over 2 sequences", "pedestrian, combined over 2 sequences",
                  "car, mean over sequences", "pedestrian, mean over sequences"):
        assert title in printed, title
    assert "0017 car" not in printed  # no true car in 0017: no table
    car_part = printed[printed.index("== car =="):printed.index("== pedestrian ==")]
    sort_row = report["combined"]["classes"]["car"]["trackers"]["sort"]
    assert re.search(rf"^  sort +{sort_row['hota']:.3f} +{sort_row['idf1']:.3f}", car_part,
                     flags=re.M), car_part


# --- 2. the same scores as occtrack track + occtrack eval --------------------------------


def test_occtrack_scores_equal_track_then_eval(run, layout, tmp_path, capsys):
    """The benchmark's object-wise scores of 0000 are those of the two-step route.

    `occtrack track` writes the boxes with 2 decimals and the confidence with 4 (the
    benchmark scores the unrounded result); otherwise the rows are the same (frames, ids,
    classes; checked: with the written boxes put into the benchmark's result every score is
    equal). The rounding moves no match, so the counts and HOTA, MOTA and IDF1 are equal
    exactly; it moves LocA and MOTP (the mean IoU of the matches) by ~1e-5 and the ECE by
    ~1e-5, compared with a tolerance of 1e-3."""
    _, report, _ = run
    result = tmp_path / "r.txt"
    assert main(["track", str(layout / "det_02" / "rrc" / "0000.txt"), "-o", str(result),
                 "--occlusion", "object-wise", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["eval", str(layout / "label_02" / "0000.txt"), str(result), "--protocol",
                 "kitti", "--json", "--calibration"]) == 0
    scored = json.loads(capsys.readouterr().out)
    assert scored["protocol"] == "kitti"
    for cls in CLASSES:
        ours = report["sequences"]["0000"]["classes"][cls]["trackers"]["object-wise"]
        theirs = scored["classes"][cls]["sequences"]["0000"]
        for key in HEADLINE:
            assert ours[key] == theirs[key], (cls, key, ours[key], theirs[key])
        for key in ("deta", "assa", "mostly_tracked", "mostly_lost"):
            assert ours[key] == theirs[key], (cls, key)
        for key in ("loca", "motp"):
            assert ours[key] == pytest.approx(theirs[key], abs=1e-3), (cls, key)
        assert ours["ece"] == pytest.approx(scored["classes"][cls]["calibration"]["ece"],
                                            abs=1e-3), cls


# --- 3. the peers track class by class ---------------------------------------------------


@needs_peers
def test_peers_track_class_by_class(run, layout):
    """sort's car scores in the benchmark are those of sort run on 0000's car detections
    alone; its pedestrian rows are sort on the pedestrian detections alone, ids apart."""
    _, report, _ = run
    seq = benchmark_kitti.load_sequence(layout.resolve(), "rrc", "0000")
    peers.load_for("sort")
    size = (seq.width, seq.height)
    both = benchmark_kitti.track("sort", seq, CLASSES)
    ids = {}
    for cls in CLASSES:
        kind = CLASS_TYPE[cls]
        det = seq.det.select(seq.det.cls == kind)
        assert len(det) > 0
        alone = peers.track_peer("sort", det, seq.length, seq.fps, size)
        result = benchmark_kitti.result_table(alone.frame, alone.id, np.full(len(alone), kind),
                                              alone.box, alone.score)
        mine = both.type == kind
        np.testing.assert_array_equal(both.frame[mine], result.frame)
        np.testing.assert_array_equal(both.box[mine], result.box)
        np.testing.assert_array_equal(both.score[mine], result.score)
        ids[cls] = set(both.id[mine].tolist())
        if cls != "car":
            continue
        part = scored_frames(seq.gt, result, seq.length, (cls,))[cls]
        expected = {**summary(sequence_results(part.trackeval)),
                    "ece": reliability(part, result.score).ece,
                    "tracks": len(np.unique(alone.id))}
        got = report["sequences"]["0000"]["classes"][cls]["trackers"]["sort"]
        for key in (*HEADLINE, "deta", "assa", "loca", "motp", "ece", "tracks"):
            assert got[key] == expected[key], (key, got[key], expected[key])
    assert not ids["car"] & ids["pedestrian"]  # each class's ids kept apart
    # sort on the mixed detections (as one class) is another result: the test can tell
    mixed = peers.track_peer("sort", seq.det.select(np.isin(seq.det.cls, list(
        CLASS_TYPE.values()))), seq.length, seq.fps, size)
    assert len(mixed) != len(both) or not np.array_equal(mixed.box, both.box)


# --- 4. layout recognition and errors ----------------------------------------------------


def test_a_folder_without_det_02_is_not_kitti(kitti_root, tmp_path, capsys):
    folder = make_layout(kitti_root, tmp_path / "nodet", names=("0000",), det=False)
    message = error_of(capsys, "benchmark", str(folder), "--sequential", "--trackers", "none")
    assert message.startswith(f"{folder}: no sequence folder here")  # MOTChallenge's error
    assert "det/det.txt" in message
    message = error_of(capsys, "benchmark", str(folder), "--layout", "kitti", "--sequential",
                       "--trackers", "none")
    assert "not a KITTI tracking folder" in message and "det_02/" in message


def test_unknown_detections_name_what_det_02_holds(layout, tmp_path, capsys):
    out = tmp_path / "x.json"
    message = error_of(capsys, "benchmark", str(layout), "--sequential", "--trackers",
                       "none", "--detections", "nope", "--json", str(out))
    assert "no detections 'nope' here; det_02/ holds rrc" in message
    assert str(layout / "det_02") in message
    assert not out.exists()


def test_two_detector_folders_without_rrc_ask_for_one(kitti_root, tmp_path, capsys):
    folder = make_layout(kitti_root, tmp_path / "two", names=("0000",),
                         detectors=("alpha", "beta"))
    message = error_of(capsys, "benchmark", str(folder), "--sequential", "--trackers", "none")
    assert "det_02/ holds alpha, beta" in message and "--detections NAME" in message
    # named, either is taken
    report = bench(folder, tmp_path / "beta.json", "--detections", "beta", trackers=("none",))
    assert report["detections"] == "beta"


def test_rrc_is_the_default_among_several_and_the_only_one_is_taken(kitti_root, tmp_path):
    several = make_layout(kitti_root, tmp_path / "several", names=("0000",),
                          detectors=("pointy", "rrc"))
    assert bench(several, tmp_path / "a.json", trackers=("none",))["detections"] == "rrc"
    single = make_layout(kitti_root, tmp_path / "single", names=("0000",),
                         detectors=("pointy",))
    assert bench(single, tmp_path / "b.json", trackers=("none",))["detections"] == "pointy"


def test_a_sequence_without_its_seqinfo_names_the_file(kitti_root, tmp_path, capsys):
    folder = make_layout(kitti_root, tmp_path / "noini", seqinfo=("0000",))
    message = error_of(capsys, "benchmark", str(folder), "--sequential", "--trackers", "none")
    missing = folder.resolve() / "seqinfo" / "0017.ini"
    assert message == f"{missing}: sequence 0017 has no seqinfo/0017.ini"


def test_kitti_options_refused(layout, tmp_path, capsys):
    message = error_of(capsys, "benchmark", str(layout), "--sequential", "--trackers", "none",
                       "--classes", "cyclist")
    assert message == "--classes: KITTI's evaluation scores car and pedestrian, not 'cyclist'"
    for option in ("--per-frame", "--keep-boxes"):
        out = tmp_path / "x.json"
        message = error_of(capsys, "benchmark", str(layout), "--sequential", "--trackers",
                           "none", option, "--json", str(out))
        assert message.startswith(f"{option} is for MOTChallenge folders"), message
        assert not out.exists()


def test_classes_on_a_motchallenge_folder_refused(tmp_path, capsys):
    write_sequence(tmp_path / "mot" / "SYN-A", "SYN-A", people=3, frames=10, length=10, seed=1)
    for option, value in (("--classes", "car"), ("--detections", "rrc")):
        message = error_of(capsys, "benchmark", str(tmp_path / "mot"), "--sequential",
                           "--trackers", "none", option, value)
        assert message.startswith(f"{option} is for a KITTI folder"), message
        assert str(tmp_path / "mot") in message


def test_without_a_seqmap_label_02_names_the_sequences(kitti_root, tmp_path):
    folder = make_layout(kitti_root, tmp_path / "noseqmap", seqmap=False)
    report = bench(folder, tmp_path / "n.json", trackers=("none",))
    assert list(report["sequences"]) == list(SEQUENCES)
    assert [e["frames"] for e in report["sequences"].values()] == [154, 145]  # seqinfo's


def test_the_json_may_not_replace_an_input_of_the_kitti_folder(kitti_root, tmp_path, capsys):
    # only the seqmap (a file of this test, not a symlink to the shared data) is put at risk
    folder = make_layout(kitti_root, tmp_path / "inputs", names=("0000",))
    seqmap = folder / "evaluate_tracking.seqmap"
    before = seqmap.read_text()
    code = main(["benchmark", str(folder), "--sequential", "--trackers", "none", "--json",
                 str(seqmap), "--force", "--quiet"])
    out, err = capsys.readouterr()
    assert seqmap.read_text() == before
    assert code == 1 and "is also an input" in err, (out, err)


def test_classes_pick_what_is_scored(layout, tmp_path):
    report = bench(layout, tmp_path / "p.json", "--classes", "Pedestrian, pedestrian",
                   trackers=("none",))
    assert report["classes"] == ["pedestrian"]
    assert list(report["combined"]["classes"]) == ["pedestrian"]
    for entry in report["sequences"].values():
        assert list(entry["classes"]) == ["pedestrian"]


# --- 5. occtrack report on the KITTI JSON ------------------------------------------------


def test_report_draws_a_part_per_class(run, tmp_path, capsys):
    path, report, _ = run
    page_path = tmp_path / "k.html"
    assert main(["report", str(path), "-o", str(page_path)]) == 0
    assert "(car, pedestrian apart; KITTI runs keep no boxes)" in capsys.readouterr().out
    page = page_path.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>")
    for cls in CLASSES:
        assert f'<section id="{cls}-combined">' in page
        assert f'<h2 class="class">{cls}</h2>' in page
        table = re.search(rf'<table class="scores" id="{cls}-combined-table">.*?</table>',
                          page, flags=re.S).group(0)
        for tracker in TRACKERS:
            row = re.search(rf"{re.escape(tracker)}</th>(.*?)</tr>", table).group(1)
            cells = re.findall(r"<td[^>]*>(.*?)</td>", row)
            values = report["combined"]["classes"][cls]["trackers"][tracker]
            assert cells[0] == f"{values['hota']:.3f}", (cls, tracker)
            assert cells[6] == str(values["fp"]), (cls, tracker)
    # a section a sequence with a true box of the class: car 0000; pedestrian 0000, 0017
    assert len(re.findall(r'<section id="car-seq-\d+">', page)) == 1
    assert len(re.findall(r'<section id="pedestrian-seq-\d+">', page)) == 2
    assert "car: 0017" not in page
    assert "pedestrian: 0017 (1224x370, 10 fps, 145 frames)" in page


def test_report_of_a_kitti_json_without_classes_names_the_file(run, tmp_path, capsys):
    _, report, _ = run
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({k: v for k, v in report.items() if k != "classes"}))
    message = error_of(capsys, "report", str(bad), "-o", str(tmp_path / "bad.html"))
    assert message.startswith(f"{bad}: not an occtrack benchmark JSON file: no 'classes' key")
    assert not (tmp_path / "bad.html").exists()


# --- 6. determinism ----------------------------------------------------------------------


def test_two_runs_give_the_same_json(run, layout, tmp_path):
    _, first, _ = run
    second = bench(layout, tmp_path / "again.json")
    assert without_times(second) == without_times(first)  # the run times may differ


def test_config_settings_reach_occtrack_and_match_track_with_the_same_config(layout, tmp_path,
                                                                             capsys):
    """--config FILE: the settings reach occtrack's models (the JSON keeps them, and the
    scores are those of `occtrack track --config FILE` then eval), the image size, frame rate
    and occlusion model in the file are the sequence's and the model's; a bad setting is one
    line before any run."""
    config = tmp_path / "c.toml"
    config.write_text("learn_size_noise = false\nlearn_score_model = false\nfps = 99\n"
                      "occlusion = \"none\"\n")
    report = bench(layout, tmp_path / "k.json", "--config", str(config),
                   trackers=("object-wise",))
    assert report["settings"] == {"learn_size_noise": False, "learn_score_model": False}
    result = tmp_path / "r.txt"
    assert main(["track", str(layout / "det_02" / "rrc" / "0000.txt"), "-o", str(result),
                 "--config", str(config), "--occlusion", "object-wise", "--fps", "10",
                 "--quiet"]) == 0
    capsys.readouterr()
    assert main(["eval", str(layout / "label_02" / "0000.txt"), str(result), "--json"]) == 0
    scored = json.loads(capsys.readouterr().out)
    for cls in CLASSES:
        ours = report["sequences"]["0000"]["classes"][cls]["trackers"]["object-wise"]
        theirs = scored["classes"][cls]["sequences"]["0000"]
        for key in HEADLINE:
            assert ours[key] == theirs[key], (cls, key)
    default = bench(layout, tmp_path / "d.json", trackers=("object-wise",))
    assert "settings" not in default
    car = "car"
    assert (default["sequences"]["0000"]["classes"][car]["trackers"]["object-wise"]
            != report["sequences"]["0000"]["classes"][car]["trackers"]["object-wise"])
    config.write_text("learn_size_noise = 3\n")
    message = error_of(capsys, "benchmark", str(layout), "--sequential", "--config",
                       str(config), "--trackers", "none")
    assert message.startswith(str(config)) and "learn_size_noise" in message
