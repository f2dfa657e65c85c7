"""benchmarks/evidence_split.py (issue 40): a half's HOTA weighted by each sequence's true
boxes and its ECE from the sequences' reliability bins pooled; and the benchmark hands its
`ground` options to `track_kitti`."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from conftest import CHECKOUT


@pytest.fixture(scope="module")
def split():
    sys.path.insert(0, str(CHECKOUT / "benchmarks"))  # (it imports hidden_kept beside it)
    spec = importlib.util.spec_from_file_location(
        "evidence_split", CHECKOUT / "benchmarks" / "evidence_split.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _entry(hota, truth, boxes, confidence, right):
    return {"truth": truth, "trackers": {"object-wise": {"hota": hota}},
            "calibration": {"object-wise": {"bins": len(boxes), "boxes": boxes,
                                            "confidence": confidence, "right": right,
                                            "ece": 0.0}}}


def test_a_half_is_weighted_by_true_boxes_and_its_bins_pooled(split):
    """HOTA (.8 x 30 + .5 x 10) / 40 = .725; ECE from the summed bins: bin 1 holds 1 + 3
    boxes at confidence (.6 + 3 x .7) / 4 with (0 + 3 x 1) right, bin 2 (empty in one
    sequence: None) 2 boxes at .9, 1 right: (|2.7 - 3| + |1.8 - 1|) / 6 = 1.1 / 6."""
    report = {"sequences": {
        "0000": {"classes": {"car": _entry(0.8, 30, [1, 2], [0.6, 0.9], [0.0, 0.5])}},
        "0001": {"classes": {"car": _entry(0.5, 10, [3, 0], [0.7, None], [1.0, None])}},
        "0002": {"classes": {"car": _entry(0.1, 99, [5, 5], [0.5, 0.5], [0.0, 0.0])}}}}
    hota, ece = split.half_scores(report, "car", ["0000", "0001"])
    assert hota == pytest.approx(0.725, abs=1e-12)
    assert ece == pytest.approx(1.1 / 6, abs=1e-12)


def test_the_chosen_on_sequences_are_the_docs_five(split):
    assert split.CHOSEN_ON == ("0000", "0003", "0005", "0009", "0017")
    assert (0.5, 0.2) in split.PAIRS  # the defaults' row
