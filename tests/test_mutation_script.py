"""benchmarks/mutation.py says when no mutant was scored instead of printing nan% (issue 38,
kind 5): a regular install makes the tests import the installed occtrack, not the mutants."""

from __future__ import annotations

import importlib.util

import pytest

from conftest import CHECKOUT


@pytest.fixture(scope="module")
def mutation():
    spec = importlib.util.spec_from_file_location("mutation_script",
                                                  CHECKOUT / "benchmarks" / "mutation.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_run_with_nothing_scored_prints_no_nan(mutation, capsys):
    status = {"occtrack.filters.x__mutmut_1": "not checked",
              "occtrack.filters.x__mutmut_2": "not checked"}
    score = mutation.report(status, set())
    out = capsys.readouterr().out
    assert score != score  # nan: main turns it into an error, not a score
    assert "nan" not in out
    assert out.splitlines()[-1].split()[-1] == "-"


def test_a_scored_run_prints_its_score(mutation, capsys):
    status = {"occtrack.filters.x__mutmut_1": "killed", "occtrack.filters.x__mutmut_2": "killed",
              "occtrack.filters.x__mutmut_3": "survived", "occtrack.filters.x__mutmut_4":
              "survived"}
    assert mutation.report(status, {"occtrack.filters.x__mutmut_4"}) == pytest.approx(2 / 3)
    assert capsys.readouterr().out.splitlines()[-1].split()[-1] == "66.7%"
