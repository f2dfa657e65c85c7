"""benchmarks/hidden_kept.py (issue 40): the missed stretches of a true object (seen, unseen,
seen again), which of them are hidden from the sensor (KITTI's `occluded` >= 1), and whether
the tracker's result keeps one id through them."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from conftest import CHECKOUT
from occtrack.io.kitti import TYPES, UNKNOWN_3D, KittiTable

CAR, PEDESTRIAN = TYPES.index("Car"), TYPES.index("Pedestrian")
BOX = (100.0, 100.0, 200.0, 180.0)  # x1 y1 x2 y2
ELSEWHERE = (500.0, 100.0, 600.0, 180.0)  # IoU 0 with BOX


@pytest.fixture(scope="module")
def hk():
    spec = importlib.util.spec_from_file_location(
        "hidden_kept", CHECKOUT / "benchmarks" / "hidden_kept.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["hidden_kept"] = module  # (its dataclass looks its module up by name)
    spec.loader.exec_module(module)
    return module


def table(frame, ids, types, boxes, occluded=None) -> KittiTable:
    n = len(frame)
    return KittiTable(frame=np.asarray(frame, np.int64), id=np.asarray(ids, np.int64),
                      type=np.asarray(types, np.int64), truncated=np.zeros(n),
                      occluded=np.zeros(n) if occluded is None else np.asarray(occluded, float),
                      alpha=np.full(n, -10.0), box=np.asarray(boxes, float).reshape(n, 4),
                      box3d=np.tile(UNKNOWN_3D, (n, 1)), score=np.ones(n))


def car(frames, occluded=None, ident=0) -> KittiTable:
    """One true car at BOX in `frames`."""
    return table(frames, [ident] * len(frames), [CAR] * len(frames), [BOX] * len(frames),
                 occluded)


def detections(frames, kind=CAR, box=BOX) -> KittiTable:
    return table(frames, [-1] * len(frames), [kind] * len(frames), [box] * len(frames))


def result(ids_by_frame: dict, kind=CAR, box=BOX) -> KittiTable:
    """The tracker's result: a box at `box` with id ids_by_frame[f] in frame f."""
    frames = list(ids_by_frame)
    return table(frames, list(ids_by_frame.values()), [kind] * len(frames),
                 [box] * len(frames))


FRAMES = list(range(8))
MISSED_3_4 = [0, 1, 2, 5, 6, 7]  # the detector misses frames 3 and 4
OCCLUDED_3_4 = [0, 0, 0, 2, 2, 0, 0, 0]


def counts(hk, gt, det, res, cls="car"):
    return hk.count_sequence(gt, det, res)[cls]


def test_the_stretch_finder(hk):
    seen = np.isin(FRAMES, MISSED_3_4)
    assert hk.missed_stretches(FRAMES, seen, OCCLUDED_3_4) == [(3, 4, True)]
    assert hk.missed_stretches(FRAMES, seen, np.zeros(8)) == [(3, 4, False)]
    # occluded 1 in one frame of the run is enough; occluded outside the run is not
    assert hk.missed_stretches(FRAMES, seen, [0, 0, 0, 0, 1, 0, 0, 0])[0][2]
    assert not hk.missed_stretches(FRAMES, seen, [3, 3, 3, 0, 0, 3, 3, 3])[0][2]
    # at the start (no frame before) and at the end (no frame after): not counted
    assert hk.missed_stretches(FRAMES, np.isin(FRAMES, [2, 3, 4, 5, 6]), OCCLUDED_3_4) == []
    # two stretches, frames given out of order
    seen = np.array([True, False, True, False, False, True, True, True])
    assert hk.missed_stretches(FRAMES[::-1], seen[::-1], OCCLUDED_3_4[::-1]) == [
        (1, 1, False), (3, 4, True)]
    # a run beside a frame where the object is not labelled has no flank
    frames = [0, 1, 2, 3, 5, 6]  # not labelled in frame 4
    assert hk.missed_stretches(frames, [True, True, False, False, True, True], np.ones(6)) == []


def test_a_result_that_holds_id_7_through_keeps_the_hidden_stretch(hk):
    got = counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4),
                 result(dict.fromkeys(FRAMES, 7)))
    assert got == {"hidden": {"stretches": 1, "held_before": 1, "kept": 1, "same_after": 1},
                   "missed": {"stretches": 1, "held_before": 1, "kept": 1, "same_after": 1}}
    # nothing for the class with no true object
    assert counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4),
                  result(dict.fromkeys(FRAMES, 7)), "pedestrian")["missed"]["stretches"] == 0


def test_a_result_that_switches_id_keeps_nothing(hk):
    switched = {f: 7 if f < 3 else 8 for f in FRAMES}  # 8 from the stretch on
    got = counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4), result(switched))
    assert got["hidden"] == {"stretches": 1, "held_before": 1, "kept": 0, "same_after": 0}


def test_same_id_after_but_not_kept_when_the_box_is_lost_in_the_stretch(hk):
    gap = {f: 7 for f in FRAMES if f != 4}  # no box in frame 4, id 7 back in frame 5
    got = counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4), result(gap))
    assert got["hidden"] == {"stretches": 1, "held_before": 1, "kept": 0, "same_after": 1}
    # id 7 in the stretch but elsewhere in the image (IoU 0): not kept either
    res = result(dict.fromkeys(FRAMES, 7))
    res.box[4] = ELSEWHERE
    assert counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4), res)["hidden"][
        "kept"] == 0


def test_not_held_before_when_the_result_has_no_box_of_the_class_there(hk):
    got = counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4),
                 result(dict.fromkeys(FRAMES, 7), kind=PEDESTRIAN))
    assert got["hidden"] == {"stretches": 1, "held_before": 0, "kept": 0, "same_after": 0}


def test_the_best_overlap_before_gives_the_id(hk):
    near = (110.0, 100.0, 210.0, 180.0)  # IoU 90/110 with BOX, under the exact box's 1
    res = table(FRAMES + [2], [7] * 8 + [9], [CAR] * 9, [BOX] * 8 + [near])
    assert counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4), res)["hidden"][
        "kept"] == 1
    res.box[2], res.box[8] = near, BOX  # now id 9 is the best in frame 2, and is not kept
    assert counts(hk, car(FRAMES, OCCLUDED_3_4), detections(MISSED_3_4), res)["hidden"] == {
        "stretches": 1, "held_before": 1, "kept": 0, "same_after": 0}


def test_a_stretch_at_the_start_is_not_counted(hk):
    got = counts(hk, car(FRAMES, [2] * 8), detections([2, 3, 4, 5, 6, 7]),
                 result(dict.fromkeys(FRAMES, 7)))
    assert got["missed"]["stretches"] == 0 and got["hidden"]["stretches"] == 0


def test_a_missed_object_labelled_unoccluded_is_missed_not_hidden(hk):
    got = counts(hk, car(FRAMES), detections(MISSED_3_4), result(dict.fromkeys(FRAMES, 7)))
    assert got["missed"] == {"stretches": 1, "held_before": 1, "kept": 1, "same_after": 1}
    assert got["hidden"]["stretches"] == 0


def test_a_detection_must_be_of_the_class_and_overlap(hk):
    # a pedestrian detection on the car, or a car detection elsewhere, does not see it
    det = table(MISSED_3_4 + [3, 4], [-1] * 8, [CAR] * 6 + [PEDESTRIAN, CAR],
                [BOX] * 6 + [BOX, ELSEWHERE])
    got = counts(hk, car(FRAMES, OCCLUDED_3_4), det, result(dict.fromkeys(FRAMES, 7)))
    assert got["hidden"]["stretches"] == 1
    # a car detection at IoU >= 0.5 in frame 3 splits nothing off: the stretch is frame 4
    det = table(MISSED_3_4 + [3], [-1] * 7, [CAR] * 7, [BOX] * 6 + [(110.0, 100.0, 210.0, 180.0)])
    gt = car(FRAMES, OCCLUDED_3_4)
    assert hk.detected(gt, det).tolist() == [True] * 4 + [False] + [True] * 3


def test_two_objects_and_sequences_add_up(hk):
    gt = table(FRAMES * 2, [0] * 8 + [1] * 8, [CAR] * 8 + [PEDESTRIAN] * 8,
               [BOX] * 8 + [ELSEWHERE] * 8, OCCLUDED_3_4 + [0] * 8)
    det = table(MISSED_3_4 + MISSED_3_4, [-1] * 12, [CAR] * 6 + [PEDESTRIAN] * 6,
                [BOX] * 6 + [ELSEWHERE] * 6)
    res = table(FRAMES * 2, [7] * 8 + [3] * 8, [CAR] * 8 + [PEDESTRIAN] * 8,
                [BOX] * 8 + [ELSEWHERE] * 8)
    one = hk.count_sequence(gt, det, res)
    assert one["car"]["hidden"]["kept"] == 1 and one["pedestrian"]["hidden"]["stretches"] == 0
    assert one["pedestrian"]["missed"] == {"stretches": 1, "held_before": 1, "kept": 1,
                                           "same_after": 1}
    total: dict = {}
    hk.add(total, one)
    hk.add(total, one)
    assert total["car"]["hidden"]["kept"] == 2 and total["pedestrian"]["missed"]["kept"] == 2
    text = hk.format_table({"none": total})
    assert "hidden" in text and "all missed" in text and "100.0%" in text
