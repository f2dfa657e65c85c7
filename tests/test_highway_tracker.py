"""The highway trackers: occlusion handlers, repeatability, capacities, scoring."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from occtrack.config.highway import HighwayTrackerConfig, RoadConfig, SimulationConfig
from occtrack.errors import OcctrackError
from occtrack.experiments.highway import evaluate
from occtrack.filters.particle_tomb import Estimates, HighwayTracker, systematic_resample
from occtrack.metrics.highway import ScoreAccumulator, distances, step_gospa
from occtrack.models.highway_sensor import MeasurementModel, Scan
from occtrack.occlusion.base import OcclusionTerms
from occtrack.occlusion.extents import occlude
from occtrack.occlusion.highway import (
    TRACKER_NAMES,
    HighwayContext,
    ObjectWiseExpval,
    ObjectWiseGrid,
    _track_extents,
    make_occlusion,
)
from occtrack.scenarios.highway import Cars, simulate

SIM = SimulationConfig()
SMALL = HighwayTrackerConfig.matching(SIM, particles=96, undetected_particles=64,
                                      birth_particles=64, max_tracks=24)


def _run(tracker: str, sensor: str, steps: int, seed: int, config=SMALL):
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[2])
    filt = HighwayTracker(config, tracker, seed=rng)
    out = []
    for cars, scan in simulate(SIM, sensor, steps, seed):
        out.append((cars, filt.step(scan)))
    return filt, out


def _bytes(run) -> bytes:
    return b"".join(np.concatenate([e.label, e.lane]).tobytes()
                    + np.concatenate([e.left, e.length, e.velocity, e.existence]).tobytes()
                    for _, e in run)


@pytest.mark.parametrize("tracker", TRACKER_NAMES)
def test_short_run_is_finite_and_repeatable(tracker):
    filt, a = _run(tracker, "measurement-wise", 80, 3)
    _, b = _run(tracker, "measurement-wise", 80, 3)
    assert _bytes(a) == _bytes(b)
    _, c = _run(tracker, "measurement-wise", 80, 4)
    assert _bytes(a) != _bytes(c)
    for _, e in a:
        for v in (e.left, e.length, e.velocity, e.existence):
            assert np.all(np.isfinite(v))
        assert np.all((e.existence > SMALL.report_threshold) & (e.existence <= 1))
    assert sum(len(e) for _, e in a) > 0
    # Fixed capacities: the arrays never grow.
    assert filt.x.shape == (SMALL.max_tracks, SMALL.particles, 3)
    assert filt.ux.shape == (SIM.road.n_lanes, 128, 3)
    assert filt.n <= SMALL.max_tracks


@pytest.mark.parametrize("seed", [9, 10])
def test_tracker_follows_a_lone_car(seed):
    """One slow car in the farthest lane and nothing else: after 30 steps the particle
    posterior mean agrees with the least-squares fit of (left end, length, speed) to the same
    measurements, the exact posterior mean but for the prior (which here adds only the entry
    band's information about the first position)."""
    config = SimulationConfig(clutter_rate=0.0)
    filt = HighwayTracker(HighwayTrackerConfig.matching(config, particles=512), "measurement-wise",
                          seed)
    rng = np.random.default_rng(seed)
    left, length, v = 28.5, 4.5, -2.0
    rows, z = [], []
    for t in range(30):
        x = left + v * t
        zl, zr = np.sort([x, x + length] + config.noise_std * rng.standard_normal(2))
        scan = Scan(np.array([3]), np.array([[zl, zl]]), np.array([[zr, zr]]),
                    np.zeros(1, bool), np.zeros(1, bool), np.array([0]))
        est = filt.step(scan)
        assert len(est) == 1 and est.lane[0] == 3 and est.existence[0] > 0.99
        rows += [[1.0, 0.0, t - 29.0], [1.0, 1.0, t - 29.0]]
        z += [zl, zr]
    fit = np.linalg.lstsq(np.array(rows), np.array(z), rcond=None)[0]
    assert abs(est.left[0] - fit[0]) < 0.3
    assert abs(est.length[0] - fit[1]) < 0.3
    assert abs(est.velocity[0] - fit[2]) < 0.03
    assert np.hypot(est.left[0] - (left + 29 * v), est.length[0] - length) < 1.0


def test_hidden_track_survives_only_with_occlusion_handling():
    """A car entering lane 2 is tracked, then hidden for a few steps behind a faster car of
    lane 1 (its shadow in lane 2 moves at twice its speed). With the measurement-wise handler
    the track's existence stays high while hidden; told that nothing hides it, it is dropped."""
    config = SimulationConfig(clutter_rate=0.0)
    rng = np.random.default_rng(4)
    frames = []
    for t in range(12):
        near = np.array([-25.5, -18.5]) + 2.5 * t
        far = np.array([-33.0, -29.0]) + 3.0 * t
        noisy = np.sort(np.array([near, far]) + 0.75 * rng.standard_normal((2, 2)), axis=1)
        occ = occlude(np.array([0, 1]), noisy[:, 0], noisy[:, 1], config.road.distances)
        k = occ.reported
        lo = np.where(occ.left_hidden[:, None], occ.left_span, noisy[:, :1])
        hi = np.where(occ.right_hidden[:, None], occ.right_span, noisy[:, 1:])
        frames.append((t, Scan(np.array([0, 1])[k], lo[k], hi[k], occ.left_hidden[k],
                               occ.right_hidden[k], np.arange(2)[k])))
    hidden_steps = [t for t, s in frames if 1 not in s.lane]
    assert len(hidden_steps) >= 2 and min(hidden_steps) >= 4

    class Blind:
        name = "none"

        def terms(self, ctx):
            return OcclusionTerms(np.ones(len(ctx.means)), np.zeros(len(ctx.means)))

    for handler, survives in (("measurement-wise", True), (Blind(), False)):
        filt = HighwayTracker(HighwayTrackerConfig.matching(config, particles=256), handler, 2)
        far_existence = []
        for t, scan in frames:
            filt.step(scan)
            if t in hidden_steps:
                lane = filt.lane[: filt.n]
                far_existence.append(filt.r[: filt.n][lane == 1].max(initial=0.0))
        assert (min(far_existence) > 0.9) == survives, far_existence


def _context(seed: int = 0):
    """A tracker's real context after some steps, for handler checks."""
    captured = []
    filt = HighwayTracker(SMALL, "object-wise-grid", seed)
    inner = filt.occlusion

    class Spy:
        name = "spy"

        def terms(self, ctx):
            # the context's arrays are the tracker's own, valid during the call: keep copies
            captured.append(replace(ctx, means=ctx.means.copy(), weights=ctx.weights.copy(),
                                    owner=ctx.owner.copy(), lane=ctx.lane.copy()))
            return inner.terms(ctx)

    filt.occlusion = Spy()
    for _, scan in simulate(SIM, "object-wise", 120, seed):
        filt.step(scan)
    return captured


@pytest.fixture(scope="module")
def contexts():
    return _context(5)[-40:]


@pytest.mark.parametrize("name", TRACKER_NAMES)
def test_handlers_follow_the_interface(name, contexts):
    handler = make_occlusion(name, SMALL)
    assert handler.name == name
    for ctx in contexts:
        terms = handler.terms(ctx)
        k = len(ctx.means)
        assert terms.visible.shape == (k,) and terms.hidden.shape == (k,)
        assert np.all((terms.visible >= 0) & (terms.visible <= 1))
        assert np.all((terms.hidden >= 0) & (terms.hidden <= 1))
        near = ctx.lane == 0
        assert np.all(terms.visible[near] == 1) and np.all(terms.hidden[near] == 0)
        if name == "measurement-wise":
            assert np.all(terms.visible == 1)
            # Skipping far-away runs changes nothing: q as computed for every particle.
            left = ctx.means[:, 0]
            q = ctx.measurement_model.hidden_probability(ctx.lane, left, left + ctx.means[:, 1],
                                                         ctx.measurements)
            assert np.array_equal(terms.hidden, q)
        else:
            assert np.all(terms.hidden == 0)


def test_expval_equals_the_plain_product(contexts):
    """The pruned, vectorised expected-value handler equals the formula written out."""
    handler = ObjectWiseExpval(SMALL)
    beta = SMALL.expval_sharpness
    for ctx in contexts:
        d = ctx.measurement_model.distances
        r, lane, occ_l, occ_r = _track_extents(ctx, d)
        a_l = ctx.means[:, 0] / d[ctx.lane]
        a_r = (ctx.means[:, 0] + ctx.means[:, 1]) / d[ctx.lane]
        v = np.ones(len(a_l))
        for i in range(len(r)):
            cl, cr = a_l - occ_l[i], occ_r[i] - a_r
            inside = (lane[i] < ctx.lane) & (cl > 0) & (cr > 0)
            v *= 1 - r[i] * np.where(inside, (1 - np.exp(-beta * cl)) * (1 - np.exp(-beta * cr)),
                                     0.0)
        v = np.maximum(v, SMALL.expval_min_visible)
        assert np.allclose(handler.terms(ctx).visible, v, rtol=1e-12, atol=1e-14)


def _plain_reading(open_rows, centres, a_l, a_r):
    """Each particle reads the most open cell (its row of `open_rows`) whose centre it covers,
    the cell nearest its middle if it covers none, and 1 outside the grid."""
    inside = (a_l[:, None] < centres) & (centres < a_r[:, None])
    expected = np.ones(len(a_l))
    for k in range(len(a_l)):
        if a_r[k] < centres[0] or a_l[k] > centres[-1]:
            continue
        cells = np.flatnonzero(inside[k])
        if len(cells) == 0:
            cells = [np.argmin(np.abs(centres - 0.5 * (a_l[k] + a_r[k])))]
        expected[k] = open_rows[k, cells].max()
    return expected


def test_grid_equals_the_plain_reading(contexts):
    """The grid handler (run pruning, sparse-table maxima) equals the cell-by-cell reading:
    cell open = prod over nearer tracks of (1 - r P(track covers the cell centre)); a particle
    reads the best cell whose centre it covers (the nearest cell if it covers none)."""
    handler = ObjectWiseGrid(SMALL)
    centres = handler.centres
    for ctx in contexts[-5:]:
        d = ctx.measurement_model.distances
        a_l = ctx.means[:, 0] / d[ctx.lane]
        a_r = (ctx.means[:, 0] + ctx.means[:, 1]) / d[ctx.lane]
        inside = (a_l[:, None] < centres) & (centres < a_r[:, None])
        n = len(ctx.existence)
        open_ = np.ones((len(d), len(centres)))
        for i in range(n):
            mine = ctx.owner == i
            p = ctx.weights[mine] @ inside[mine] / max(ctx.weights[mine].sum(), 1e-300)
            lane = ctx.lane[mine][0]
            open_[lane + 1:] *= 1 - ctx.existence[i] * np.minimum(p, 1.0)
        expected = _plain_reading(open_[ctx.lane], centres, a_l, a_r)
        assert np.allclose(handler.terms(ctx).visible, expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("lanes", [(1, 0), (1, 1), (2, 2)])
def test_grid_spans_the_angles_a_second_lane_car_can_reach(lanes):
    """Cells from -A to A, A = (half_length + max_length + 3 noise_std) / d_2: the widest angle
    of a measured end in the second lane (the first lane's when the road has one)."""
    road = RoadConfig(lanes_right=lanes[0], lanes_left=lanes[1])
    config = HighwayTrackerConfig.matching(SimulationConfig(road=road))
    second = 3.0 if lanes == (1, 0) else 6.0
    widest = (30.0 + 7.0 + 3 * 0.75) / second
    centres = ObjectWiseGrid(config).centres
    assert len(centres) == config.grid_cells == 101
    assert centres[0] == -widest and centres[-1] == widest
    assert np.allclose(np.diff(centres), 2 * widest / 100, rtol=1e-12)


def test_grid_reading_at_every_cell_and_past_both_ends():
    """A lane-1 track whose particles cover different spans (so P(cover) changes from cell to
    cell) and narrow lane-2 particles on every cell, between cells and past both ends of the
    grid: the handler equals the plain reading of cells placed as documented."""
    handler = ObjectWiseGrid(SMALL)
    widest = (SMALL.road.half_length + SMALL.max_length + 3 * SMALL.noise_std) / 6.0
    centres = np.linspace(-widest, widest, SMALL.grid_cells)
    rng = np.random.default_rng(4)
    occluder = np.c_[rng.uniform(-30.0, 10.0, 40), rng.uniform(4.0, 20.0, 40), np.zeros(40)]
    mid = np.r_[centres, 0.7 * centres[:-1] + 0.3 * centres[1:], -widest - 0.01, widest + 0.01]
    behind = np.c_[6.0 * mid - 0.01, np.full(len(mid), 0.02), np.zeros(len(mid))]
    k = len(behind)
    ctx = HighwayContext(means=np.r_[occluder, behind], covs=None,
                         weights=np.r_[rng.uniform(0.5, 1.5, 40), np.ones(k)],
                         owner=np.r_[np.zeros(40, int), np.full(k, -1)],
                         existence=np.array([0.8]), measurements=Scan.empty(),
                         measurement_model=MeasurementModel(SMALL),
                         lane=np.r_[np.zeros(40, int), np.ones(k, int)])
    a_l, a_r = occluder[:, 0] / 3.0, occluder[:, :2].sum(axis=1) / 3.0
    w = ctx.weights[:40] / ctx.weights[:40].sum()
    p_cover = w @ ((a_l[:, None] < centres) & (centres < a_r[:, None]))
    open_ = 1.0 - 0.8 * p_cover
    b_l, b_r = behind[:, 0] / 6.0, behind[:, :2].sum(axis=1) / 6.0
    expected = _plain_reading(np.tile(open_, (k, 1)), centres, b_l, b_r)
    assert len(np.unique(expected)) > 20 and np.all(expected[-2:] == 1.0)
    assert np.allclose(handler.terms(ctx).visible[40:], expected, rtol=1e-12, atol=1e-14)


def _single_occluder_context(existence: float, handler_name: str):
    """One sure track in lane 1 over [-4, 4]; particles of lane 2 behind it and beside it."""
    model = MeasurementModel(SMALL)
    occluder = np.c_[np.full(50, -4.0), np.full(50, 8.0), np.full(50, 3.0)]
    behind = np.array([[-3.0, 4.0, 3.0], [20.0, 4.0, 3.0]])
    ctx = HighwayContext(means=np.r_[occluder, behind], covs=None,
                         weights=np.r_[np.full(50, 1 / 50), 1.0, 1.0],
                         owner=np.r_[np.zeros(50, int), -1, -1], existence=np.array([existence]),
                         measurements=Scan.empty(), measurement_model=model,
                         lane=np.r_[np.zeros(50, int), 1, 1])
    return make_occlusion(handler_name, SMALL).terms(ctx).visible[-2:]


@pytest.mark.parametrize("name", ["object-wise-expval", "object-wise-grid"])
def test_object_wise_handlers_hide_what_is_behind(name):
    # Lane 1 [-4, 4] covers [-8, 8] in lane 2 (twice as far): [-3, 1] is hidden, [20, 24] not.
    sure = _single_occluder_context(1.0, name)
    assert sure[0] < 0.05 and sure[1] == 1.0
    half = _single_occluder_context(0.5, name)
    assert 0.45 < half[0] < 0.6


def test_unknown_handler_is_a_user_error():
    with pytest.raises(OcctrackError, match="unknown occlusion handler 'object-wise-magic'; "
                       "choose from measurement-wise, object-wise-expval, object-wise-grid$"):
        make_occlusion("object-wise-magic", SMALL)


def test_systematic_resample_counts():
    rng = np.random.default_rng(0)
    w = np.array([[0.5, 0.25, 0.25, 0.0], [0.0, 0.0, 1.0, 0.0]])
    idx = systematic_resample(w, 8, rng)
    assert np.array_equal(np.bincount(idx[0], minlength=4), [4, 2, 2, 0])
    assert np.all(idx[1] == 2)


def test_gospa_scores():
    cars = Cars(np.arange(3), np.array([0, 1, 1]), np.array([0.0, 5.0, 20.0]),
                np.array([4.0, 3.0, 5.0]), np.array([3.0, 3.0, 3.0]))
    perfect = Estimates(np.arange(3), cars.lane, cars.left, cars.length, cars.velocity,
                        np.ones(3))
    assert step_gospa(cars, perfect).total == 0
    none = Estimates(*(np.empty(0) for _ in range(6)))
    assert step_gospa(cars, none).total == pytest.approx(3 * 2.5)
    # Right place, wrong lane: infinite distance, so one missed and one false.
    wrong = Estimates(np.arange(1), np.array([2]), cars.left[:1], cars.length[:1],
                      cars.velocity[:1], np.ones(1))
    g = step_gospa(cars, wrong)
    assert g.total == pytest.approx(4 * 2.5) and g.n_false == 1
    d = distances(np.array([0]), np.array([4.0]), np.array([4.0]), np.array([0, 1]),
                  np.array([7.0, 4.0]), np.array([8.0, 4.0]))
    assert d[0, 0] == pytest.approx(5.0) and np.isinf(d[0, 1])
    acc = ScoreAccumulator()
    acc.add(cars, perfect)
    acc.add(cars, none)
    s = acc.result()
    assert s.per_step == pytest.approx(3.75) and s.per_object == pytest.approx(7.5 / 6)
    assert s.missed == pytest.approx(3.75) and s.localisation == 0


def test_evaluate_runs_and_scores():
    score, seconds = evaluate(SIM, SMALL, "object-wise", "object-wise-expval", 60, 2)
    assert score.steps == 60 and seconds > 0
    assert np.isfinite(score.per_step) and score.per_step >= 0
    total = score.localisation + score.missed + score.false
    assert total == pytest.approx(score.per_step)
