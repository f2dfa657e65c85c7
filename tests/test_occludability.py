"""The learnt occludability: its weighted least-squares sums by hand, what it learns from
simulated hits of hidden objects (Monte Carlo), the compiled per-frame sums against numpy, and
what it does in the tracker (a person a detector keeps seeing behind another lowers it, one it
never sees again raises it)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.filters.gmpmb.weights import _hidden_evidence
from occtrack.models.occludability import OccludabilityLearner
from occtrack.tracker import Tracker, TrackerConfig


def test_the_prior_until_hidden_objects_teach_it_and_then_least_squares_by_hand():
    learner = OccludabilityLearner(0.8, prior_weight=20.0, memory=60.0, hidden=0.8)
    assert learner.value == 0.8
    # objects under `hidden` say nothing
    learner.update(np.array([1.0, 1.0]), np.array([0.0, 0.79]), np.array([False, False]),
                   0.9, dt=0.1)
    assert (learner.evidence, learner.weight, learner.value) == (0.0, 0.0, 0.8)
    # a hidden object of weight 1 missed (u = 1) and one of weight 1/2 detected (u = .9)
    d = 0.9
    learner.update(np.array([1.0, 0.5]), np.array([1.0, 0.9]), np.array([False, True]), d,
                   dt=0.1)
    a = 1.0 * 1.0 * 1.0 + 0.5 * 0.9 * (1.0 - 1.0 / d)
    b = 1.0 + 0.5 * 0.81
    keep = math.exp(-0.1 / 60.0)
    assert learner.evidence == pytest.approx(a, rel=1e-12)  # (0 discounted is 0)
    assert learner.value == pytest.approx((a + 20 * 0.8) / (b + 20), rel=1e-12)
    # a memory's ln 2 later the old sums weigh half, and a new miss comes in whole
    learner.update(np.array([1.0]), np.array([1.0]), np.array([False]), d,
                   dt=60.0 * math.log(2))
    assert learner.evidence == pytest.approx(a / 2 + 1.0, rel=1e-12)
    assert learner.weight == pytest.approx(b * keep / keep / 2 + 1.0, rel=1e-12)
    assert learner.value == pytest.approx((a / 2 + 1.0 + 16.0) / (b / 2 + 1.0 + 20.0),
                                          rel=1e-12)


def test_the_value_stays_a_probability():
    always_seen = OccludabilityLearner(0.8, prior_weight=1.0)
    for _ in range(50):  # hidden, detected every frame: 1 - h / d < 0
        always_seen.update(np.ones(3), np.ones(3), np.ones(3, bool), 0.5, dt=0.1)
    assert always_seen.evidence < 0 and always_seen.value == 0.0
    never_seen = OccludabilityLearner(0.8, prior_weight=1.0)
    never_seen.update(np.ones(3), np.full(3, 0.8), np.zeros(3, bool), 0.9, dt=0.1)
    assert (3 * 0.8 + 0.8) / (3 * 0.64 + 1.0) > 1.0
    assert never_seen.value == 1.0


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="prior occludability"):
        OccludabilityLearner(1.5)
    with pytest.raises(ValueError, match="positive"):
        OccludabilityLearner(0.8, memory=0.0)
    with pytest.raises(ValueError, match="hidden"):
        OccludabilityLearner(0.8, hidden=0.0)


@pytest.mark.parametrize("p_seen", [0.1, 0.6, 0.85])
def test_learns_one_minus_the_hidden_objects_detection_rate_over_d(p_seen):
    """Fully hidden objects (u = 1) detected with probability p_seen, d = .9: without a
    memory's forgetting the value is (sum (1 - h / d) + n0 o0) / (N + n0), whose expectation
    is (N (1 - p / d) + n0 o0) / (N + n0); it lands within 4 standard errors of it (the
    standard error of the mean of 1 - h / d is sqrt(p (1 - p)) / d / sqrt(N))."""
    rng = np.random.default_rng(int(p_seen * 100))
    d, n0, o0, frames, objects = 0.9, 20.0, 0.8, 2000, 5
    learner = OccludabilityLearner(o0, prior_weight=n0, memory=1e12)
    for _ in range(frames):
        learner.update(np.ones(objects), np.ones(objects), rng.random(objects) < p_seen, d,
                       dt=0.1)
    N = frames * objects
    want = (N * (1.0 - p_seen / d) + n0 * o0) / (N + n0)
    se = math.sqrt(p_seen * (1 - p_seen)) / d / math.sqrt(N) * N / (N + n0)
    assert abs(learner.value - max(0.0, want)) < 4 * se


def test_the_compiled_sums_are_the_learners_own():
    """`_hidden_evidence` (the filter's one pass over components and slots) gives the sums
    `OccludabilityLearner.update` takes from per-object arrays: u_i = 1 - sum_k (w_k / r_i)
    v_k (1 - q_k) over the components of slot i, confirmed slots only."""
    rng = np.random.default_rng(5)
    for trial in range(30):
        L, n = 12, 60
        label = rng.integers(-1, L, n)
        within = rng.random(n)
        for i in range(L):  # each slot's weights sum to one, as w_k / r_i do
            m = label == i
            if m.any():
                within[m] /= within[m].sum()
        v = rng.random(n) * (rng.random(n) < 0.5)
        q = rng.random(n) * (rng.random(n) < 0.3)
        r = rng.random(L)
        used = rng.random(L) < 0.8
        hits = rng.integers(0, 6, L)
        detection = rng.integers(-1, 3, L)
        d, hidden = 0.93, [0.8, 0.5, 1e-9][trial % 3]
        seen = np.bincount(label[label >= 0], weights=(within * v * (1 - q))[label >= 0],
                           minlength=L)
        confirmed = used & (hits >= 3)
        learner = OccludabilityLearner(0.8, hidden=hidden, memory=1e12)
        learner.update(r[confirmed], 1.0 - seen[confirmed], detection[confirmed] >= 0, d,
                       dt=0.0)
        a, b = _hidden_evidence(label, within, v, q, r, used, hits, 3, detection, d, hidden)
        assert a == pytest.approx(learner.evidence, rel=1e-12, abs=1e-12)
        assert b == pytest.approx(learner.weight, rel=1e-12, abs=1e-12)


def pair_frames(frames: int, rear_seen: bool) -> list[tuple[np.ndarray, np.ndarray]]:
    """A person standing (bottom at 600 px) and one farther away (bottom at 530 px) who
    walks behind them at 150 px/s and stays there, box inside the front one's from frame 56:
    both detected every frame, or the rear one only while less than half of its box is
    behind the front one (`rear_seen` False: the detector misses hidden people)."""
    front = np.array([600.0, 300.0, 100.0, 300.0])
    out = []
    for t in range(frames):
        x = max(610.0, 900.0 - 5.0 * t)
        rear = np.array([x, 290.0, 80.0, 240.0])
        behind = min(80.0, max(0.0, 700.0 - x)) / 80.0
        boxes = [front, rear] if (rear_seen or behind < 0.5) else [front]
        out.append((np.array(boxes), np.full(len(boxes), 0.9)))
    return out


@pytest.mark.parametrize("rear_seen", [True, False])
def test_a_detector_that_sees_behind_people_lowers_it_one_that_does_not_raises_it(rear_seen):
    config = TrackerConfig(image_size=(1920.0, 1080.0), fps=30.0, camera_motion="none")
    tracker = Tracker(config)
    o = []
    for boxes, scores in pair_frames(150, rear_seen):
        tracker.step(boxes, scores)
        o.append(tracker.filter.occludability.stationary)
    assert o[29] == 0.8  # nobody hidden yet: the prior
    learner = tracker.filter.occludability_learner
    assert learner.weight > 0  # the rear person was hidden, in the model's eyes too
    if rear_seen:
        assert o[-1] < 0.2  # hidden and found every frame: hardly ever lost
    else:
        assert o[-1] > 0.8  # hidden and never found
    off = Tracker(config.replace(learn_occludability=False))
    for boxes, scores in pair_frames(150, rear_seen):
        off.step(boxes, scores)
    assert off.filter.occludability_learner is None
    assert off.filter.occludability.stationary == 0.8


def test_the_compiled_sums_refuse_a_label_past_the_slots():
    ones = np.ones(2)
    with pytest.raises(ValueError, match="past the slots"):
        _hidden_evidence(np.array([0, 3]), ones, ones, ones * 0, np.ones(3),
                         np.ones(3, bool), np.full(3, 5), 3, np.zeros(3, np.int64), 0.9, 0.8)
