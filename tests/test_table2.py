"""`occtrack reproduce table2`: the data search, and the JSON shape on MOT17-04 when present."""

from __future__ import annotations

import json

import pytest

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


def test_json_on_mot17(capsys):
    try:
        find_sequence()
    except OcctrackError:
        pytest.skip("MOT17-04 ground truth not present")
    assert main(["reproduce", "table2", "--json", "--no-norfair", "--quiet"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert list(data) == ["paper", "mot17"]
    for protocol, rows in data.items():
        assert list(rows) == ["none", "measurement-wise", "object-wise"]
        for values in rows.values():
            assert list(values) == list(KEYS)
            assert 0 < values["idf1"] <= 1 and values["mota"] <= 1
            assert (values["hota"] is None) == (protocol == "paper")
