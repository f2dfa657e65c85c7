"""The highway tracker's and sensor's Python layer: defaults, the arrays it hands to the
occlusion handler and the compiled kernels, and the sensor's wrappers with other input types.

The compiled kernels are held to numpy by tests/test_highway_kernels.py; what is checked here
is what surrounds them (found by mutation testing, `benchmarks/mutation.py --modules
highway`): a fresh tracker's state, its defaults, the owner of the Poisson part's particles,
and wrappers that must give the same numbers for lists, integer arrays and precomputed
hidden parts."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import norm

from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig
from occtrack.filters.particle_tomb import HighwayTracker, systematic_resample
from occtrack.models.highway_sensor import MeasurementModel, Scan
from occtrack.occlusion.highway import MeasurementWise, make_occlusion
from occtrack.scenarios.highway import simulate

SIM = SimulationConfig()
SMALL = HighwayTrackerConfig.matching(SIM, particles=96, undetected_particles=64,
                                      birth_particles=64, max_tracks=24)


def _digest(estimates) -> bytes:
    return b"".join(np.concatenate([e.left, e.length, e.velocity, e.existence]).tobytes()
                    + np.concatenate([e.label, e.lane]).tobytes() for e in estimates)


def _scans(steps: int, seed: int = 3):
    return [scan for _, scan in simulate(SIM, "measurement-wise", steps, seed)]


def test_empty_scan_has_the_shapes_and_types_of_a_scan():
    scan = Scan.empty()
    assert len(scan) == 0
    for name, shape, dtype in (("lane", (0,), np.int64), ("left", (0, 2), np.float64),
                               ("right", (0, 2), np.float64), ("left_hidden", (0,), np.bool_),
                               ("right_hidden", (0,), np.bool_), ("source", (0,), np.int64)):
        a = getattr(scan, name)
        assert a.shape == shape and a.dtype == dtype, name


def test_a_new_tracker_holds_nothing_and_its_defaults_are_documented():
    tracker = HighwayTracker(SMALL)
    assert tracker.n == 0 and tracker.next_label == 0 and tracker.last_iterations == 0
    assert len(tracker.estimates()) == 0
    assert isinstance(tracker.occlusion, MeasurementWise)
    # default handler and seed: measurement-wise, seed 0
    scans = _scans(30)
    tracker_a = HighwayTracker(SMALL)
    a = [tracker_a.step(s) for s in scans]
    tracker_b = HighwayTracker(SMALL, "measurement-wise", seed=0)
    b = [tracker_b.step(s) for s in scans]
    tracker_c = HighwayTracker(SMALL, "measurement-wise", seed=1)
    c = [tracker_c.step(s) for s in scans]
    assert _digest(a) == _digest(b) != _digest(c)


def test_labels_are_whole_numbers_from_zero_in_birth_order():
    tracker = HighwayTracker(SMALL, seed=2)
    seen = []
    for scan in _scans(60, 2):
        e = tracker.step(scan)
        assert e.label.dtype == np.int64 and e.lane.dtype == np.int64
        seen.extend(e.label.tolist())
    born = tracker.next_label
    assert born > 0
    assert tracker.label.dtype == np.int64
    assert min(seen) == 0 and max(seen) < born


class Recorder:
    """A measurement-wise handler that keeps a copy of what the tracker hands it."""

    name = "recorder"

    def __init__(self, config):
        self.inner = make_occlusion("measurement-wise", config)
        self.seen = []

    def terms(self, ctx):
        self.seen.append((ctx.owner.copy(), ctx.lane.copy()))
        return self.inner.terms(ctx)


def test_the_handler_sees_the_poisson_part_as_owner_minus_one_then_each_track():
    recorder = Recorder(SMALL)
    tracker = HighwayTracker(SMALL, recorder, seed=4)
    u = SMALL.road.n_lanes * (SMALL.undetected_particles + SMALL.birth_particles)
    held = []
    for scan in _scans(40, 4):
        held.append((tracker.n, tracker.lane[:tracker.n].copy()))
        tracker.step(scan)
    assert any(n > 0 for n, _ in held)
    for (owner, lane), (n, track_lane) in zip(recorder.seen, held, strict=True):
        N = SMALL.particles
        assert len(owner) == u + n * N
        assert np.all(owner[:u] == -1)
        assert np.array_equal(owner[u:], np.repeat(np.arange(n), N))
        per_lane = SMALL.undetected_particles + SMALL.birth_particles
        assert np.array_equal(lane[:u], np.repeat(np.arange(SMALL.road.n_lanes), per_lane))
        assert np.array_equal(lane[u:], np.repeat(track_lane, N))


def test_the_poisson_part_is_sorted_by_left_end_when_the_handler_sees_it():
    """Step 1 sorts each lane's Poisson particles by their left end (the windows of particles
    a measurement can have come from are found by binary search)."""
    seen = []

    class Peek(Recorder):
        def terms(self, ctx):
            seen.append(ctx.means[:u].copy())
            return self.inner.terms(ctx)

    u = SMALL.road.n_lanes * (SMALL.undetected_particles + SMALL.birth_particles)
    tracker = HighwayTracker(SMALL, Peek(SMALL), seed=5)
    for scan in _scans(10, 5):
        tracker.step(scan)
    for means in seen:
        left = means[:, 0].reshape(SMALL.road.n_lanes, -1)
        assert np.all(np.diff(left, axis=1) >= 0)
        assert len(np.unique(means, axis=0)) > len(means) // 2  # sorted, not collapsed


def test_sensor_wrappers_give_the_same_numbers_for_lists_and_integer_arrays():
    model = MeasurementModel(SMALL)
    left_f = np.array([[0.0, 2.0], [-3.0, 1.0]])
    right_f = left_f + 4.0
    zl, zr = np.array([1.0, -2.0]), np.array([5.0, 6.0])
    lh, rh = np.array([False, True]), np.array([True, False])
    want = model.likelihood(left_f, right_f, np.c_[zl, zl], np.c_[zr, zr + 2], lh, rh)
    got = model.likelihood(left_f.astype(int).tolist(), right_f.astype(int).tolist(),
                           np.c_[zl, zl].astype(int).tolist(),
                           np.c_[zr, zr + 2].astype(int).tolist(), [0, 1], [1, 0])
    assert np.array_equal(got, want)

    idx = systematic_resample(np.array([[1.0, 3.0, 0.0, 4.0]]), 5, np.random.default_rng(1))
    idx_int = systematic_resample([[1, 3, 0, 4]], 5, np.random.default_rng(1))
    assert np.array_equal(idx, idx_int)


def _q_brute(model, lane, left, right, parts):
    s = model.sigma
    out = np.zeros(len(lane))
    for i, (k, a_l, a_r) in enumerate(zip(lane, left, right, strict=True)):
        for a, b in zip(*parts[k], strict=True):
            out[i] += ((norm.cdf((b - a_l) / s) - norm.cdf((a - a_l) / s))
                       * (norm.cdf((b - a_r) / s) - norm.cdf((a - a_r) / s)))
    return out


@pytest.mark.parametrize("noise_std", [0.75, 2.0])
def test_hidden_probability_equals_the_sum_over_parts_given_or_not(noise_std):
    """q = sum over hidden parts C of P(l' in C) P(r' in C), by brute force over every part;
    the same whether the parts are passed in (as float or integer lists) or found from the
    scan; with sigma = 2, parts 3 to 12 m away still count."""
    config = replace(SMALL, noise_std=noise_std)
    model = MeasurementModel(config)
    scans = [s for s in _scans(60, 6) if len(s) > 4]
    rng = np.random.default_rng(6)
    checked = 0
    for scan in scans[:12]:
        parts = model.occluded_parts(scan)
        lane = rng.integers(0, model.n_lanes, 400)
        left = rng.uniform(-60.0, 60.0, 400)
        right = left + rng.uniform(3.0, 12.0, 400)
        want = _q_brute(model, lane, left, right, parts)
        q = model.hidden_probability(lane, left, right, scan)
        assert np.allclose(q, want, rtol=0, atol=1e-8)
        given = model.hidden_probability(lane, left, right, scan, parts=parts)
        assert np.array_equal(given, q)
        as_lists = [(list(lo), list(hi)) for lo, hi in parts]
        assert np.array_equal(model.hidden_probability(lane.tolist(), left.tolist(),
                                                       right.tolist(), scan, as_lists), q)
        checked += int(np.sum(want > 1e-6))
    assert checked > 50


def test_hidden_probability_with_integer_parts_and_ends():
    model = MeasurementModel(replace(SMALL, noise_std=2.0))
    parts = [([], [])] + [([-10, 5], [-2, 20])] * (model.n_lanes - 1)
    lane, left, right = [1, 2, 1, 0], [-9, 7, -20, 0], [-3, 15, -12, 4]
    want = _q_brute(model, lane, left, right, parts)
    got = model.hidden_probability(lane, left, right, Scan.empty(), parts)
    assert np.allclose(got, want, rtol=0, atol=1e-8)
    assert got[3] == 0.0 and got[1] > 0.5 and 0 < got[2] < 0.1


def _cloud(rng, k, width=40, lane=None):
    left = rng.uniform(-50.0, 50.0, (k, width))
    length = rng.uniform(SMALL.min_length, SMALL.max_length, (k, width))
    speed = rng.uniform(SMALL.min_speed, SMALL.max_speed, (k, width))
    particles = np.stack([left, length, speed], axis=-1)
    weights = rng.random((k, width))
    return particles, weights / weights.sum(axis=1, keepdims=True)


def test_full_track_table_keeps_the_strongest_old_and_new_tracks():
    config = replace(SMALL, max_tracks=4)
    tracker = HighwayTracker(config, seed=8)
    rng = np.random.default_rng(8)
    particles, weights = _cloud(rng, 3)
    tracker._start_tracks(particles, weights, np.array([0.9, 0.2, 0.6]), np.array([0, 1, 2]))
    assert tracker.n == 3 and tracker.next_label == 3
    assert np.array_equal(tracker.label[:3], [0, 1, 2])
    assert np.array_equal(tracker.r[:3], [0.9, 0.2, 0.6])
    assert np.array_equal(tracker.w[:3], np.full((3, config.particles), 1 / config.particles))
    kept = tracker.x[:3].copy()
    particles, weights = _cloud(rng, 3)
    tracker._start_tracks(particles, weights, np.array([0.5, 0.95, 0.1]), np.array([3, 1, 0]))
    # pool 0.9 0.2 0.6 | 0.5 0.95 0.1: keep 0.95, 0.9, 0.6, 0.5; old ones first, in order
    assert tracker.n == 4 and tracker.next_label == 5
    assert np.array_equal(tracker.label[:4], [0, 2, 3, 4])
    assert np.array_equal(tracker.r[:4], [0.9, 0.6, 0.5, 0.95])
    assert np.array_equal(tracker.lane[:4], [0, 2, 3, 1])
    assert np.array_equal(tracker.x[:2], kept[[0, 2]])
    # exactly as many as the free slots: all are taken, in order
    tracker = HighwayTracker(config, seed=8)
    particles, weights = _cloud(rng, 4)
    tracker._start_tracks(particles, weights, np.array([0.3, 0.4, 0.2, 0.7]), np.arange(4))
    assert np.array_equal(tracker.r[:4], [0.3, 0.4, 0.2, 0.7])
    assert np.array_equal(tracker.label[:4], [0, 1, 2, 3])


def test_without_a_kernel_bandwidth_resampling_copies_particles_and_draws_no_noise():
    config = replace(SMALL, kernel_bandwidth=0.0)
    tracker = HighwayTracker(config, seed=9)
    rng = np.random.default_rng(9)
    particles, weights = _cloud(rng, 3)
    twin = np.random.default_rng(0)
    twin.bit_generator.state = tracker.rng.bit_generator.state
    out = tracker._resample_move(particles, weights, np.zeros(3, np.int64))
    idx = systematic_resample(weights, config.particles, twin)
    assert np.array_equal(out, particles[np.arange(3)[:, None], idx])
    assert tracker.rng.random() == twin.random()  # only the systematic offsets were drawn
    # with a bandwidth, each particle moves (Liu-West) and stays within the prior's support
    moved = HighwayTracker(SMALL, seed=9)._resample_move(particles, weights,
                                                          np.zeros(3, np.int64))
    assert moved.shape == out.shape and not np.isin(moved[..., 0], particles[..., 0]).any()


def test_reported_tracks_are_held_ones_with_unique_labels():
    tracker = HighwayTracker(SMALL, seed=10)
    pruned = 0
    for scan in _scans(120, 10):
        before = tracker.next_label
        e = tracker.step(scan)
        held = set(tracker.label[:tracker.n].tolist())
        assert len(set(e.label.tolist())) == len(e) <= tracker.n
        assert set(e.label.tolist()) <= held
        assert np.all(e.existence > SMALL.report_threshold)
        pruned += tracker.next_label - before
    assert pruned > 5


def test_lbp_runs_at_most_the_configured_iterations():
    for limit in (1, 2):
        tracker = HighwayTracker(replace(SMALL, lbp_max_iter=limit, lbp_tol=1e-300), seed=11)
        counts = []
        for scan in _scans(40, 11):
            tracker.step(scan)
            counts.append(tracker.last_iterations)
        assert all(isinstance(k, int) for k in counts)
        assert max(counts) == limit
        # a step without measurements runs no LBP and leaves the count of the last one
        assert counts[-1] > 0 and tracker.n > 0
        tracker.step(Scan.empty())
        assert tracker.last_iterations == counts[-1]
    free = HighwayTracker(SMALL, seed=11)
    counts = []
    for scan in _scans(40, 11):
        free.step(scan)
        counts.append(free.last_iterations)
    assert max(counts) > 2


class IntegerTerms(Recorder):
    """Measurement-wise terms (every particle visible, q = 0 or 1) as integer arrays."""

    def terms(self, ctx):
        t = self.inner.terms(ctx)
        return type(t)(visible=t.visible.astype(np.int64),
                       hidden=(t.hidden > 0.5).astype(np.int64))


class RoundedTerms(Recorder):
    def terms(self, ctx):
        t = self.inner.terms(ctx)
        return type(t)(visible=t.visible, hidden=(t.hidden > 0.5).astype(float))


def test_a_handler_may_return_integer_terms():
    scans = _scans(40, 12)
    a, b = HighwayTracker(SMALL, IntegerTerms(SMALL), 12), HighwayTracker(SMALL,
                                                                         RoundedTerms(SMALL), 12)
    assert _digest([a.step(s) for s in scans]) == _digest([b.step(s) for s in scans])


def test_full_track_table_breaks_ties_by_age_then_measurement_order():
    """Existences tie often (they are clipped at 1): among equals, the tracks already held
    keep their slots before newborns, and newborns go in measurement order, so which tracks
    survive does not depend on a sort's whim. Checked against sorting by (-r, position)."""
    config = replace(SMALL, max_tracks=20, kernel_bandwidth=0.0)  # copies: who is who
    rng = np.random.default_rng(13)
    for _ in range(20):
        tracker = HighwayTracker(config, seed=13)
        old = rng.choice([1.0, 0.9, 0.5], 18)
        new = rng.choice([1.0, 0.9, 0.5], 6)
        particles, weights = _cloud(rng, 24, width=4)
        tracker._start_tracks(particles[:18], weights[:18], old, np.zeros(18, np.int64))
        tracker._start_tracks(particles[18:], weights[18:], new, np.ones(6, np.int64))
        pool = np.r_[old, new]
        keep = sorted(sorted(range(24), key=lambda i: (-pool[i], i))[:20])
        held = [int(np.flatnonzero((particles[:, :, 0] == x[0, 0]).any(axis=1))[0])
                for x in tracker.x[:20]]
        assert held == keep
        assert np.array_equal(tracker.r[:20], pool[keep])


def test_thresholds_keep_an_existence_equal_to_the_pruning_one_and_report_above():
    tracker = HighwayTracker(SMALL, seed=14)
    particles, weights = _cloud(np.random.default_rng(14), 3, width=4)
    p, report = SMALL.prune_threshold, SMALL.report_threshold
    tracker._start_tracks(particles, weights, np.array([p, np.nextafter(p, 0), report]),
                          np.zeros(3, np.int64))
    assert len(tracker.estimates()) == 0  # r == report_threshold is not reported
    tracker._prune()
    assert tracker.label[:tracker.n].tolist() == [0, 2]


def test_births_use_a_sobol_set_scrambled_by_the_seed():
    a, b = HighwayTracker(SMALL, seed=0)._sobol, HighwayTracker(SMALL, seed=1)._sobol
    assert a.shape == (SMALL.birth_particles, 3)
    assert not np.array_equal(a, b)
    assert np.all((a > 0) & (a < 1))  # an unscrambled set starts at the origin


@pytest.mark.parametrize("name", ["object-wise-expval", "object-wise-grid"])
def test_object_wise_handlers_give_the_same_terms_for_lists_and_int32_arrays(name):
    """The handlers hand owner, lane, weights and existence to compiled kernels through
    `np.asarray`: lists and other integer widths give the same numbers, bit for bit."""
    from occtrack.occlusion.highway import HighwayContext

    rng = np.random.default_rng(6)
    k = 90
    owner = np.r_[np.repeat([0, 1, 2], 20), np.full(30, -1)]
    lane = np.r_[np.repeat([0, 1, 1], 20), rng.integers(1, 4, 30)]
    means = np.c_[rng.uniform(-20.0, 15.0, k), rng.uniform(3.0, 7.0, k), np.zeros(k)]
    weights = rng.uniform(0.1, 1.0, k)
    existence = np.array([0.9, 0.6, 0.3])
    handler = make_occlusion(name, SMALL)
    common = dict(means=means, covs=None, measurements=Scan.empty(),
                  measurement_model=MeasurementModel(SMALL))
    arrays = handler.terms(HighwayContext(weights=weights, owner=owner, existence=existence,
                                          lane=lane, **common))
    assert np.ptp(arrays.visible) > 0.2  # something is hidden, by degrees
    for cast in (lambda a: a.tolist(), lambda a: a.astype(np.int32) if a.dtype.kind == "i" else a):
        other = handler.terms(HighwayContext(weights=cast(weights), owner=cast(owner),
                                             existence=cast(existence), lane=cast(lane),
                                             **common))
        assert other.visible.tobytes() == arrays.visible.tobytes()
        assert other.hidden.tobytes() == arrays.hidden.tobytes()
