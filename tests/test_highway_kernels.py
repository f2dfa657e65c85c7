"""The highway's compiled kernels against the plain numpy they replaced.

The particle tracker's step runs as a few compiled kernels (predict, associate, update,
resample, recycle); `NumpyStep` below is the step as it was written with numpy array
expressions, on the same random stream. Both must give the same states and estimates bit for
bit (the kernels sum rows in numpy's pairwise order), with more than 128 particles a row so
that the pairwise sums recurse. The sensor's kernels (hidden parts, q, clutter density) are
checked against their numpy forms on simulated scans."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.association import lbp_marginals
from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig
from occtrack.filters.particle_tomb import (
    HighwayTracker,
    _advance,
    _liu_west,
    _row_sum,
    systematic_resample,
)
from occtrack.models.highway_sensor import MeasurementModel, Scan
from occtrack.occlusion.extents import union
from occtrack.occlusion.highway import TRACKER_NAMES, HighwayContext
from occtrack.scenarios.highway import simulate

SIM = SimulationConfig()
# rows above 128 (pairwise sums recurse) and a full track table now and then
CONFIG = HighwayTrackerConfig.matching(SIM, particles=200, undetected_particles=72,
                                      birth_particles=64, max_tracks=12)


class NumpyStep(HighwayTracker):
    """The tracker's step in numpy array expressions (the reference the kernels replaced)."""

    def step(self, scan: Scan):
        c = self.config
        pd = c.detection_probability
        n, N = self.n, c.particles
        x, w, r, lane = self.x[:n], self.w[:n], self.r[:n], self.lane[:n]
        nu = c.undetected_particles
        alive = _advance(x, w, self.direction[lane], c.road.half_length, c.survival)
        r *= alive
        w /= np.where(alive > 0, alive, 1.0)[:, None]
        ux, uw = self.ux, self.uw
        _advance(ux[:, :nu], uw[:, :nu], self.direction, c.road.half_length, c.survival)
        ux[:, nu:] = self._births()
        uw[:, nu:] = c.birth_rate / c.birth_particles
        order = np.argsort(ux[..., 0], axis=1, kind="stable")
        rows = np.arange(self.n_lanes)[:, None]
        ux[:], uw[:] = ux[rows, order], uw[rows, order]

        ctx = HighwayContext(
            means=np.concatenate([x.reshape(-1, 3), ux.reshape(-1, 3)]), covs=None,
            weights=np.concatenate([w.ravel(), uw.ravel()]),
            owner=np.concatenate([np.repeat(np.arange(n), N), np.full(uw.size, -1)]),
            existence=r.copy(), measurements=scan, measurement_model=self.model,
            lane=np.concatenate([np.repeat(lane, N),
                                 np.repeat(np.arange(self.n_lanes), ux.shape[1])]))
        terms = self.occlusion.terms(ctx)
        v = terms.visible
        miss = 1.0 - pd * v + pd * v * terms.hidden
        v_t, v_u = v[: n * N].reshape(n, N), v[n * N:].reshape(ux.shape[:2])
        miss_t, miss_u = miss[: n * N].reshape(n, N), miss[n * N:].reshape(ux.shape[:2])
        m = len(scan)
        w_miss = 1.0 - r + r * np.sum(w * miss_t, axis=1)
        if m:
            first_u, hit_u = self._undetected_hits(scan, uw * v_u)
            e = pd * hit_u.sum(axis=1)
            w_new = np.maximum(c.clutter_rate * clutter_density(self.model, scan) + e, 1e-12)
        if m and n:
            ti, mj = self._pairs(x, lane, scan)
            hit_pair = self.model.hit_weights(x, w * v_t, ti, np.zeros_like(ti),
                                              np.full_like(ti, N), N, scan, mj)
            w_hit = np.zeros((n, m))
            w_hit[ti, mj] = r[ti] * pd * hit_pair.sum(axis=1)
            marg = lbp_marginals(w_hit, w_miss, w_new, c.lbp_tol, c.lbp_max_iter)
            p_hit, p_miss, p_new = marg.p_hit, marg.p_miss, marg.p_new
        else:
            p_miss, p_new = np.ones(n), np.ones(m)
        post = (p_miss * r / np.maximum(w_miss, 1e-300))[:, None] * w * miss_t
        if m and n and len(ti):
            gain = p_hit[ti, mj] / np.maximum(w_hit[ti, mj], 1e-300)
            first = np.flatnonzero(np.diff(ti, prepend=-1))
            post[ti[first]] += np.add.reduceat((gain * r[ti] * pd)[:, None] * hit_pair, first)
        r_post = post.sum(axis=1)
        r[:] = np.clip(r_post, 0.0, 1.0)
        w[:] = post / np.where(r_post > 0, r_post, 1.0)[:, None]
        uw *= miss_u
        if m:
            r_born = p_new * e / np.maximum(w_new, 1e-300)
            born = np.flatnonzero(r_born > c.prune_threshold)
            if len(born):
                width = hit_u.shape[1]
                at = np.minimum(first_u[born, None] + np.arange(width), ux.shape[1] - 1)
                self._start_tracks(ux[scan.lane[born, None], at], hit_u[born], r_born[born],
                                   scan.lane[born])
        self._resample_tracks()
        total = uw.sum(axis=1)
        idx = systematic_resample(uw, nu, self.rng)
        ux[:, :nu] = ux[np.arange(self.n_lanes)[:, None], idx]
        uw[:, :nu] = (total / nu)[:, None]
        self._prune()
        return self.estimates()

    def _births(self):
        c, rng = self.config, self.rng
        u = (self._sobol[None] + rng.random((self.n_lanes, 1, 3))) % 1.0
        speed = c.min_speed + (c.max_speed - c.min_speed) * u[..., 0]
        length = c.min_length + (c.max_length - c.min_length) * u[..., 1]
        front = -c.road.half_length + speed * u[..., 2]
        d = self.direction[:, None]
        left = np.where(d > 0, front - length, -front)
        return np.stack([left, length, d * speed], axis=-1)

    def _undetected_hits(self, scan, wv_u):
        reach = MeasurementModel.tail * self.config.noise_std
        per_lane = self.ux.shape[1]
        lane = scan.lane
        lo = scan.left[:, 0] - reach
        hi = np.maximum(scan.left[:, 1], scan.right[:, 1]) + reach
        shift = 1e3 * (self.config.road.half_length + self.config.max_length + reach)
        keys = (self.ux[..., 0] + shift * np.arange(self.n_lanes)[:, None]).ravel()
        key = lane * per_lane
        first = np.searchsorted(keys, lo + shift * lane) - key
        count = np.searchsorted(keys, hi + shift * lane, side="right") - key - first
        width = max(int(np.max(count)), 1)
        hit = self.model.hit_weights(self.ux, wv_u, lane, first, count, width, scan,
                                     np.arange(len(scan)))
        return first, hit

    def _pairs(self, x, lane, scan):
        reach = MeasurementModel.tail * self.config.noise_std
        left = x[..., 0]
        right = left + x[..., 1]
        l_min, l_max = left.min(axis=1), left.max(axis=1)
        r_min, r_max = right.min(axis=1), right.max(axis=1)
        gate = ((lane[:, None] == scan.lane[None, :])
                & (l_min[:, None] - reach <= scan.left[None, :, 1])
                & (l_max[:, None] + reach >= scan.left[None, :, 0])
                & (r_min[:, None] - reach <= scan.right[None, :, 1])
                & (r_max[:, None] + reach >= scan.right[None, :, 0]))
        return np.nonzero(gate)

    def _resample_tracks(self):
        n, c = self.n, self.config
        if n == 0:
            return
        w = self.w[:n]
        ess = 1.0 / np.maximum(np.sum(w * w, axis=1), 1e-300)
        rows = np.flatnonzero((ess < c.resample_threshold * c.particles) & (self.r[:n] > 0))
        if len(rows) == 0:
            return
        self.x[rows] = self._resample_move(self.x[rows], w[rows], self.lane[rows])
        self.w[rows] = 1.0 / c.particles

    def _resample_move(self, x, w, lane):
        c = self.config
        idx = systematic_resample(w, c.particles, self.rng)
        eps = self.rng.standard_normal(idx.shape + (3,), dtype=np.float32)
        return _liu_west(np.ascontiguousarray(x, dtype=float),
                         np.ascontiguousarray(w, dtype=float), idx, eps, c.kernel_bandwidth,
                         self.direction[lane].astype(float), c.min_length, c.max_length,
                         c.min_speed, c.max_speed)


def clutter_density(model: MeasurementModel, scan: Scan) -> np.ndarray:
    """p_F(z_j) in numpy array expressions."""
    def overlap(a0, a1, b0, b1):
        return np.clip(np.minimum(a1, b1) - np.maximum(a0, b0), 0.0, None)

    half = model.half_length
    lmin, lmax = model.clutter_lengths
    c = 1.0 / (model.n_lanes * 2.0 * half * (lmax - lmin))
    lh, rh = scan.left_hidden, scan.right_hidden
    s_lo = np.maximum(scan.left[:, 0], -half)
    s_hi = np.minimum(scan.left[:, 1], half)
    e_lo, e_hi = scan.right[:, 0], scan.right[:, 1]
    out = np.zeros(len(scan))
    seen_s = (scan.left[:, 0] >= -half) & (scan.left[:, 0] <= half)
    gap = e_lo - scan.left[:, 0]
    vv = ~lh & ~rh
    out[vv] = (seen_s & (gap >= lmin) & (gap <= lmax))[vv]
    hv = lh & ~rh
    out[hv] = overlap(s_lo, s_hi, e_lo - lmax, e_lo - lmin)[hv]
    vh = ~lh & rh
    out[vh] = (seen_s * overlap(e_lo, e_hi, scan.left[:, 0] + lmin, scan.left[:, 0] + lmax))[vh]
    hh = lh & rh
    s0, s1, e0, e1 = s_lo[hh], s_hi[hh], e_lo[hh], e_hi[hh]
    knots = np.stack([s0, s1, e0 - lmax, e0 - lmin, e1 - lmax, e1 - lmin], axis=1)
    knots = np.sort(np.clip(knots, s0[:, None], np.maximum(s0, s1)[:, None]), axis=1)
    width = overlap(e0[:, None], e1[:, None], knots + lmin, knots + lmax)
    out[hh] = np.sum(0.5 * (width[:, 1:] + width[:, :-1]) * np.diff(knots, axis=1), axis=1)
    return c * out


def _state(tracker: HighwayTracker) -> bytes:
    n = tracker.n
    return b"".join(a.tobytes() for a in (tracker.x[:n], tracker.w[:n], tracker.r[:n],
                                          tracker.lane[:n], tracker.label[:n], tracker.ux,
                                          tracker.uw))


@pytest.mark.parametrize("sensor", ["object-wise", "measurement-wise"])
@pytest.mark.parametrize("name", TRACKER_NAMES)
def test_step_kernels_equal_the_numpy_step_bit_for_bit(name, sensor):
    fast = HighwayTracker(CONFIG, name, seed=7)
    plain = NumpyStep(CONFIG, name, seed=7)
    full = 0
    for t, (_, scan) in enumerate(simulate(SIM, sensor, 250, 7)):
        a, b = fast.step(scan), plain.step(scan)
        for field in ("label", "lane", "left", "length", "velocity", "existence"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), (t, field)
        assert _state(fast) == _state(plain), t
        full += fast.n == CONFIG.max_tracks
    assert fast.next_label > 100 and full > 0


@pytest.mark.parametrize("n", [*range(1, 140), 255, 256, 257, 768, 1000])
def test_row_sum_is_numpys_sum(n):
    rng = np.random.default_rng(n)
    a = rng.standard_normal(n) * 10.0 ** rng.integers(-8, 8, n)
    assert _row_sum(a) == np.sum(a)


@pytest.fixture(scope="module")
def scans():
    return [scan for sensor in ("object-wise", "measurement-wise")
            for _, scan in simulate(SIM, sensor, 400, 3)]


def test_clutter_density_equals_the_numpy_form(scans):
    model = MeasurementModel(CONFIG)
    hidden_both = 0
    for scan in scans:
        assert np.array_equal(model.clutter_density(scan), clutter_density(model, scan))
        hidden_both += int(np.sum(scan.left_hidden & scan.right_hidden))
    assert hidden_both > 0


def test_occluded_parts_and_q_equal_the_plain_forms(scans):
    """Parts: the union, lane after lane, of the nearer lanes' shapes (by angle); q: the sum
    over every part of a lane of P(l' in part) P(r' in part), no part skipped, no copy
    reused (each particle comes twice in a row here, as copies do after resampling)."""
    model = MeasurementModel(CONFIG)
    sigma = model.sigma
    rng = np.random.default_rng(0)

    def phi(x):
        return 0.5 * np.array([math.erfc(-v / math.sqrt(2.0)) for v in x])

    for scan in scans[::25]:
        parts = []
        starts, ends = np.empty(0), np.empty(0)
        lo, hi = scan.extent
        for k, d in enumerate(model.distances):
            parts.append((starts * d, ends * d))
            sel = scan.lane == k
            starts, ends = union(np.r_[starts, lo[sel] / d], np.r_[ends, hi[sel] / d])
        got = model.occluded_parts(scan)
        for (a, b), (c, e) in zip(parts, got, strict=True):
            assert np.array_equal(a, c) and np.array_equal(b, e)
        lane = rng.integers(0, len(model.distances), 300)
        left = rng.uniform(-40, 40, 300)
        right = left + rng.uniform(2, 7, 300)
        lane, left, right = np.repeat(lane, 2), np.repeat(left, 2), np.repeat(right, 2)
        q = np.zeros(len(lane))
        for i in range(len(lane)):
            a, b = parts[lane[i]]
            q[i] = np.sum((phi((b - left[i]) / sigma) - phi((a - left[i]) / sigma))
                          * (phi((b - right[i]) / sigma) - phi((a - right[i]) / sigma)))
        got = model.hidden_probability(lane, left, right, scan)
        # parts beyond 6 sigma of an end are skipped: a probability below 1e-8 is lost
        assert np.allclose(got, np.clip(q, 0, 1), rtol=1e-12, atol=1e-8)
        # a copy takes its original's q, the very number computed for it alone
        alone = model.hidden_probability(lane[::2], left[::2], right[::2], scan)
        assert np.array_equal(got[::2], alone) and np.array_equal(got[1::2], alone)
