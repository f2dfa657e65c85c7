"""The learnt half-size process noise: SizeNoiseLearner (method of moments over two lags)
against simulated random walks, its floor, blend and ring buffers; SizeHistory's bookkeeping
of the detections each label slot takes; the tracker that learns it, end to end."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from occtrack.models.box import MIN_HEIGHT
from occtrack.models.motion import SizeNoiseLearner
from occtrack.tracker import Tracker, TrackerConfig
from occtrack.tracker.sizes import SizeHistory

DT = 0.1
C = SizeNoiseLearner.CHI2_MEDIAN


def variance(diffs):
    """The learner's robust variance: median of d^2 over the median of chi-square(1)."""
    return float(np.median(np.square(diffs))) / C


def simulate(rng, q, sigma, objects=1000, frames=20, lag=3):
    """Lag-1 and lag-`lag` changes of measured half-sizes (box heights, h = 1): each true
    half-size a random walk of q per sqrt(s) sampled every DT s, measured with N(0, sigma)."""
    steps = rng.normal(0.0, q * math.sqrt(DT), (objects, frames))
    measured = np.cumsum(steps, axis=1) + rng.normal(0.0, sigma, (objects, frames))
    return measured[:, 1:] - measured[:, :-1], measured[:, lag:] - measured[:, :-lag]


# -- SizeNoiseLearner: Monte Carlo --------------------------------------------------------------

@pytest.mark.parametrize("q, sigma", [(0.2, 0.01), (0.1, 0.02), (0.05, 0.03)])
def test_learnt_noise_agrees_with_simulated_random_walks(q, sigma):
    """1000 objects x 20 frames (19000 lag-1 and 17000 lag-3 changes, all in memory), a
    tiny prior and prior_weight 0 (no pull towards it: the blend is tested below). Over
    R = 40 seeded runs the mean estimate is within 3 standard errors of q, the standard
    error being the measured spread of the runs over sqrt(R) (about 0.3 % of q where the
    drift dominates, 0.8 % at q = 0.05, sigma = 0.03, where 2 sigma^2 is 7 times q^2 dt).
    The spread itself is bounded (a run within 8 % of q), so the test has power: a wrong
    chi-square median (0.5) is off by 4.6 %, a wrong lag scale (L instead of L - 1) by
    18 %, and the lag-1 variance alone (the detection noise left in) by 34 % at q = 0.1,
    sigma = 0.02."""
    runs = 40
    estimates, naive = [], []
    for seed in range(runs):
        rng = np.random.default_rng([seed, round(q * 1000), round(sigma * 1000)])
        d1, d3 = simulate(rng, q, sigma)
        learner = SizeNoiseLearner(1e-6, lag=3, memory=20000, prior_weight=0)
        learner.add(1, d1)
        learner.add(3, d3)
        estimates.append(learner.noise(DT))
        naive.append(math.sqrt(variance(d1) / DT))
    estimates = np.array(estimates)
    spread = estimates.std(ddof=1)
    standard_error = spread / math.sqrt(runs)
    assert spread < 0.08 * q
    assert abs(estimates.mean() - q) < 3 * standard_error
    # the lag-1 variance alone holds 2 sigma^2 as well: far outside these errors
    if sigma / q >= 0.2:
        assert np.mean(naive) - q > 10 * standard_error


# -- SizeNoiseLearner: floor, blend, memory ---------------------------------------------------

def test_no_data_gives_the_prior_exactly():
    learner = SizeNoiseLearner(0.044)
    assert learner.noise(DT) == 0.044
    learner.add(1, [0.3])
    learner.add(3, [0.9])  # one difference of each lag: too few
    assert learner.noise(DT) == 0.044
    only_one_lag = SizeNoiseLearner(0.044)
    only_one_lag.add(3, np.linspace(-1, 1, 50))
    assert only_one_lag.noise(DT) == 0.044
    learner.add(1, [np.nan, np.inf, -np.inf])  # not finite: not counted
    learner.add(3, [np.nan])
    assert learner.noise(DT) == 0.044


@pytest.mark.parametrize("q1, q3", [(0.01, 0.012), (0.02, 0.01), (0.03, 0.03)])
def test_noise_below_the_prior_gives_the_prior_exactly(q1, q3):
    """Lag-3 changes hardly wider than lag-1 ones (or narrower: a negative moment estimate)
    give q_hat below the prior of 0.2, and the prior comes back unchanged."""
    rng = np.random.default_rng(3)
    learner = SizeNoiseLearner(0.2, memory=500)
    learner.add(1, rng.normal(0, q1, 400))
    learner.add(3, rng.normal(0, q3, 400))
    assert learner.noise(DT) == 0.2


@pytest.mark.parametrize("n1, n3, memory, weight", [
    (150, 120, 1000, 200),  # n = 120 < prior_weight
    (200, 200, 1000, 200),  # n = prior_weight: half the excess
    (300, 700, 100, 50),  # past the memory: n = 100
    (40, 60, 1000, 0),  # no prior weight: the estimate itself
])
def test_blend_of_prior_and_estimate(n1, n3, memory, weight):
    """q^2 = q0^2 + n / (n0 + n) max(q_hat^2 - q0^2, 0), n = min(n_1, n_L, memory), q_hat^2
    = (V_L - V_1) / ((L - 1) dt) from the last `memory` changes of each lag."""
    rng = np.random.default_rng(n1 + n3)
    d1, d3 = rng.normal(0, 0.02, n1), rng.normal(0, 0.06, n3)
    q0 = 0.05
    learner = SizeNoiseLearner(q0, lag=3, memory=memory, prior_weight=weight)
    learner.add(1, d1)
    learner.add(3, d3)
    q_hat2 = (variance(d3[-memory:]) - variance(d1[-memory:])) / (2 * DT)
    assert q_hat2 > 2 * q0**2
    n = min(n1, n3, memory)
    expected = math.sqrt(q0**2 + n / (weight + n) * (q_hat2 - q0**2))
    assert learner.noise(DT) == pytest.approx(expected, rel=1e-12, abs=0)
    if n == weight:
        assert learner.noise(DT) ** 2 - q0**2 == pytest.approx((q_hat2 - q0**2) / 2, rel=1e-9)
    # with another dt q^2 scales by 1 / dt
    other = math.sqrt(q0**2 + n / (weight + n) * (q_hat2 * DT / 0.04 - q0**2))
    assert learner.noise(0.04) == pytest.approx(other, rel=1e-12, abs=0)


@pytest.mark.parametrize("lag", [3, 5])
def test_ring_buffer_keeps_only_the_last_memory_changes(lag):
    """Huge changes (q of tens of h / sqrt(s)) then `memory` small ones, fed in chunks that
    wrap around the ring: the estimate is exactly that of the small ones alone, the huge
    ones forgotten; one add of more than `memory` changes keeps its last `memory`."""
    memory = 50
    rng = np.random.default_rng(lag)
    huge1, huge_l = rng.normal(0, 3, 61), rng.normal(0, 30, 137)
    small1, small_l = rng.normal(0, 0.02, memory), rng.normal(0, 0.08, memory)
    learner = SizeNoiseLearner(0.01, lag=lag, memory=memory, prior_weight=10)
    learner.add(1, huge1)
    learner.add(lag, huge_l)
    for start in range(0, memory, 7):
        learner.add(1, small1[start:start + 7])
        learner.add(lag, small_l[start:start + 7])
    fresh = SizeNoiseLearner(0.01, lag=lag, memory=memory, prior_weight=10)
    fresh.add(1, small1)
    fresh.add(lag, small_l)
    assert learner.noise(DT) == fresh.noise(DT)
    assert fresh.noise(DT) > 0.01  # the small ones do raise it above the prior
    assert learner.noise(DT) < 0.5  # the huge ones would give tens
    np.testing.assert_array_equal(np.sort(learner._diffs[1]), np.sort(small1))
    np.testing.assert_array_equal(np.sort(learner._diffs[lag]), np.sort(small_l))
    at_once = SizeNoiseLearner(0.01, lag=lag, memory=memory, prior_weight=10)
    at_once.add(1, np.concatenate([huge1, small1]))
    at_once.add(lag, np.concatenate([huge_l, small_l]))
    assert at_once.noise(DT) == fresh.noise(DT)
    # before the small ones came, the huge ones were in
    before = SizeNoiseLearner(0.01, lag=lag, memory=memory, prior_weight=10)
    before.add(1, huge1)
    before.add(lag, huge_l)
    assert before.noise(DT) > 10


@pytest.mark.parametrize("lag", [1, 0, -2])
def test_lag_below_two_is_refused(lag):
    with pytest.raises(ValueError, match="lag"):
        SizeNoiseLearner(0.044, lag=lag)


# -- SizeHistory --------------------------------------------------------------------------------

class RecordingLearner(SizeNoiseLearner):
    """A learner that keeps every `add` call (lag, changes)."""

    def __init__(self):
        super().__init__(0.044, lag=3)
        self.calls: list[tuple[int, np.ndarray]] = []

    def add(self, lag, diffs):
        self.calls.append((lag, np.array(diffs, dtype=float).ravel()))
        super().add(lag, diffs)


FRAMES = 11
# slot -> {frame: serial} of the frames the slot takes a detection; slot 1 exists from frame
# 1 (the filter's slot arrays grow), misses frame 5 (its Bernoulli lives on; the ring entry
# frame 5 would use still holds frame 1's sizes) and is reused by another Bernoulli (serial
# 21) from frame 7
TAKES = {0: {t: 10 for t in range(FRAMES)},
         1: {1: 20, 2: 20, 3: 20, 4: 20, 6: 20, 7: 21, 8: 21, 9: 21, 10: 21}}
SERIAL = {0: [10] * FRAMES, 1: [-1, 20, 20, 20, 20, 20, 20, 21, 21, 21, 21]}
# (slot, frame) -> the axis (0: x, 1: y) with an edge on the border (not measured)
CUT = {(0, 3): 0, (1, 9): 1}
# frame -> lag -> [(slot, earlier frame, axes)], in the order the learner gets them (by slot,
# then x before y), written out by hand from TAKES, SERIAL and CUT
EXPECTED = {
    1: {1: [(0, 0, "xy")], 3: []},
    2: {1: [(0, 1, "xy"), (1, 1, "xy")], 3: []},
    3: {1: [(0, 2, "y"), (1, 2, "xy")], 3: [(0, 0, "y")]},
    4: {1: [(0, 3, "y"), (1, 3, "xy")], 3: [(0, 1, "xy"), (1, 1, "xy")]},
    5: {1: [(0, 4, "xy")], 3: [(0, 2, "xy")]},  # slot 1 missed
    6: {1: [(0, 5, "xy")], 3: [(0, 3, "y"), (1, 3, "xy")]},  # slot 1: no lag 1 over the miss
    7: {1: [(0, 6, "xy")], 3: [(0, 4, "xy")]},  # slot 1 reused: nothing from serial 20
    8: {1: [(0, 7, "xy"), (1, 7, "xy")], 3: [(0, 5, "xy")]},
    9: {1: [(0, 8, "xy"), (1, 8, "x")], 3: [(0, 6, "xy")]},  # slot 1 at 6: serial 20
    10: {1: [(0, 9, "xy"), (1, 9, "x")], 3: [(0, 7, "xy"), (1, 7, "xy")]},
}


def history_boxes():
    """Per frame the detections (ltwh, px; one not taken) and their `observed`, and which
    detection each slot took; slot 1's detection comes first on odd frames."""
    rng = np.random.default_rng(7)
    size = {0: rng.uniform(30, 120, (FRAMES, 2)), 1: rng.uniform(30, 120, (FRAMES, 2))}
    frames = []
    for t in range(FRAMES):
        slots = [s for s in (1, 0) if t in TAKES[s]]
        if t % 2 == 0:
            slots = slots[::-1]
        boxes = [[200.0 + 300 * s, 100.0, *size[s][t]] for s in slots] + [[900, 50, 40, 80]]
        observed = np.ones((len(boxes), 2, 2), bool)
        took = np.full(len(SERIAL), -1)
        for j, s in enumerate(slots):
            took[s] = j
            if (s, t) in CUT:
                observed[j, CUT[s, t], j % 2] = False  # one edge of that axis on the border
        L = 1 if t == 0 else 2
        serial = np.array([SERIAL[s][t] for s in range(L)], np.int64)
        frames.append((serial, took[:L], np.array(boxes, float), observed))
    return frames, size


def test_size_history_feeds_the_expected_changes():
    """Lag-1 and lag-3 relative half-size changes (half-size difference over the mean of
    the two box heights), only for axes with both edges measured at both frames, none over
    a missed frame at lag 1, none across a change of the slot's Bernoulli."""
    learner = RecordingLearner()
    history = SizeHistory(learner)
    frames, size = history_boxes()
    for t, frame in enumerate(frames):
        learner.calls.clear()
        history.record(*frame)
        got = {1: [], 3: []}
        for lag, diffs in learner.calls:
            got[lag].extend(diffs)
        want = {1: [], 3: []}
        for lag, pairs in EXPECTED.get(t, {1: [], 3: []}).items():
            for slot, before, axes in pairs:
                height = (size[slot][t][1] + size[slot][before][1]) / 2
                for axis in axes:
                    a = "xy".index(axis)
                    want[lag].append((size[slot][t][a] - size[slot][before][a]) / 2 / height)
        for lag in (1, 3):
            assert len(got[lag]) == len(want[lag]), (t, lag)
            np.testing.assert_allclose(got[lag], want[lag], rtol=1e-12, atol=0,
                                       err_msg=f"frame {t}, lag {lag}")
    total = {lag: sum(len(p[2]) for e in EXPECTED.values() for p in e[lag]) for lag in (1, 3)}
    assert learner._count == total


def test_size_history_frames_without_takes_still_count():
    """A frame in which no slot takes a detection is still a tracked frame: a slot that
    took at frames 0 and 3 only has a lag-3 change and no lag-1 change."""
    learner = RecordingLearner()
    history = SizeHistory(learner)
    serial, none = np.array([4]), np.zeros((0, 4))
    box = np.array([[10.0, 10, 40, 80]])
    later = np.array([[10.0, 10, 48, 100]])
    seen = np.ones((1, 2, 2), bool)
    history.record(serial, np.array([0]), box, seen)
    for _ in range(2):
        history.record(serial, np.array([-1]), none, np.zeros((0, 2, 2), bool))
    history.record(serial, np.array([0]), later, seen)
    got = {lag: np.concatenate([d for k, d in learner.calls if k == lag] or [np.zeros(0)])
           for lag in (1, 3)}
    assert len(got[1]) == 0
    np.testing.assert_allclose(got[3], [4 / 90, 10 / 90], rtol=1e-12)


# -- the tracker ----------------------------------------------------------------------------

def config(**changes):
    return TrackerConfig(occlusion="none", camera_motion="none", image_size=(1242.0, 375.0),
                         fps=10.0, **changes)


GROW_FRAMES = 25
MISSED = [t for t in range(GROW_FRAMES) if t >= 8 and t % 3 == 2]


def growing_scene(still_inside=False, noise=0.0, seed=0):
    """One box centred at (600, 190) px growing 8 % a frame (40 x 30 px to 254 x 190 px),
    undetected at the frames MISSED (there the reported box is the state's), and two still
    boxes: in the image corners, where the border cuts both axes and their sizes do not
    count (the median follows the majority of the measured sizes: two still boxes inside
    the image would pin the estimate at the prior, `test_still_majority_keeps_the_prior`).
    Returns the per frame detections (ltwh) and the growing box's truth."""
    rng = np.random.default_rng(seed)
    if still_inside:
        still = [[100.0, 150, 50, 40], [1000.0, 150, 60, 45]]
    else:
        still = [[0.0, 0, 60, 45], [1242.0 - 50, 375 - 40, 50, 40]]
    frames, truth = [], []
    for t in range(GROW_FRAMES):
        w, h = 40 * 1.08**t, 30 * 1.08**t
        box = np.array([600 - w / 2, 190 - h / 2, w, h])
        truth.append(box)
        rows = [still[0], still[1]] if t in MISSED else [still[0], box, still[1]]
        rows = np.array(rows, float)
        rows[:, :2] += rng.normal(0, noise, (len(rows), 2))
        frames.append(rows)
    return frames, np.array(truth)


def run(tracker, frames):
    """Per frame the filter's size_noise and the reported boxes."""
    noises, reports = [], []
    for boxes in frames:
        tracks = tracker.step(boxes)
        noises.append(tracker.filter.size_noise)
        reports.append(tracks.boxes)
    return noises, reports


def edge_errors(reports, truth, frames):
    """Relative (box heights) error of the right and bottom edges of the growing object's
    reported box at `frames`: the report whose centre is within a quarter height of the
    truth's, inf where there is none."""
    errors = []
    for t in frames:
        g, boxes = truth[t], reports[t]
        centre = boxes[:, :2] + boxes[:, 2:] / 2
        near = np.hypot(*(centre - (g[:2] + g[2:] / 2)).T) < g[3] / 4
        if not near.any():
            errors.append([np.inf, np.inf])
            continue
        b = boxes[np.flatnonzero(near)[0]]
        errors.append(np.abs(b[:2] + b[2:] - g[:2] - g[2:]) / g[3])
    return np.array(errors)


def test_growing_object_raises_the_learnt_noise_and_is_followed_closer():
    """The learnt size noise rises above twice the configured 0.044 (the half-height grows
    by 4 % of h a frame, 0.13 h / sqrt(s) were it a random walk, and lag-3 changes are three
    times the lag-1 ones, not sqrt(3)); without learning it stays the configured value; with
    it the state's box of the growing object (reported where its detection is missed) lags
    the truth less, by the median right and bottom edge errors (inf where it is not reported:
    without learning the object is lost after some misses)."""
    frames, truth = growing_scene()
    learnt, with_learning = run(Tracker(config()), frames)
    fixed, without = run(Tracker(config(learn_size_noise=False)), frames)
    assert learnt[-1] > 2 * 0.044
    assert all(b >= a for a, b in zip(learnt, learnt[1:], strict=False))  # only growth here
    assert all(q == 0.044 for q in fixed)
    better = edge_errors(with_learning, truth, MISSED)
    worse = edge_errors(without, truth, MISSED)
    assert np.isfinite(better).all()  # followed through every miss
    assert (np.median(better, axis=0) < np.median(worse, axis=0)).all()
    # the detected frames report the detection itself either way
    detected = [t for t in range(2, GROW_FRAMES) if t not in MISSED]
    assert (edge_errors(with_learning, truth, detected) < 1e-9).all()


def test_still_majority_keeps_the_prior():
    """Two still boxes inside the image and one growing box: most measured sizes keep still,
    the medians of the lag-1 and lag-3 squared changes are 0 and the learnt noise is the
    prior exactly (the floor the docstring describes: the median follows the majority)."""
    frames, _ = growing_scene(still_inside=True)
    learnt, _ = run(Tracker(config()), frames)
    assert all(q == 0.044 for q in learnt)


def test_learnt_noise_is_repeatable():
    """Two trackers over the same (noisy) sequence learn identical size noises at every
    frame, and so does the first one again after reset()."""
    frames, _ = growing_scene(noise=2.0, seed=5)
    tracker = Tracker(config())
    first, _ = run(tracker, frames)
    second, _ = run(Tracker(config()), frames)
    assert first == second
    assert first[-1] > 0.044
    tracker.reset()
    assert tracker.filter.size_noise == 0.044
    again, _ = run(tracker, frames)
    assert again == first


def test_prediction_uses_the_filter_size_noise():
    """The half-size variance a prediction adds is size_noise^2 dt h^2 (h the component's
    box height), with the filter's size_noise in place of the configured one; nothing else
    in the prediction changes."""
    tracker = Tracker(config(learn_size_noise=False))
    for t in range(3):
        tracker.step(np.array([[100.0, 100, 50, 40], [600, 150, 80 + t, 60 + t]]))
    plain = tracker.filter
    raised = copy.deepcopy(plain)
    raised.size_noise = 0.3
    n = plain.n
    assert n > 0
    h = np.maximum(2 * plain.mean[:n, 1, 2], MIN_HEIGHT)
    plain._predict()
    raised._predict()
    np.testing.assert_array_equal(raised.mean[:n], plain.mean[:n])
    extra = (0.3**2 - 0.044**2) * plain.dt * h**2
    np.testing.assert_allclose(raised.cov[:n, :, 2, 2] - plain.cov[:n, :, 2, 2],
                               np.repeat(extra[:, None], 2, axis=1), rtol=1e-9)
    other = np.ones((3, 3), bool)
    other[2, 2] = False
    np.testing.assert_array_equal(raised.cov[:n][:, :, other], plain.cov[:n][:, :, other])


def test_learnt_noise_per_sqrt_second_does_not_depend_on_the_step_length():
    """q is per square-root second: after 20 frames at 10 fps, a dropped frame (the next
    step 0.2 s later, `Tracker.step(dt=0.2)`, which is to predict over its true interval)
    leaves the learnt q about as it was (the one new pair of changes hardly moves the
    medians of 22 and 26), so the half-size variance added over the gap doubles."""
    frames, _ = growing_scene()
    tracker = Tracker(config())
    for boxes in frames[:20]:
        tracker.step(boxes)
    before = tracker.filter.size_noise
    assert before > 2 * 0.044
    tracker.step(frames[21], dt=0.2)
    assert tracker.filter.size_noise == pytest.approx(before, rel=0.1)


def test_camera_expansion_moves_boxes_away_from_the_centre():
    """camera_expansion: a camera driving forward moves every box away from the image centre
    by k h (x - centre) a frame. The tracker estimates k from consecutive frames' detections
    (shrunk toward 0 unless it is pinned to 5 standard errors) and hands it to the filter,
    which moves each component exactly so (centre, velocity and half-size by 1 + k h, the
    covariance by its square). Off by default."""
    assert TrackerConfig().camera_expansion is False
    centre = np.array([621.0, 187.5])
    k = 0.0004  # 1 / px a frame

    def scene(t):
        """Six parked cars, each moving away from the centre by k h (x - c) a frame."""
        boxes = []
        for x, y, h in [(300, 150, 60), (900, 160, 70), (200, 200, 90), (1000, 190, 80),
                        (450, 170, 50), (800, 175, 55)]:
            c = np.array([x, y], float)
            hh = float(h)
            for _ in range(t):
                s = 1 + k * hh
                c = centre + s * (c - centre)
                hh *= s
            boxes.append([c[0] - hh, c[1] - hh / 2, 2 * hh, hh])
        return np.array(boxes)

    def tracker(expand):
        return Tracker(TrackerConfig(occlusion="none", camera_motion="detections",
                                     camera_expansion=expand, image_size=(1242.0, 375.0),
                                     fps=10.0))

    plain, expanding = tracker(False), tracker(True)
    for t in range(6):
        plain.step(scene(t))
        expanding.step(scene(t))
    assert len(plain._camera_motion(scene(6), 0.1)) == 3
    motion = expanding._camera_motion(scene(6), 0.1)
    focus, learnt = motion[3]
    np.testing.assert_array_equal(focus, centre)
    assert learnt == pytest.approx(k, rel=0.1)

    f = expanding.filter
    n = f.n
    mean, cov = f.mean[:n].copy(), f.cov[:n].copy()
    f.expand_image(centre, k)
    scale = 1 + k * 2 * mean[:, 1, 2]
    for axis in range(2):
        np.testing.assert_allclose(f.mean[:n, axis, 0],
                                   centre[axis] + scale * (mean[:, axis, 0] - centre[axis]))
        np.testing.assert_allclose(f.mean[:n, axis, 1:], mean[:, axis, 1:] * scale[:, None])
    np.testing.assert_allclose(f.cov[:n], cov * scale[:, None, None, None] ** 2)


def test_the_median_of_squares_is_numpys_to_the_last_bit():
    """The learner's median (a compiled quickselect) against np.median(np.square(x)) for odd
    and even lengths, one value to the full buffer, and scales from 1e-3 to 1e3."""
    from occtrack.models.motion import _median_of_squares

    rng = np.random.default_rng(11)
    for n in [*range(1, 40), 1999, 2000]:
        for scale in (1e-3, 1.0, 1e3):
            x = rng.standard_normal(n) * scale
            assert _median_of_squares(x) == float(np.median(np.square(x)))
    # orders and ties that defeat a careless selection: sorted either way, all equal, a few
    # distinct values repeated, signs mixed (squares tie)
    for n in (2, 3, 10, 11, 1999, 2000):
        ramp = np.arange(n, dtype=float)
        for x in (ramp, ramp[::-1].copy(), np.full(n, 0.3), rng.integers(0, 3, n) * 0.1,
                  np.where(ramp % 2, -1.0, 1.0) * (ramp // 2)):
            assert _median_of_squares(x) == float(np.median(np.square(x)))
