"""`occtrack reproduce table2`: the data search, the options, and the JSON shape on the real
MOT17-04 detections when present."""

from __future__ import annotations

import json

import pytest

from occtrack import peers
from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.io.data import find_sequence
from occtrack.metrics.protocols import KEYS


def test_missing_data_is_explained(tmp_path, capsys):
    assert main(["reproduce", "table2", "--data", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "MOT17 data not found" in err and str(tmp_path) in err and "--data" in err


def test_environment_variable_is_searched(tmp_path, monkeypatch):
    monkeypatch.setenv("OCCTRACK_DATA", str(tmp_path))
    with pytest.raises(OcctrackError, match="OCCTRACK_DATA"):
        find_sequence()
    seq = tmp_path / "MOT17-04-FRCNN"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("1,1,0,0,5,5,1,1,1\n")
    (seq / "seqinfo.ini").write_text("[Sequence]\n")
    assert find_sequence() == seq


def test_seed_needs_simulated_detections(capsys):
    assert main(["reproduce", "table2", "--seed", "3"]) == 1
    assert "--detections simulated" in capsys.readouterr().err


def test_missing_detection_file_is_named(tmp_path, capsys):
    seq = tmp_path / "MOT17-04-FRCNN"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("1,1,0,0,5,5,1,1,1\n")
    (seq / "seqinfo.ini").write_text("[Sequence]\nimWidth=64\nimHeight=48\nseqLength=1\n")
    assert main(["reproduce", "table2", "--data", str(tmp_path), "--no-norfair"]) == 1
    err = capsys.readouterr().err
    assert str(seq / "det" / "det.txt") in err and "no such file" in err


def test_json_on_mot17_real_detections(capsys, mot17_04):
    data = str(mot17_04.parent)
    assert main(["reproduce", "table2", "--data", data, "--json", "--no-norfair",
                 "--quiet"]) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    expected = ["none", "measurement-wise", "object-wise"]
    if peers.available():
        expected += ["bytetrack", "ocsort"]
    else:
        assert "ByteTrack and OC-SORT left out" in captured.err
    assert list(data) == ["paper", "mot17"]
    for protocol, rows in data.items():
        assert list(rows) == expected
        for values in rows.values():
            assert list(values) == list(KEYS)
            assert 0 < values["idf1"] <= 1 and values["mota"] <= 1
            assert (values["hota"] is None) == (protocol == "paper")
    # The public detections: occlusion reasoning beats the plain tracker under both
    # protocols, as in the paper's Table II.
    for protocol in ("paper", "mot17"):
        rows = data[protocol]
        assert min(rows["measurement-wise"]["mota"], rows["object-wise"]["mota"]) \
            > rows["none"]["mota"]
        assert rows["measurement-wise"]["gospa"] < rows["none"]["gospa"]
