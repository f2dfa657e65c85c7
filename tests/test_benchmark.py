"""`occtrack benchmark DIR` on tiny synthetic sequence folders."""

from __future__ import annotations

import json
import os
import shutil

import pytest

from occtrack import peers
from occtrack.cli import main
from occtrack.experiments.benchmark import MODELS, find_sequences
from sequences import SEQINFO, write_sequence

LENGTH = 36
FRACTIONS = ("hota", "idf1", "deta", "assa", "loca", "motp")
COUNTS = ("mostly_tracked", "mostly_lost", "fp", "fn", "id_switches", "tracks")


def make_sequence(folder, name: str, truth_as_detections: bool = False):
    return write_sequence(folder, name, people=5, frames=LENGTH - 4, length=LENGTH, seed=4,
                          truth_as_detections=truth_as_detections, shuffle=True)


@pytest.fixture(scope="module")
def two_copies(tmp_path_factory):
    """A folder holding the same sequence twice, under two names, and a stray folder."""
    root = tmp_path_factory.mktemp("bench")
    make_sequence(root / "SYN-A", "SYN-A")
    shutil.copytree(root / "SYN-A", root / "SYN-B")
    (root / "SYN-B" / "seqinfo.ini").write_text(SEQINFO.format(name="SYN-B", length=LENGTH))
    (root / "notes").mkdir()
    return root


@pytest.fixture(scope="module")
def report(two_copies, tmp_path_factory):
    out = tmp_path_factory.mktemp("out") / "bench.json"
    assert main(["benchmark", str(two_copies), "--json", str(out), "--quiet"]) == 0
    return json.loads(out.read_text())


def test_report_shape_and_ranges(report):
    expected = list(MODELS) + (list(peers.PEERS) if peers.available() else [])
    assert report["protocol"] == "mot17" and report["trackers"] == expected
    assert list(report["sequences"]) == ["SYN-A", "SYN-B"]
    for entry in report["sequences"].values():
        assert entry["frames"] == LENGTH and entry["fps"] == 10
        assert entry["image_size"] == [1280, 720]
        assert list(entry["trackers"]) == expected
    assert list(report["combined"]["trackers"]) == expected
    assert "COMBINED_SEQ" in report["combined"]["method"]
    for values in [*report["combined"]["trackers"].values(),
                   *(v for e in report["sequences"].values() for v in e["trackers"].values())]:
        for key in FRACTIONS:
            assert 0 <= values[key] <= 1, key
        assert values["mota"] <= 1
        for key in COUNTS:
            assert isinstance(values[key], int) and values[key] >= 0, key
        assert values["frames_per_second"] > 0 and values["seconds"] > 0


def _without_times(report: dict) -> dict:
    """The report with the run times (which differ from run to run) left out."""
    if isinstance(report, dict):
        return {k: _without_times(v) for k, v in report.items()
                if k not in ("seconds", "frames_per_second")}
    return report


def test_dask_engine_gives_the_sequential_report(two_copies, report, tmp_path):
    """The fixture ran its (sequence, tracker) tasks on a Dask LocalCluster (the default);
    in this process, one after another, the report is the same, run times aside."""
    pytest.importorskip("distributed", reason="the engine needs `pip install occtrack[sweep]`")
    out = tmp_path / "sequential.json"
    assert main(["benchmark", str(two_copies), "--json", str(out), "--quiet",
                 "--sequential"]) == 0
    assert _without_times(json.loads(out.read_text())) == _without_times(report)


def test_identical_sequences_combine_to_themselves(report):
    """Two copies of one sequence: every tracker is deterministic, so both copies score the
    same, TrackEval's combination sums their counts and keeps their ratios, and the mean over
    sequences equals either copy."""
    a, b = (report["sequences"][name]["trackers"] for name in ("SYN-A", "SYN-B"))
    for name in report["trackers"]:
        both = report["combined"]["trackers"][name]
        for key in ("hota", "idf1", "mota", "deta", "assa", "loca", "motp"):
            assert a[name][key] == pytest.approx(b[name][key])
            assert both[key] == pytest.approx(a[name][key])
            assert report["mean"]["trackers"][name][key] == pytest.approx(a[name][key])
        for key in COUNTS:
            assert both[key] == a[name][key] + b[name][key] == 2 * a[name][key]


def test_table_and_json_to_stdout(two_copies, capsys):
    seq = two_copies / "SYN-A"
    assert main(["benchmark", str(seq), "--trackers", "none,none", "--sequential"]) == 0
    out = capsys.readouterr().out
    assert "SYN-A (1280x720, 10 fps, 36 frames)" in out and "Combined" not in out
    assert out.strip().splitlines()[-1].startswith(f"{LENGTH} frames, ")
    assert main(["benchmark", str(seq), "--trackers", "object-wise", "--json", "-",
                 "--sequential"]) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert data["trackers"] == ["object-wise"] and list(data["sequences"]) == ["SYN-A"]
    assert "frames per second" in captured.err


def test_peers_report_the_detection_boxes(tmp_path):
    """Given the ground truth as detections, a peer reports true boxes only: no false
    positive, and every match is exact."""
    pytest.importorskip("trackers", reason="the peers need `pip install occtrack[peers]`")
    make_sequence(tmp_path / "SYN", "SYN", truth_as_detections=True)
    out = tmp_path / "bench.json"
    assert main(["benchmark", str(tmp_path / "SYN"), "--trackers", ",".join(peers.PEERS),
                 "--json", str(out), "--quiet", "--sequential"]) == 0
    for values in json.loads(out.read_text())["sequences"]["SYN"]["trackers"].values():
        assert values["fp"] == 0
        assert values["loca"] == pytest.approx(1.0) and values["motp"] == pytest.approx(1.0)


def test_bad_input_is_named(tmp_path, capsys):
    assert main(["benchmark", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert str(tmp_path) in err and "det/det.txt" in err
    assert main(["benchmark", str(tmp_path / "absent")]) == 1
    assert "no such folder" in capsys.readouterr().err
    seq = tmp_path / "SEQ"
    make_sequence(seq, "SEQ")
    assert main(["benchmark", str(seq), "--trackers", "none,deepsort", "--sequential"]) == 1
    assert "unknown tracker 'deepsort'" in capsys.readouterr().err
    (seq / "seqinfo.ini").unlink()
    assert main(["benchmark", str(seq), "--trackers", "none", "--sequential"]) == 1
    assert "seqinfo.ini" in capsys.readouterr().err
    assert find_sequences(seq) == [seq]


def test_json_file_is_kept_unless_forced(tmp_path, capsys):
    seq = tmp_path / "SEQ"
    make_sequence(seq, "SEQ")
    out = tmp_path / "bench.json"
    out.write_text("keep me\n")
    out.chmod(0o644)
    assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(out),
                 "--sequential"]) == 1
    assert "exists already" in capsys.readouterr().err and out.read_text() == "keep me\n"
    assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(out), "--force",
                 "--quiet", "--sequential"]) == 0
    assert json.loads(out.read_text())["trackers"] == ["none"]
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    # written through occtrack.io.atomic: the old file's permissions, not a temporary's 0600
    assert out.stat().st_mode & 0o777 == 0o644
    truth = seq / "gt" / "gt.txt"
    kept = truth.read_text()
    assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(truth), "--force",
                 "--quiet", "--sequential"]) == 1
    assert f"{truth}: is also an input" in capsys.readouterr().err
    assert truth.read_text() == kept


def test_new_json_file_has_the_permissions_of_any_new_file(tmp_path):
    seq = tmp_path / "SEQ"
    make_sequence(seq, "SEQ")
    out = tmp_path / "bench.json"
    umask = os.umask(0o022)
    try:
        assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(out),
                     "--quiet", "--sequential"]) == 0
    finally:
        os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o644


def test_without_the_peers_extra(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(peers, "available", lambda: False)
    seq = tmp_path / "SEQ"
    make_sequence(seq, "SEQ")
    assert main(["benchmark", str(seq), "--trackers", "none,bytetrack", "--sequential"]) == 1
    assert 'pip install "occtrack[peers]"' in capsys.readouterr().err
    assert main(["benchmark", str(seq), "--json", "-", "--sequential"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["trackers"] == list(MODELS)
    assert "note: the peers" in captured.err and "occtrack[peers]" in captured.err


def test_failed_run_is_named_and_the_others_finish(tmp_path, capsys, monkeypatch):
    """A run that raises (here a tracker made to fail on one sequence) is named with its
    tracker and sequence after every other run finished; the exit status is 1."""
    make_sequence(tmp_path / "GOOD", "GOOD")
    make_sequence(tmp_path / "BAD", "BAD")
    from occtrack.experiments import benchmark

    ran = []
    real = benchmark.track_with_states

    def track(name, seq, settings=None):
        ran.append((name, seq.name))
        if seq.name == "BAD" and name == "none":
            raise FloatingPointError("made to fail")
        return real(name, seq, settings)

    monkeypatch.setattr(benchmark, "track_with_states", track)
    assert main(["benchmark", str(tmp_path), "--trackers", "none,object-wise",
                 "--sequential"]) == 1
    err = capsys.readouterr().err
    assert "1 of 4 runs failed (the others finished)" in err
    assert f"none on {(tmp_path / 'BAD').resolve()}: FloatingPointError: made to fail" in err
    assert len(ran) == 4
