"""benchmarks/leave_one_set_out.py (issue 37, item 5): the value chosen without a set is the
best mean over the others, ties go to the default, and the left-out set is scored with it."""

from __future__ import annotations

import importlib.util

import pytest

from conftest import CHECKOUT


@pytest.fixture(scope="module")
def loso():
    spec = importlib.util.spec_from_file_location(
        "leave_one_set_out", CHECKOUT / "benchmarks" / "leave_one_set_out.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_value_is_chosen_on_the_other_sets_only(loso):
    scores = {"a": {0.0: 0.50, 0.05: 0.50, 0.1: 0.40},
              "b": {0.0: 0.60, 0.05: 0.62, 0.1: 0.70},
              "c": {0.0: 0.70, 0.05: 0.80, 0.1: 0.75}}
    rows = {row["left_out"]: row for row in loso.leave_one_out(scores, 0.05)}
    # without a: b and c mean .65 / .71 / .725 -> .1, which scores .40 on a
    assert rows["a"]["chosen"] == 0.1 and rows["a"]["hota_chosen"] == 0.40
    assert rows["a"]["hota_default"] == 0.50 and rows["a"]["best_alone"] == 0.0
    # without b: a and c .60 / .65 / .575 -> .05
    assert rows["b"]["chosen"] == 0.05 and rows["b"]["hota_best_alone"] == 0.70
    # without c: a and b .55 / .56 / .55 -> .05
    assert rows["c"]["chosen"] == 0.05


def test_a_tie_goes_to_the_default_then_to_the_first_value(loso):
    scores = {"a": {1.0: 0.5, 2.0: 0.5, 3.0: 0.5}, "b": {1.0: 0.4, 2.0: 0.4, 3.0: 0.4}}
    assert {row["chosen"] for row in loso.leave_one_out(scores, 3.0)} == {3.0}
    scores["a"][3.0] = 0.1
    assert loso.leave_one_out(scores, 3.0)[1]["chosen"] == 1.0


def test_every_grid_holds_its_default(loso):
    from occtrack import TrackerConfig

    for name, grid in loso.GRIDS.items():
        assert getattr(TrackerConfig(), name) in grid, name
