"""The learnt score term of the clutter density: ScoreLearner's prior table, its discounted EM
statistics and shrunk log ratios (exactly, by hand), what it learns from simulated clutter
probabilities (Monte Carlo), its memory and refresh; the filter's clutter probabilities and
the tracker that feeds them to the learner, end to end."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.models.box import edges_from_ltwh
from occtrack.models.score_model import ScoreLearner
from occtrack.scenarios.pedestrians import Crowd, crowd_scene
from occtrack.tracker import Tracker, TrackerConfig

DT = 0.1
EPS = 1e-3  # the learner's pseudo-count on each side of a bin


def centres(bins):
    return (np.arange(bins) + 0.5) / bins


def table(learner):
    """The learner's table, read through `score_term` at the bin centres."""
    return learner.score_term(centres(learner.bins))


def prior_log_ratio(learner):
    """log(g0(s_b) / g0(s_top)) of every bin, written out from g0 = max(s, floor)^-power."""
    c = np.maximum(centres(learner.bins), learner.score_floor)
    return -learner.power * (np.log(c) - np.log(c[-1]))


def in_bin(rng, b, size, bins=10):
    """`size` scores drawn uniformly inside bin b, a hundredth of a bin away from its edges."""
    return (b + rng.uniform(0.01, 0.99, size)) / bins


# -- the prior ----------------------------------------------------------------------------------

@pytest.mark.parametrize("floor, power, bins", [(0.05, 2.0, 10), (0.2, 1.5, 7), (0.01, 3.0, 2)])
def test_fresh_learner_gives_the_prior_at_every_bin(floor, power, bins):
    """g0(s_b) / g0(s_top), g0 = max(centre, floor)^-power, exactly, for any score inside
    bin b (the lower edge b / bins included), 0 and below in the first bin, 1 and above in the
    last: the top bin is 1, as g0(1) = 1 where the clutter rate was calibrated."""
    learner = ScoreLearner(score_floor=floor, power=power, bins=bins)
    c = centres(bins)
    g0 = np.maximum(c, floor) ** -power
    g0 = g0 / g0[-1]
    np.testing.assert_array_equal(table(learner), g0)
    # by hand at the ends: the first bin's centre is below the floor in the default learner
    if (floor, bins) == (0.05, 10):
        assert g0[0] == pytest.approx(400.0 * 0.95**2, rel=1e-15)
        assert g0[-1] == 1.0
    rng = np.random.default_rng(bins)
    for b in range(bins):
        scores = np.concatenate([[b / bins, c[b]], in_bin(rng, b, 20, bins)])
        np.testing.assert_array_equal(learner.score_term(scores), np.full(len(scores), g0[b]))
    np.testing.assert_array_equal(learner.score_term(np.array([0.0, -0.3, -1e6])),
                                  np.full(3, g0[0]))
    np.testing.assert_array_equal(learner.score_term(np.array([1.0, 1.7, 1e6])),
                                  np.full(3, g0[-1]))
    np.testing.assert_array_equal(learner.clutter, np.zeros(bins))
    np.testing.assert_array_equal(learner.objects, np.zeros(bins))
    np.testing.assert_allclose(learner.log_ratio(), prior_log_ratio(learner), rtol=1e-14,
                               atol=1e-15)


def test_huge_scores_land_in_the_last_bin():
    """Scores of 1 or above belong to the last bin, however large (bin_of's docstring); the
    tracker takes any finite score, so its clutter density for a score of 1e19 is that of a
    score of 1."""
    learner = ScoreLearner()
    g0 = table(learner)
    with np.errstate(invalid="ignore"):
        got = learner.score_term(np.array([1e19, 1e300, np.inf]))
    np.testing.assert_array_equal(got, np.full(3, g0[-1]))
    tracker = Tracker(config())
    boxes = np.array([[100.0, 100, 40, 100], [600, 100, 40, 100]])
    with np.errstate(invalid="ignore"):
        tracker.step(boxes, np.array([1.0, 1e19]))
        m = tracker.filter.measurement
        z = edges_from_ltwh(boxes)
        density = m.clutter_density(z, m.observed(z), np.array([1.0, 1e19]))
    assert density[1] == density[0]


def test_empty_bin_without_prior_weight():
    """prior_weight = 0 with detections in the top and lowest bins only: the other bins
    keep the prior (or the learner refuses a weight of 0 at construction)."""
    try:
        learner = ScoreLearner(prior_weight=0.0, refresh=1)
    except ValueError:
        return
    with np.errstate(invalid="ignore"):
        learner.update(np.array([0.05, 0.95]), np.array([0.8, 0.1]), DT)
        ratio = learner.log_ratio()
    assert np.isfinite(ratio).all()
    assert np.isfinite(table(learner)).all()
    np.testing.assert_allclose(ratio[1:9], prior_log_ratio(learner)[1:9], rtol=1e-14)


@pytest.mark.parametrize("bins", [1, 0])
def test_fewer_than_two_bins_are_refused(bins):
    with pytest.raises(ValueError, match="bins"):
        ScoreLearner(bins=bins)


# -- the EM statistics, exactly -------------------------------------------------------------------

FRAMES = [  # (scores, pi, dt): scores out of [0, 1] go to the first or last bin
    ([0.97, 0.12, 0.55, 0.01], [0.02, 0.8, 0.4, 0.99], 0.1),
    ([], [], 0.1),  # no detections: the sums decay all the same
    ([1.0, 0.0, 0.999, 0.5, 0.5, 0.13, 0.17, 0.14, 0.11], [0.0, 1.0, 0.1, 0.25, 0.75, 0.6, 0.9,
                                                          0.3, 0.5], 0.3),
    ([1.4, -0.2, 0.35], [1.0, 0.0, 0.6], 0.05),
    ([0.91, 0.15, 0.72, 0.05, 0.93, 0.16, 0.19, 0.1], [0.03, 0.7, 0.2, 0.95, 0.01, 0.4, 0.85,
                                                        0.65], 2.0),
]


def by_hand(frames, memory, bins=10):
    """The discounted sums of pi and 1 - pi per bin, in plain Python loops."""
    clutter, objects = [0.0] * bins, [0.0] * bins
    for scores, pis, dt in frames:
        keep = math.exp(-dt / memory)
        clutter = [c * keep for c in clutter]
        objects = [o * keep for o in objects]
        for s, p in zip(scores, pis, strict=True):
            b = min(int(min(max(s, 0.0), 1.0) * bins), bins - 1)
            clutter[b] += p
            objects[b] += 1.0 - p
    return clutter, objects


# (prior_weight 0 gives NaN in the empty bins: test_empty_bin_without_prior_weight)
@pytest.mark.filterwarnings("ignore:invalid value encountered in divide:RuntimeWarning")
@pytest.mark.parametrize("memory, prior_weight", [(60.0, 50.0), (0.5, 3.0), (1e6, 1e-9)])
def test_statistics_and_log_ratio_by_hand(memory, prior_weight):
    """After every update C_b and O_b equal the discounted bincounts (decay exp(-dt /
    memory) per update) to 1e-12; log rho_b equals (n0 prior_b + n_b learnt_b) / (n0 + n_b),
    learnt_b = log((C_b + eps) / (O_b + eps)) - the same of the top bin, n_b = min(C_b + O_b,
    C_top + O_top), written out here bin by bin."""
    learner = ScoreLearner(memory=memory, prior_weight=prior_weight)
    for t in range(1, len(FRAMES) + 1):
        scores, pis, dt = FRAMES[t - 1]
        learner.update(np.array(scores, dtype=float), np.array(pis, dtype=float), dt)
        clutter, objects = by_hand(FRAMES[:t], memory)
        np.testing.assert_allclose(learner.clutter, clutter, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(learner.objects, objects, rtol=1e-12, atol=1e-15)
    # the top bin's sum written out for the short memory: .02 (frame 1), then .1 and 0
    # (frame 3, dt .3), then 1 (frame 4: score 1.4, in the last bin), then .03 + .01
    if memory == 0.5:
        c9 = ((0.02 * math.exp(-0.2) * math.exp(-0.6) + 0.1) * math.exp(-0.1) + 1.0) \
            * math.exp(-4.0) + 0.04
        assert learner.clutter[9] == pytest.approx(c9, rel=1e-12)
    top_c, top_o = clutter[-1], objects[-1]
    # bin 1 holds more (discounted) detections than the top bin: its n is the top bin's
    assert clutter[1] + objects[1] > top_c + top_o
    theta_top = math.log((top_c + EPS) / (top_o + EPS))
    for b in range(10):
        g0 = max((b + 0.5) / 10, 0.05) ** -2.0
        prior = math.log(g0 / 0.95**-2.0)
        learnt = math.log((clutter[b] + EPS) / (objects[b] + EPS)) - theta_top
        n = min(clutter[b] + objects[b], top_c + top_o)
        if prior_weight + n == 0:
            continue  # an empty bin without a prior: test_empty_bin_without_prior_weight
        want = (prior_weight * prior + n * learnt) / (prior_weight + n)
        assert learner.log_ratio()[b] == pytest.approx(want, rel=1e-11, abs=1e-12), b
    if prior_weight == 0:
        # no prior: the top bin is 0 and a bin with detections is its learnt ratio itself
        assert learner.log_ratio()[-1] == pytest.approx(0.0, abs=1e-12)
    # bins 2, 4, 6 and 8 never had a detection: n_b = 0, the prior exactly (to rounding)
    if prior_weight > 0:
        empty = [2, 4, 6, 8]
        np.testing.assert_allclose(learner.log_ratio()[empty], prior_log_ratio(learner)[empty],
                                   rtol=1e-14)


@pytest.mark.parametrize("bins", [2, 7, 10])
def test_compiled_sums_and_lookup_are_numpys_to_the_bit(bins):
    """The compiled update and look-up (`_score_update`, `_score_lookup`) give numpy's
    expressions exactly: clip to [0, 1], times the bins, truncated, the last bin capped; the
    discount, then bincounts of pi and 1 - pi added. Scores below 0, above 1 and on every bin
    edge included."""
    rng = np.random.default_rng(bins)
    learner = ScoreLearner(bins=bins, refresh=1)
    clutter, objects = np.zeros(bins), np.zeros(bins)
    edges = np.arange(bins + 1) / bins
    for t in range(20):
        scores = np.concatenate([rng.uniform(-0.5, 1.5, 30), edges, [-0.0, 0.0, 1.0, 1e300]])
        if t == 3:
            scores = np.zeros(0)
        pis = rng.uniform(0.0, 1.0, len(scores))
        dt = rng.uniform(0.01, 2.0)
        keep = math.exp(-dt / learner.memory)
        b = (np.clip(scores, 0.0, 1.0) * bins).astype(np.int64)
        np.minimum(b, bins - 1, out=b)
        clutter *= keep
        objects *= keep
        if len(scores):
            clutter += np.bincount(b, weights=pis, minlength=bins)
            objects += np.bincount(b, weights=1.0 - pis, minlength=bins)
        learner.update(scores, pis, dt)
        assert learner.clutter.tobytes() == clutter.tobytes()
        assert learner.objects.tobytes() == objects.tobytes()
        np.testing.assert_array_equal(learner.bin_of(scores), b)
        want = np.exp(learner.log_ratio())[b]
        assert learner.score_term(scores).tobytes() == want.tobytes()


def test_a_nan_score_is_refused():
    """A NaN score has no bin: the learner says so rather than count it anywhere."""
    learner = ScoreLearner()
    with pytest.raises(ValueError, match="NaN"):
        learner.update(np.array([0.5, np.nan]), np.array([0.1, 0.2]), DT)
    with pytest.raises(ValueError, match="NaN"):
        learner.score_term(np.array([np.nan]))


# -- learning (Monte Carlo) ----------------------------------------------------------------------

def feed(learner, rng, frames, per_bin, alpha_beta, dt=DT):
    """`frames` updates, each with `per_bin[b]` detections of scores inside bin b and clutter
    probabilities drawn from Beta(alpha_beta[b]) (mean a / (a + b))."""
    for _ in range(frames):
        scores, pis = [], []
        for b, k in per_bin.items():
            if k:
                scores.append(in_bin(rng, b, k))
                pis.append(rng.beta(*alpha_beta[b], size=k))
        if not scores:
            learner.update(np.zeros(0), np.zeros(0), dt)
            continue
        learner.update(np.concatenate(scores), np.concatenate(pis), dt)


LOW, TOP = range(5), 9


def test_clutter_at_low_scores_raises_their_ratio():
    """Bins 0-4: 4 detections a frame with pi ~ Beta(9, 1) (mean .9); bin 9: 4 with pi ~
    Beta(1, 99) (mean .01); bins 5-8 none. 3000 frames of 0.1 s with a memory of 60 s hold
    n = 4 (1 - e^-5) / (1 - e^(-1/600)) = 2384 discounted detections in each filled bin; the
    learnt log ratio tends to log(.9 / .1) - log(.01 / .99) = log(891) = 6.79. Standard
    errors (effective sample 2 memory / dt per detection stream, 4800): log odds of the low
    bins .013 (Beta(9, 1) sd .090 over a mean 1 - pi of .1), of the top bin .014 (sd .0099
    over .01): .02 on the difference, so a tolerance of .1 (5 standard errors). Every low
    bin rises above the prior's relative ratio (bin 4's 1.49 to about 6.6) and the table's
    ratio g(s_b) / g(s_top) with it; the empty bins keep the prior (to rounding)."""
    learner = ScoreLearner(memory=60.0)
    rng = np.random.default_rng(11)
    per_bin = {b: 4 for b in LOW} | {TOP: 4}
    ab = {b: (9.0, 1.0) for b in LOW} | {TOP: (1.0, 99.0)}
    feed(learner, rng, 3000, per_bin, ab)
    n = 4 * (1 - math.exp(-5)) / (1 - math.exp(-DT / 60))
    assert learner.clutter[0] + learner.objects[0] == pytest.approx(n, rel=1e-9)
    prior = prior_log_ratio(learner)
    learnt = math.log(891.0)
    want = (50 * prior + n * learnt) / (50 + n)
    got = learner.log_ratio()
    np.testing.assert_allclose(got[list(LOW)], want[list(LOW)], atol=0.1)
    assert (got[list(LOW)] > prior[list(LOW)] + 0.5).all()
    g, g0 = table(learner), table(ScoreLearner())
    assert (g[list(LOW)] / g[TOP] > g0[list(LOW)] / g0[TOP]).all()
    np.testing.assert_allclose(np.log(g[list(LOW)] / g[TOP]), got[list(LOW)], rtol=1e-12)
    # the level stays anchored: the top bin's g is g0's there
    assert got[TOP] == 0.0
    assert g[TOP] == pytest.approx(g0[TOP], rel=1e-15)
    empty = [5, 6, 7, 8]
    np.testing.assert_allclose(got[empty], prior[empty], rtol=1e-14)
    np.testing.assert_allclose(g[empty], g0[empty], rtol=1e-13)


def test_equal_clutter_odds_everywhere_give_a_flat_ratio():
    """pi ~ Beta(3, 7) (mean .3) in every bin but bin 7, 4 detections a frame each; 3000
    frames with a memory of 600 s: n = 4 (1 - e^-.5) / (1 - e^(-1/6000)) = 9443 per bin. The
    learnt log ratio is 0 up to noise (log odds sd .0046 per bin, Beta(3, 7) sd .138 over
    about 12000 effective detections; .0065 on a difference) and the shrinkage keeps
    50 / (50 + n) = .5 % of the prior (.031 in bin 0, whose prior is 5.89): every filled bin
    within .07 of 0 (.031 + 6 standard errors). The same run with a memory of 30 s (n = 1200,
    4 % of the prior) is further from 0 in bin 0: the ratio tends to 0 with the data. Bin 7,
    empty, keeps the prior."""
    filled = [0, 1, 2, 3, 4, 5, 6, 8, 9]
    per_bin = {b: 4 for b in filled}
    ab = {b: (3.0, 7.0) for b in filled}
    long, short = ScoreLearner(memory=600.0), ScoreLearner(memory=30.0)
    feed(long, np.random.default_rng(5), 3000, per_bin, ab)
    feed(short, np.random.default_rng(5), 3000, per_bin, ab)
    got = long.log_ratio()
    prior = prior_log_ratio(long)
    assert prior[0] > 5.8
    assert np.abs(got[filled]).max() < 0.07
    assert got[7] == pytest.approx(prior[7], rel=1e-14)
    assert short.log_ratio()[0] > got[0] + 0.1  # 4 % of 5.89 against .5 %
    assert short.log_ratio()[0] < 0.5  # but far from the prior already
    np.testing.assert_allclose(table(long)[filled], table(long)[TOP], rtol=0.08)


# -- memory -----------------------------------------------------------------------------------

def test_the_table_follows_the_latest_data():
    """Low-score clutter (as above) for 600 s, then equal odds everywhere for 1200 s = 20
    memories of 60 s: what is left of the first run is e^-20 = 2e-9 of it, so the log ratios
    equal those of a learner fed the second run alone to 1e-6 (and the table to 1e-6
    relative), where before the switch bin 0 was more than 0.5 above them; the ratios are
    those of flat odds. Both learners
    see the same second run (same seed), updates counted alike so they refresh together."""
    per_bin = {b: 4 for b in range(10)}
    clutter_low = {b: (9.0, 1.0) if b < 5 else (1.0, 99.0) for b in range(10)}
    flat = {b: (3.0, 7.0) for b in range(10)}
    learner, fresh = ScoreLearner(memory=60.0), ScoreLearner(memory=60.0)
    feed(learner, np.random.default_rng(1), 600, per_bin, clutter_low, dt=1.0)
    feed(fresh, np.random.default_rng(2), 600, {}, {}, dt=1.0)  # no detections: sums stay 0
    before = learner.log_ratio()
    feed(learner, np.random.default_rng(3), 1200, per_bin, flat, dt=1.0)
    feed(fresh, np.random.default_rng(3), 1200, per_bin, flat, dt=1.0)
    after, alone = learner.log_ratio(), fresh.log_ratio()
    assert before[0] > alone[0] + 0.5
    np.testing.assert_allclose(after, alone, rtol=0, atol=1e-6)
    np.testing.assert_allclose(table(learner), table(fresh), rtol=1e-6)
    np.testing.assert_allclose(learner.clutter, fresh.clutter, rtol=1e-7)
    # the flat odds' shape: a learnt ratio of 0 shrunk towards the prior with n = 4 / (1 -
    # e^(-1/60)) = 242 per bin, i.e. 50 / (50 + n) = 17 % of the prior; noise .027 (.023 log
    # odds per bin, 480 effective detections of sd .138 over .3, times sqrt 2 and n / (50 +
    # n)): within .15
    n = 4 / (1 - math.exp(-1 / 60))
    assert learner.clutter[0] + learner.objects[0] == pytest.approx(n, rel=1e-6)
    np.testing.assert_allclose(after, 50 / (50 + n) * prior_log_ratio(learner), atol=0.15)


# -- refresh ----------------------------------------------------------------------------------

@pytest.mark.parametrize("refresh", [1, 4, 10])
def test_table_is_renewed_every_refresh_updates(refresh):
    """Data that moves the statistics every update (a clutter share that grows with t in
    the low bins): the table is the prior until update `refresh`, is exp(log_ratio) of that
    moment at every multiple of `refresh` and unchanged in between."""
    learner = ScoreLearner(refresh=refresh, prior_weight=5.0)
    last = table(learner).copy()
    assert np.array_equal(last, table(ScoreLearner()))
    rng = np.random.default_rng(refresh)
    for t in range(1, 3 * refresh + 3):
        scores = np.concatenate([in_bin(rng, 1, 3), in_bin(rng, 9, 3)])
        pi = np.array([min(0.1 * t, 1.0)] * 3 + [0.05] * 3)
        learner.update(scores, pi, DT)
        now = table(learner)
        if t % refresh == 0:
            np.testing.assert_allclose(now, np.exp(learner.log_ratio()), rtol=1e-14)
            assert not np.array_equal(now, last), t
        else:
            np.testing.assert_array_equal(now, last)
            assert not np.allclose(now, np.exp(learner.log_ratio()), rtol=1e-6)
        last = now.copy()


# -- the filter's clutter probabilities ------------------------------------------------------

def config(**changes):
    return TrackerConfig(occlusion="none", camera_motion="none", image_size=(1242.0, 375.0),
                         fps=10.0, **changes)


def test_clutter_probability_of_a_tracked_box_and_an_isolated_one():
    """One box tracked for 11 frames (score .95), then a 12th frame with it and an isolated
    box of score .15 far from it: `clutter_probability` has one entry per detection, in
    [0, 1]; the tracked box's is below 1e-3, the isolated one's above .5 (it has nothing
    to explain it but clutter or a birth, and its low score favours clutter). With no
    detections the array is empty."""
    tracker = Tracker(config())
    for t in range(11):
        tracker.step(np.array([[400.0 + 5 * t, 150, 50, 120]]), np.array([0.95]))
        pi = tracker.filter.clutter_probability
        assert pi.shape == (1,)
        assert 0.0 <= pi[0] <= 1.0
    assert pi[0] < 1e-3
    boxes = np.array([[455.0, 150, 50, 120], [1000.0, 60, 30, 70]])
    tracker.step(boxes, np.array([0.95, 0.15]))
    pi = tracker.filter.clutter_probability
    assert pi.shape == (2,)
    assert ((pi >= 0) & (pi <= 1)).all()
    assert pi[0] < 1e-3
    assert pi[1] > 0.5
    # a high score makes the isolated box less likely clutter
    high = Tracker(config())
    for t in range(11):
        high.step(np.array([[400.0 + 5 * t, 150, 50, 120]]), np.array([0.95]))
    high.step(boxes, np.array([0.95, 0.95]))
    assert high.filter.clutter_probability[1] < pi[1]
    tracker.step(np.zeros((0, 4)), np.zeros(0))
    assert tracker.filter.clutter_probability.shape == (0,)


def test_clutter_probability_in_unit_interval_in_a_crowd():
    """A crowd with occlusion (measurement-wise, where seen_hidden reduces the clutter share)
    and a few false boxes: at every frame one probability per detection, all in [0, 1],
    most detections of a confirmed track well below .5."""
    scene = crowd_scene(Crowd(people=8, frames=60), seed=4)
    tracker = Tracker(TrackerConfig(occlusion="measurement-wise"))
    taken = []
    for rows in scene.detections.frame_slices(scene.frames):
        tracker.step(scene.detections.box[rows], scene.detections.score[rows])
        f = tracker.filter
        pi = f.clutter_probability
        assert pi.shape == (len(scene.detections.box[rows]),)
        assert ((pi >= 0) & (pi <= 1)).all()
        j = f.slot_detection[f.slot_used & (f.slot_hits >= 5) & (f.slot_detection >= 0)]
        taken.extend(pi[j])
    assert len(taken) > 100
    assert np.median(taken) < 0.05


# -- the tracker ------------------------------------------------------------------------------

def cluttered_frames(frames=30, seed=0):
    """Two boxes walking (score .9) and, at every frame, one or two false boxes at random
    places and sizes with scores in bin 1 (.1 - .2)."""
    rng = np.random.default_rng(seed)
    out = []
    for t in range(frames):
        boxes = [[200.0 + 4 * t, 120, 40, 100], [800.0 - 3 * t, 150, 50, 120]]
        scores = [0.9, 0.9]
        for _ in range(rng.integers(1, 3)):
            h = rng.uniform(40, 110)
            boxes.append([rng.uniform(0, 1242 - 0.4 * h), rng.uniform(0, 375 - h), 0.4 * h, h])
            scores.append(rng.uniform(0.11, 0.19))
        out.append((np.array(boxes), np.array(scores)))
    return out


def test_tracker_learns_the_score_term():
    """With learn_score_model (the default) the measurement model's score_model is the
    learner, fresh with the configured floor and power; each step feeds it the frame's
    scores, the filter's clutter probabilities and the step's dt (an independent learner fed
    the same reproduces its sums exactly, a dt=0.3 step included); after 30 frames of
    low-score clutter its table differs from the prior, bin 1 above it, and the clutter
    density is clutter_rate g(s) / (W H w h) with the learnt g."""
    c = config(clutter_rate=3.5, clutter_score_power=1.5, score_floor=0.1)
    assert c.learn_score_model
    tracker = Tracker(c)
    model = tracker.filter.measurement.score_model
    assert isinstance(model, ScoreLearner)
    g0 = np.maximum(centres(10), 0.1) ** -1.5
    g0 = g0 / g0[-1]
    np.testing.assert_array_equal(table(model), g0)
    mirror = ScoreLearner(0.1, 1.5)
    for t, (boxes, scores) in enumerate(cluttered_frames()):
        dt = 0.3 if t == 7 else None
        tracker.step(boxes, scores, dt=dt)
        mirror.update(scores, tracker.filter.clutter_probability, 0.3 if t == 7 else 0.1)
        np.testing.assert_array_equal(model.clutter, mirror.clutter)
        np.testing.assert_array_equal(model.objects, mirror.objects)
    assert tracker.filter.measurement.score_model is model
    learnt = table(model)
    assert not np.allclose(learnt, g0, rtol=1e-6)
    assert learnt[1] > 1.5 * g0[1]  # the bin of the false boxes
    np.testing.assert_array_equal(learnt, table(mirror))
    boxes, scores = cluttered_frames(1, seed=9)[0]
    z = edges_from_ltwh(boxes)
    m = tracker.filter.measurement
    W, H = c.image_size
    want = 3.5 / (W * H * (boxes[:, 2] * boxes[:, 3])) * model.score_term(scores)
    np.testing.assert_allclose(m.clutter_density(z, m.observed(z), scores), want, rtol=1e-14)


def test_without_learning_the_clutter_density_is_the_power_law():
    """learn_score_model=False: no score_model, before and after frames, and the clutter
    density is clutter_rate max(min(s, 1), floor)^-power / (W H w h) exactly."""
    c = config(learn_score_model=False, clutter_rate=3.5, clutter_score_power=1.5,
               score_floor=0.1)
    tracker = Tracker(c)
    assert tracker.filter.measurement.score_model is None
    for boxes, scores in cluttered_frames(15):
        tracker.step(boxes, scores)
    m = tracker.filter.measurement
    assert m.score_model is None
    boxes = np.array([[10.0, 20, 40, 100], [300, 50, 25, 64], [600, 0, 33, 90],
                      [900, 100, 50, 120], [1000, 200, 16, 32]])
    scores = np.array([0.01, 0.1, 0.37, 0.95, 1.0])
    z = edges_from_ltwh(boxes)
    W, H = 1242.0, 375.0
    want = 3.5 / (W * H * (boxes[:, 2] * boxes[:, 3])) * np.clip(scores, 0.1, 1.0) ** -1.5
    np.testing.assert_array_equal(m.clutter_density(z, m.observed(z), scores), want)
    term = want * W * H * boxes[:, 2] * boxes[:, 3] / 3.5
    np.testing.assert_allclose(term, [0.1**-1.5, 0.1**-1.5, 0.37**-1.5, 0.95**-1.5, 1.0],
                               rtol=1e-14)  # below the floor: the floor's
    assert want[4] == pytest.approx(3.5 / (W * H * 16 * 32), rel=1e-15)


def test_learnt_table_is_repeatable():
    """Two trackers over the same frames learn identical sums and tables, and the first
    again after reset() (which starts from the prior)."""
    frames = cluttered_frames(35, seed=3)
    first, second = Tracker(config()), Tracker(config())
    for boxes, scores in frames:
        first.step(boxes, scores)
        second.step(boxes, scores)
    a, b = first.filter.measurement.score_model, second.filter.measurement.score_model
    assert a is not b
    np.testing.assert_array_equal(a.clutter, b.clutter)
    np.testing.assert_array_equal(a.objects, b.objects)
    grid = np.linspace(0, 1, 101)
    np.testing.assert_array_equal(a.score_term(grid), b.score_term(grid))
    assert not np.array_equal(table(a), table(ScoreLearner()))
    first.reset()
    fresh = first.filter.measurement.score_model
    np.testing.assert_array_equal(table(fresh), table(ScoreLearner()))
    for boxes, scores in frames:
        first.step(boxes, scores)
    np.testing.assert_array_equal(fresh.score_term(grid), a.score_term(grid))
    np.testing.assert_array_equal(fresh.clutter, a.clutter)
