"""Paper Table I, cell by cell, and the four-square example against an independent brute force."""

from __future__ import annotations

import itertools
import json
from fractions import Fraction as F

import pytest

from occtrack.cli import main
from occtrack.experiments.table1 import PAPER, paper_value
from occtrack.scenarios.foursquare import OUTCOMES, QUANTITIES, FourSquare, table

# Paper Table I, typed in from the paper: model -> quantity -> values for outcomes A..E.
TABLE_I = {
    "none": {"top_exists": ["1/5", "1/5", "1", "1", "1"],
             "top_left_given_exists": ["1/2", "1/2", "2/3", "2/3", "2/3"],
             "bottom_left": ["1/2", "2/3", "1/2", "1/3", "2/3"]},
    "object-wise": {"top_exists": ["5/13", "5/13", "1", "1", "1"],
                    "top_left_given_exists": ["1/2", "3/5", "2/3", "4/5", "1/2"],
                    "bottom_left": ["1/2", "2/3", "1/3", "1/5", "1/2"]},
    "measurement-wise": {"top_exists": ["1/5", "5/13", "1", "1", None],
                         "top_left_given_exists": ["1/2", "3/5", "2/3", "2/3", None],
                         "bottom_left": ["1/2", "2/3", "1/2", "1/3", None]},
}

CELLS = [(model, quantity, k) for model in TABLE_I for quantity in TABLE_I[model]
         for k in range(5)]


@pytest.fixture(scope="module")
def paper_example():
    return table()


@pytest.mark.parametrize("model,quantity,k", CELLS)
def test_table_one_cell(paper_example, model, quantity, k):
    outcome = "ABCDE"[k]
    expected = TABLE_I[model][quantity][k]
    got = paper_example[model][outcome]
    if expected is None:
        assert got is None
    else:
        assert got[quantity] == F(expected)


def test_all_45_cells_are_checked(paper_example):
    """The engine computes 45 cells (3 models x 5 outcomes x 3 quantities, an impossible
    outcome counting as its 3 cells), the module's own copy of the paper's table has the same
    45, and the test above checks exactly those; the two typed-in copies agree."""
    engine = {(model, quantity, outcome) for model, row in paper_example.items()
              for outcome, values in row.items()
              for quantity in (QUANTITIES if values is None else values)}
    paper = {(model, quantity, outcome) for model, row in PAPER.items()
             for quantity, values in row.items() for outcome, _ in zip(OUTCOMES, values,
                                                                        strict=True)}
    checked = {(model, quantity, "ABCDE"[k]) for model, quantity, k in CELLS}
    assert len(engine) == 45 and engine == paper == checked
    for model, quantity, outcome in engine:
        ours = TABLE_I[model][quantity]["ABCDE".index(outcome)]
        assert paper_value(model, outcome, quantity) == (None if ours is None else F(ours))


def brute_force(p_correct: F, p_wrong: F, p_top: F, occlusion: str) -> dict:
    """Enumerate worlds of the four-square example directly: where each object is, what each
    sensor reading is, and what the occlusion rule lets through."""
    p_miss = 1 - p_correct - p_wrong
    joint: dict = {}
    for top_present, top_col, bottom_col, top_reading, bottom_reading in itertools.product(
            (True, False), (0, 1), (0, 1), ("own", "other", "none"), ("own", "other", "none")):
        p = (p_top if top_present else (1 - p_top)) * F(1, 2) * F(1, 2)
        if not top_present:
            if top_col == 1 or top_reading != "none":
                continue  # an absent object: count its world once, with no reading
            p *= 2
        reading_p = {"own": p_correct, "other": p_wrong, "none": p_miss}
        p *= reading_p[bottom_reading]
        if top_present:
            p *= reading_p[top_reading]
        if p == 0:
            continue

        def column(col, reading):
            return None if reading == "none" else (col if reading == "own" else 1 - col)

        top_meas = column(top_col, top_reading) if top_present else None
        bottom_meas = column(bottom_col, bottom_reading)
        if occlusion == "object-wise" and top_present and top_col == bottom_col:
            top_meas = None
        if occlusion == "measurement-wise" and top_meas is not None and top_meas == bottom_meas:
            top_meas = None
        key = (top_meas, bottom_meas)
        acc = joint.setdefault(key, {"all": F(0), "top": F(0), "top_left": F(0),
                                     "bottom_left": F(0)})
        acc["all"] += p
        if top_present:
            acc["top"] += p
            if top_col == 0:
                acc["top_left"] += p
        if bottom_col == 0:
            acc["bottom_left"] += p
    outcomes = {"A": (None, None), "B": (None, 0), "C": (0, None), "D": (0, 1), "E": (0, 0)}
    result = {}
    for name, key in outcomes.items():
        acc = joint.get(key)
        if acc is None or acc["all"] == 0:
            result[name] = None
            continue
        result[name] = {
            "top_exists": acc["top"] / acc["all"],
            "top_left_given_exists": acc["top_left"] / acc["top"] if acc["top"] else None,
            "bottom_left": acc["bottom_left"] / acc["all"],
        }
    return result


@pytest.mark.parametrize("params", [
    (F(1, 2), F(1, 4), F(1, 2)),
    (F(3, 5), F(1, 10), F(2, 7)),
    (F(9, 10), F(1, 20), F(4, 5)),
    (F(1, 3), F(1, 3), F(1, 9)),
    (F(1), F(0), F(1, 2)),
])
def test_engine_matches_brute_force(params):
    ours = table(FourSquare(*params))
    for occlusion in ("none", "object-wise", "measurement-wise"):
        assert ours[occlusion] == brute_force(*params, occlusion), occlusion


def test_json_shape(capsys):
    assert main(["foursquare", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert list(data) == ["none", "object-wise", "measurement-wise"]
    for model in data.values():
        assert list(model) == list(OUTCOMES)
    assert data["measurement-wise"]["E"] is None
    assert data["object-wise"]["A"] == {"top_exists": "5/13", "top_left_given_exists": "1/2",
                                        "bottom_left": "1/2"}


def test_text_table_reports_agreement(capsys):
    assert main(["foursquare"]) == 0
    out = capsys.readouterr().out
    assert "45 of 45 cells equal the paper's Table I." in out
    assert "]!" not in out


def test_other_parameters_marked_not_comparable(capsys):
    assert main(["foursquare", "--p-correct", "0.6", "--p-wrong", "1/5"]) == 0
    out = capsys.readouterr().out
    assert "P(own square) = 3/5" in out and "only for its own parameters" in out


@pytest.mark.parametrize("args,message,status", [
    (["--p-correct", "-0.1"], "outside [0, 1]", 2),
    (["--p-top", "3/2"], "outside [0, 1]", 2),
    (["--p-wrong", "abc"], "is not a probability", 2),
    (["--p-wrong", "nan"], "is not a probability", 2),
    (["--p-top", "1/0"], "is not a probability", 2),
    (["--p-correct", "0.8", "--p-wrong", "0.3"], "exceeds 1", 1),
])
def test_invalid_probabilities(capsys, args, message, status):
    try:
        code = main(["foursquare", *args])
    except SystemExit as exc:  # argparse rejects a bad value itself: a usage error
        code = exc.code
    assert code == status
    assert message in capsys.readouterr().err


def test_figure_written_and_not_overwritten(tmp_path, capsys):
    path = tmp_path / "fs.png"
    assert main(["foursquare", "--figure", str(path)]) == 0
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["foursquare", "--figure", str(path)]) == 1
    assert "exists already" in capsys.readouterr().err
