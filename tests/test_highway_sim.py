"""Invariants of the highway simulation and its sensor, and the exact hidden probability."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.config.highway import (
    HighwayTrackerConfig,
    RoadConfig,
    SimulationConfig,
    load_highway,
)
from occtrack.errors import OcctrackError
from occtrack.models.highway_sensor import MeasurementModel, Scan
from occtrack.occlusion.extents import locate, occlude, union
from occtrack.scenarios.highway import Cars, Traffic, cars_overlap, sense, simulate

SIM = SimulationConfig()


def run(mode: str, steps: int, seed: int, config: SimulationConfig = SIM):
    return list(simulate(config, mode, steps, seed))


@pytest.fixture(scope="module")
def object_wise():
    return run("object-wise", 1500, 11)


@pytest.fixture(scope="module")
def measurement_wise():
    return run("measurement-wise", 1500, 11)


def test_same_seed_same_traffic_under_either_sensor(object_wise, measurement_wise):
    for (a, _), (b, _) in zip(object_wise[:200], measurement_wise[:200], strict=True):
        assert np.array_equal(a.id, b.id) and np.array_equal(a.left, b.left)


@pytest.mark.parametrize("delay", [0.0, 1.0])
def test_cars_never_collide(delay):
    config = SimulationConfig(entry_delay=delay)
    traffic = Traffic(config, np.random.default_rng(5))
    seen = 0
    for _ in range(4000):
        cars = traffic.step()
        assert not cars_overlap(cars, config.min_headway - 1e-9)
        seen += len(cars)
    assert seen > 0


def test_cars_move_at_constant_speed_within_the_section():
    traffic = Traffic(SIM, np.random.default_rng(2))
    before = traffic.step()
    for _ in range(300):
        after = traffic.step()
        common, i, j = np.intersect1d(before.id, after.id, return_indices=True)
        assert np.allclose(after.left[j] - before.left[i], before.velocity[i])
        assert np.array_equal(np.sign(after.velocity), SIM.road.directions[after.lane])
        half = SIM.road.half_length
        rear = np.where(after.velocity > 0, after.left, -after.right)
        front = np.where(after.velocity > 0, after.right, -after.left)
        assert np.all(rear < half) and np.all(front >= -half)
        assert np.all((after.length >= SIM.min_length) & (after.length <= SIM.max_length))
        assert np.all((np.abs(after.velocity) >= SIM.min_speed)
                      & (np.abs(after.velocity) <= SIM.max_speed))
        before = after


def _car_end(cars: Cars, source: np.ndarray, which: str) -> np.ndarray:
    index = {i: k for k, i in enumerate(cars.id)}
    rows = np.array([index[s] for s in source], dtype=np.int64)
    return (cars.left if which == "left" else cars.right)[rows]


@pytest.mark.parametrize("mode", ["object-wise", "measurement-wise"])
def test_reported_ends_are_in_order_and_where_the_car_is(mode, object_wise, measurement_wise):
    frames = object_wise if mode == "object-wise" else measurement_wise
    residuals, hidden_outside = [], 0
    sigma = SIM.noise_std
    for cars, scan in frames:
        assert np.all(scan.left[:, 0] <= scan.left[:, 1])
        assert np.all(scan.right[:, 0] <= scan.right[:, 1])
        assert np.all(scan.left[:, 1] <= scan.right[:, 0])
        assert np.array_equal(scan.left[~scan.left_hidden, 0], scan.left[~scan.left_hidden, 1])
        real = scan.source >= 0
        for which, ends, hidden in (("left", scan.left, scan.left_hidden),
                                    ("right", scan.right, scan.right_hidden)):
            true = _car_end(cars, scan.source[real], which)
            z, h = ends[real], hidden[real]
            seen_residual = z[~h, 0] - true[~h]
            assert np.all(np.abs(seen_residual) < 6 * sigma)
            if mode == "object-wise":
                # Object-wise: the hidden span is where the true end is, exactly.
                assert np.all(z[h, 0] - 1e-9 <= true[h]) and np.all(true[h] <= z[h, 1] + 1e-9)
            else:
                # Measurement-wise: it holds the noisy end, so the true end is within noise.
                hidden_outside += np.sum((true[h] < z[h, 0] - 6 * sigma)
                                         | (true[h] > z[h, 1] + 6 * sigma))
            # Lane 1 is never hidden: there the seen ends of long cars (never reordered by
            # noise) are plain Gaussian.
            long = _car_end(cars, scan.source[real], "right") - _car_end(
                cars, scan.source[real], "left") > 5.0
            near = ((scan.lane[real] == 0) & long)[~h]
            residuals.append(seen_residual[near])
    assert hidden_outside == 0
    if mode == "measurement-wise":
        r = np.concatenate(residuals)
        assert len(r) > 2000
        assert abs(r.mean()) < 3 * sigma / np.sqrt(len(r))
        assert abs(r.std() / sigma - 1) < 0.05


def test_measurement_wise_hidden_spans_are_the_nearer_lanes_shadows(measurement_wise):
    model = MeasurementModel(HighwayTrackerConfig.matching(SIM))
    checked = 0
    for _, scan in measurement_wise[:400]:
        parts = model.occluded_parts(scan)
        for ends, hidden in ((scan.left, scan.left_hidden), (scan.right, scan.right_hidden)):
            for j in np.flatnonzero(hidden):
                lo, hi = parts[scan.lane[j]]
                k = locate(np.array([0.5 * (ends[j, 0] + ends[j, 1])]), lo, hi)[0]
                assert k >= 0
                assert np.allclose([lo[k], hi[k]], ends[j], atol=1e-9)
                checked += 1
            for j in np.flatnonzero(~hidden):
                lo, hi = parts[scan.lane[j]]
                assert locate(ends[j, :1], lo, hi)[0] == -1
    assert checked > 50


def test_first_lane_is_never_hidden(object_wise, measurement_wise):
    for _, scan in object_wise + measurement_wise:
        near = scan.lane == 0
        assert not np.any(scan.left_hidden[near] | scan.right_hidden[near])


def test_clutter_rate_and_detection_probability(object_wise):
    clutter = np.array([np.sum(scan.source < 0) for _, scan in object_wise])
    rate = SIM.clutter_rate
    assert abs(clutter.mean() - rate) < 3 * np.sqrt(rate / len(clutter))
    near_cars = sum(np.sum(cars.lane == 0) for cars, _ in object_wise)
    near_seen = sum(np.sum((scan.lane == 0) & (scan.source >= 0)) for _, scan in object_wise)
    p = SIM.detection_probability
    assert abs(near_seen / near_cars - p) < 3 * np.sqrt(p * (1 - p) / near_cars)


@pytest.mark.parametrize("mode", ["object-wise", "measurement-wise"])
def test_empty_road(mode):
    empty = Cars(*(np.empty(0, dtype=t) for t in (np.int64, np.int64, float, float, float)))
    rng = np.random.default_rng(0)
    quiet = SimulationConfig(clutter_rate=0.0)
    scan = sense(empty, quiet, mode, rng)
    assert len(scan) == 0
    noisy = SimulationConfig(clutter_rate=5.0)
    scans = [sense(empty, noisy, mode, rng) for _ in range(50)]
    assert sum(len(s) for s in scans) > 0
    assert all(np.all(s.source == -1) for s in scans)
    model = MeasurementModel(HighwayTrackerConfig.matching(SIM))
    assert np.all(model.clutter_density(Scan.empty()) == 0)
    q = model.hidden_probability(np.array([1, 2]), np.array([0.0, 1.0]), np.array([3.0, 4.0]),
                                 Scan.empty())
    assert np.array_equal(q, [0.0, 0.0])


def test_union_and_locate():
    starts, ends = union(np.array([3.0, 0.0, 1.0, 7.0]), np.array([4.0, 2.0, 2.5, 8.0]))
    assert np.array_equal(starts, [0.0, 3.0, 7.0]) and np.array_equal(ends, [2.5, 4.0, 8.0])
    assert np.array_equal(locate(np.array([-1.0, 0.0, 2.6, 3.5, 8.0, 9.0]), starts, ends),
                          [-1, 0, -1, 1, 2, -1])
    assert len(union(np.empty(0), np.empty(0))[0]) == 0
    # touching intervals are one part
    starts, ends = union(np.array([1.0, 0.0, 2.0]), np.array([2.0, 1.0, 3.0]))
    assert np.array_equal(starts, [0.0]) and np.array_equal(ends, [3.0])


def test_occlusion_by_angle():
    # Lane 1 (3 m) car over [-1, 2] hides the angles [-1/3, 2/3]: [-2, 4] in lane 2 (6 m).
    occ = occlude(np.array([0, 1, 1, 1]), np.array([-1.0, -1.5, 3.0, -6.0]),
                  np.array([2.0, 3.5, 7.0, -3.0]), np.array([3.0, 6.0, 9.0, 12.0]))
    assert np.array_equal(occ.reported, [True, False, True, True])
    assert occ.right_hidden[1] and occ.left_hidden[2] and not occ.right_hidden[2]
    assert np.allclose(occ.left_span[2], [-2.0, 4.0])
    assert not occ.left_hidden[3] and not occ.right_hidden[3]
    # one [start, end] per hidden end, NaN for an end that is seen
    assert occ.left_span.shape == occ.right_span.shape == (4, 2)
    assert np.allclose(occ.right_span[1], [-2.0, 4.0]) and np.isnan(occ.right_span[2]).all()
    assert np.isnan(occ.left_span[[0, 3]]).all() and np.isnan(occ.right_span[[0, 3]]).all()


def test_hidden_probability_matches_monte_carlo():
    """q from the measured nearer shapes against how often the simulator's measurement-wise
    sensor hides the car: mean(1[hidden] - q) within 3 standard errors of 0, per car."""
    config = SimulationConfig(clutter_rate=0.0, detection_probability=1.0)
    model = MeasurementModel(HighwayTrackerConfig.matching(config))
    # An occluder in lane 1 and, behind it, cars that are hidden only some of the time.
    cars = Cars(id=np.arange(5), lane=np.array([0, 1, 1, 2, 3]),
                left=np.array([-2.0, -3.6, 3.5, -4.9, -10.0]),
                length=np.array([5.0, 8.8, 2.4, 11.0, 6.5]),
                velocity=np.array([3.0, 3.0, 3.0, -3.0, -3.0]))
    rng = np.random.default_rng(123)
    draws = 4000
    diff = np.zeros((draws, 4))
    q_mean = np.zeros(4)
    for n in range(draws):
        scan = sense(cars, config, "measurement-wise", rng)
        q = model.hidden_probability(cars.lane[1:], cars.left[1:], cars.right[1:], scan)
        hidden = ~np.isin(cars.id[1:], scan.source)
        diff[n] = hidden - q
        q_mean += q / draws
    assert np.all((q_mean > 0.05) & (q_mean < 0.95)), q_mean
    stderr = diff.std(axis=0, ddof=1) / np.sqrt(draws)
    assert np.all(np.abs(diff.mean(axis=0)) < 3 * stderr), (diff.mean(axis=0), stderr)


def test_likelihood_is_a_density_over_seen_ends():
    """For a car that nothing hides, p(z | car) integrates to 1 over ordered pairs of ends."""
    model = MeasurementModel(HighwayTrackerConfig.matching(SIM))
    grid = np.linspace(-8, 12, 801)
    step = grid[1] - grid[0]
    zl, zr = np.meshgrid(grid, grid, indexing="ij")
    ordered = zl <= zr
    weight = np.where(zl == zr, 0.5, 1.0)[ordered]
    zl, zr = zl[ordered], zr[ordered]
    m = len(zl)
    for left, right in ((0.0, 4.0), (1.0, 1.6)):
        p = model.likelihood(np.full((m, 1), left), np.full((m, 1), right), np.c_[zl, zl],
                             np.c_[zr, zr], np.zeros(m, bool), np.zeros(m, bool))
        assert abs(np.sum(weight * p[:, 0]) * step * step - 1.0) < 1e-4


def test_clutter_density_integrates_hidden_ends():
    model = MeasurementModel(HighwayTrackerConfig.matching(SIM))
    half, lmin, lmax = SIM.road.half_length, SIM.clutter_min_length, SIM.clutter_max_length
    c = 1.0 / (SIM.road.n_lanes * 2 * half * (lmax - lmin))
    scan = Scan(lane=np.array([1, 1, 2, 3]),
                left=np.array([[0.0, 0.0], [-4.0, 1.0], [2.0, 2.0], [-1.0, 2.0]]),
                right=np.array([[3.0, 3.0], [5.0, 5.0], [3.0, 8.0], [4.0, 6.0]]),
                left_hidden=np.array([False, True, False, True]),
                right_hidden=np.array([False, False, True, True]), source=np.full(4, -1))
    f = model.clutter_density(scan)
    # Both seen; left in [-4, 1] with right at 5 (length 2..7 -> left in [-2, 1] -> 3 m);
    # right in [3, 8] with left at 2 (right in [4, 8] -> 4 m).
    assert np.allclose(f[:3], [c, 3 * c, 4 * c])
    # Both hidden: area by brute force.
    s = np.linspace(-1, 2, 3001)
    e = np.linspace(4, 6, 3001)
    ss, ee = np.meshgrid(s, e, indexing="ij")
    inside = ((ee - ss) >= lmin) & ((ee - ss) <= lmax)
    area = inside.mean() * 3 * 2
    assert abs(f[3] / c - area) < 0.01


def test_config_validation_and_toml(tmp_path):
    with pytest.raises(ValueError, match=r"noise_std must be a number in \(0, 1000\]"):
        SimulationConfig(noise_std=-1.0)
    with pytest.raises(ValueError, match="at least one lane"):
        RoadConfig(lanes_right=0, lanes_left=0)
    good = tmp_path / "h.toml"
    good.write_text("[simulation]\nclutter_rate = 0.3\n[simulation.road]\nhalf_length = 40.0\n"
                    "[tracker]\nparticles = 128\n")
    sim, tracker = load_highway(good)
    assert sim.clutter_rate == 0.3 and tracker.clutter_rate == 0.3
    assert sim.road.half_length == 40.0 and tracker.road.half_length == 40.0
    assert tracker.particles == 128
    bad = tmp_path / "bad.toml"
    bad.write_text("[tracker]\nparticle = 12\n")
    with pytest.raises(OcctrackError, match="tracker.particle"):
        load_highway(bad)
    nan = tmp_path / "nan.toml"
    nan.write_text("[simulation]\nnoise_std = nan\n")
    with pytest.raises(OcctrackError):
        load_highway(nan)
