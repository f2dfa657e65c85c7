"""Track-oriented multi-Bernoulli tracker over particles for the highway (paper appendix).

State of a car: x = (left end, length, signed velocity), in a lane that is known and fixed per
track; motion is constant speed, x <- (left + velocity, length, velocity). A car survives with
P_S while its rear is on the road section and is gone once it has left.

Objects are a Poisson part for cars not yet detected (particles per lane, fed each step by
births: lambda_b cars per lane entering within the last step, length and speed uniform) and
tracks, each a Bernoulli with existence r and N weighted particles (Williams' track-oriented
PMB, the "TOMB" of the paper, with the Poisson part's hits starting new tracks). One step:

1. predict particles and existence; add births to the Poisson part;
2. occlusion terms v_k, q_k of every particle from the chosen handler (the filter never asks
   which): hit h_kj = w_k P_D v_k p(z_j | x_k), miss m_k = w_k (1 - P_D v_k + P_D v_k q_k);
3. association weights w_hit[i, j] = r_i sum_k h_kj, w_miss[i] = 1 - r_i + r_i sum_k m_k,
   w_new[j] = kappa p_F(z_j) + sum over Poisson particles of h_kj; marginals by loopy belief
   propagation (`occtrack.association.lbp_marginals`, tolerance-stopped);
4. each track becomes the marginal-weighted mixture of its miss and hit posteriors; the Poisson
   part keeps its miss term; measurement j starts a track with r = p_new_j e_j / w_new_j
   (e_j its Poisson hit weight), particles drawn from the Poisson particles it fits;
5. resample tracks whose effective sample size is low (systematic) and move the copies with a
   shrunk Gaussian kernel (Liu and West 2001), which keeps each track's mean and covariance:
   the motion has no noise, so without it the particle cloud would collapse; prune tracks below
   `prune_threshold`; report those above `report_threshold` (existence-weighted means).

All tracks of all lanes are handled at once: arrays (tracks, particles, 3) of fixed capacity,
one array with the Poisson part's particles, so the occlusion handler gets them all without a
copy. Only pairs in the same lane whose particle ends come within 6 sigma of the measured ends
are scored. A step is a few compiled loops (numba; predict, associate, update, resample,
recycle), one pass over the particles each: as numpy array expressions it was about a hundred
array calls, whose overhead, not the arithmetic, set the speed. The loops sum in numpy's
order (pairwise), so they give the numbers the array code gave, to the last bit
(tests/test_highway_kernels.py keeps that code as the reference).

Written here because no well-kept library has a track-oriented multi-Bernoulli filter over
particles with a pluggable occlusion step (Stone Soup's particle filters are single-object and
its multi-object trackers Gaussian); the association itself is occtrack's loopy belief
propagation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from occtrack.association import lbp_marginals
from occtrack.config.highway import HighwayTrackerConfig
from occtrack.jit import njit
from occtrack.models.highway_sensor import MeasurementModel, Scan, _both_orders
from occtrack.occlusion.highway import HighwayContext, make_occlusion


@dataclass(frozen=True)
class Estimates:
    """Reported cars: label (track id), lane, left end, length, signed velocity, existence."""

    label: np.ndarray
    lane: np.ndarray
    left: np.ndarray
    length: np.ndarray
    velocity: np.ndarray
    existence: np.ndarray

    def __len__(self) -> int:
        return len(self.label)

    @property
    def front(self) -> np.ndarray:
        return np.where(self.velocity > 0, self.left + self.length, self.left)


def systematic_resample(weights: np.ndarray, n_out: int, rng: np.random.Generator) -> np.ndarray:
    """Row-wise systematic resampling: (R, N) weights -> (R, n_out) indices into each row."""
    u0 = rng.random(len(weights))
    return _systematic(np.ascontiguousarray(weights, dtype=float), u0, n_out)


class HighwayTracker:
    """`step(scan) -> Estimates`, once per time step. `occlusion` is a handler name
    (measurement-wise, object-wise-expval, object-wise-grid) or an OcclusionModel."""

    def __init__(self, config: HighwayTrackerConfig, occlusion="measurement-wise",
                 seed: int | np.random.Generator = 0):
        config.validate()
        self.config = c = config
        self.occlusion = make_occlusion(occlusion, c) if isinstance(occlusion, str) else occlusion
        self.rng = np.random.default_rng(seed)
        self.model = MeasurementModel(c)
        road = c.road
        self.n_lanes = road.n_lanes
        self.direction = road.directions
        s, n = c.max_tracks, c.particles
        nu, nb = c.undetected_particles, c.birth_particles
        # All particles in one array, the Poisson part's first: the first u + n N rows are
        # what the occlusion handler sees, without copying (u: Poisson particles).
        u = self.n_lanes * (nu + nb)
        self._flat_x = np.zeros((u + s * n, 3))
        self._flat_w = np.zeros(u + s * n)
        self._flat_owner = np.r_[np.full(u, -1), np.repeat(np.arange(s), n)]
        self._flat_lane = np.r_[np.repeat(np.arange(self.n_lanes), nu + nb),
                                np.zeros(s * n, np.int64)]
        self.ux = self._flat_x[:u].reshape(self.n_lanes, nu + nb, 3)
        self.uw = self._flat_w[:u].reshape(self.n_lanes, nu + nb)
        self.x = self._flat_x[u:].reshape(s, n, 3)
        self.w = self._flat_w[u:].reshape(s, n)
        self.r = np.zeros(s)
        self.lane = np.zeros(s, np.int64)
        self.label = np.zeros(s, np.int64)
        self.n = 0
        self.next_label = 0
        self._sobol = qmc.Sobol(3, scramble=True, seed=self.rng).random(nb)
        self.last_iterations = 0

    # -- one step -----------------------------------------------------------------------------
    def step(self, scan: Scan) -> Estimates:
        c = self.config
        pd = c.detection_probability
        n, N = self.n, c.particles
        x, w, r, lane = self.x[:n], self.w[:n], self.r[:n], self.lane[:n]
        ux, uw = self.ux, self.uw

        # 1. Predict tracks and the Poisson part, add the births, sort each lane's Poisson
        # particles by left end.
        shift = self.rng.random((self.n_lanes, 3))
        _predict(x, w, r, self.direction[lane], ux, uw, c.undetected_particles, self._sobol,
                 shift, self.direction, c.road.half_length, c.survival, c.min_speed,
                 c.max_speed, c.min_length, c.max_length, c.birth_rate / c.birth_particles)
        # numpy's vectorised sort is faster here than a compiled loop
        _reorder(ux, uw, np.argsort(ux[..., 0], axis=1))

        # 2. Occlusion terms of every particle (the Poisson part's first).
        k = uw.size + n * N
        self._flat_lane[uw.size:k].reshape(n, N)[:] = lane[:, None]
        ctx = HighwayContext(means=self._flat_x[:k], covs=None, weights=self._flat_w[:k],
                             owner=self._flat_owner[:k], existence=r.copy(),
                             measurements=scan, measurement_model=self.model,
                             lane=self._flat_lane[:k])
        terms = self.occlusion.terms(ctx)

        # 3. Association weights and marginals.
        m = len(scan)
        clutter = (c.clutter_rate * self.model.clutter_density(scan) if m else np.empty(0))
        reach = MeasurementModel.tail * c.noise_std
        a = _associate(x, w, r, lane, ux, uw, np.ascontiguousarray(terms.visible, float),
                       np.ascontiguousarray(terms.hidden, float), pd, scan.lane, scan.left,
                       scan.right, scan.left_hidden, scan.right_hidden, clutter,
                       self.model.sigma, MeasurementModel.tail, reach,
                       1e3 * (c.road.half_length + c.max_length + reach))
        w_miss, miss, w_new, e, first_u, hit_u, ti, mj, hit_pair, w_hit = a
        if m and n:
            marg = lbp_marginals(w_hit, w_miss, w_new, c.lbp_tol, c.lbp_max_iter)
            self.last_iterations = marg.iterations
            p_hit, p_miss, p_new = marg.p_hit, marg.p_miss, marg.p_new
        else:
            p_hit, p_miss, p_new = np.zeros((n, m)), np.ones(n), np.ones(m)

        # 4. Update tracks, the Poisson part, and start new tracks.
        r_born = _update(x, w, r, uw, miss, w_miss, p_miss, p_hit, w_hit, ti, mj, hit_pair,
                         p_new, e, w_new, pd)
        if m:
            born = np.flatnonzero(r_born > c.prune_threshold)
            if len(born):
                # the Poisson particles each measurement saw (padding has weight 0)
                mlane = scan.lane
                width = hit_u.shape[1]
                at = np.minimum(first_u[born, None] + np.arange(width), ux.shape[1] - 1)
                self._start_tracks(ux[mlane[born, None], at], hit_u[born], r_born[born],
                                   mlane[born])

        # 5. Resample, regularise, prune; recycle the Poisson particles.
        self._resample_tracks()
        _recycle(ux, uw, c.undetected_particles, self.rng.random(self.n_lanes))
        self._prune()
        return self.estimates()

    def _start_tracks(self, particles: np.ndarray, weights: np.ndarray, existence: np.ndarray,
                      lane: np.ndarray) -> None:
        c = self.config
        if len(existence) > c.max_tracks - self.n:
            # Full: the strongest of the old and the new tracks keep the slots.
            pool = np.r_[self.r[: self.n], existence]
            keep = np.argsort(-pool, kind="stable")[: c.max_tracks]
            new = np.sort(keep[keep >= self.n]) - self.n
            self._compact(np.sort(keep[keep < self.n]))
            particles, weights, existence, lane = (particles[new], weights[new], existence[new],
                                                   lane[new])
        k = len(existence)
        if k == 0:
            return
        s = slice(self.n, self.n + k)
        self.x[s] = self._resample_move(particles, weights, lane)
        self.w[s] = 1.0 / c.particles
        self.r[s], self.lane[s] = existence, lane
        self.label[s] = self.next_label + np.arange(k)
        self.next_label += k
        self.n += k

    def _resample_tracks(self) -> None:
        n, c = self.n, self.config
        if n == 0:
            return
        rows = _degenerate(self.w[:n], self.r[:n], c.resample_threshold * c.particles)
        if len(rows) == 0:
            return
        self.x[rows] = self._resample_move(self.x[rows], self.w[rows], self.lane[rows])
        self.w[rows] = 1.0 / c.particles

    def _resample_move(self, x: np.ndarray, w: np.ndarray, lane: np.ndarray) -> np.ndarray:
        """`config.particles` particles drawn from each weighted cloud (x, w) by systematic
        resampling, then moved by the Liu-West kernel: xs <- a xs + (1 - a) mean + h chol(cov)
        eps, a = sqrt(1 - h^2), with the mean and covariance of the cloud before resampling
        (less noisy); then back into the prior's support."""
        c = self.config
        h = c.kernel_bandwidth
        x = np.ascontiguousarray(x, dtype=float)
        w = np.ascontiguousarray(w, dtype=float)
        u0 = self.rng.random(len(w))
        if h == 0:
            return x[np.arange(len(x))[:, None], _systematic(w, u0, c.particles)]
        eps = self.rng.standard_normal((len(w), c.particles, 3), dtype=np.float32)
        return _resample_move(x, w, u0, eps, h, self.direction[lane].astype(float),
                              c.min_length, c.max_length, c.min_speed, c.max_speed)

    def _prune(self) -> None:
        keep = np.flatnonzero(self.r[: self.n] >= self.config.prune_threshold)
        if len(keep) < self.n:
            self._compact(keep)

    def _compact(self, keep: np.ndarray) -> None:
        k = len(keep)
        for a in (self.x, self.w, self.r, self.lane, self.label):
            a[:k] = a[keep]
        self.n = k

    def estimates(self) -> Estimates:
        n = self.n
        sel = np.flatnonzero(self.r[:n] > self.config.report_threshold)
        mean = np.matmul(self.w[sel][:, None, :], self.x[sel])[:, 0]
        return Estimates(self.label[sel].copy(), self.lane[sel].copy(), mean[:, 0], mean[:, 1],
                         mean[:, 2], self.r[sel].copy())


# -- compiled loops (numba): one call per stage of a step, one pass over the particles each ---

@njit
def _row_sum(a):
    """np.sum of a contiguous 1-D array, in numpy's order: pairwise over blocks of 128, each
    block summed in 8 interleaved partial sums. Keeping the order keeps the results of the
    numpy code this replaced, to the last bit."""
    n = len(a)
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
        r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
        i = 8
        stop = n - n % 8
        while i < stop:
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return _row_sum(a[:half]) + _row_sum(a[half:])


@njit
def _advance(x, w, direction, half, survival):
    """Constant speed for one step, then P_S: `survival` while the rear is on the section, else
    0, applied to the weights in place. Returns each row's surviving weight."""
    rows, n = w.shape
    alive = np.zeros(rows)
    for i in range(rows):
        total = 0.0
        forward = direction[i] > 0
        for k in range(n):
            left = x[i, k, 0] + x[i, k, 2]
            x[i, k, 0] = left
            rear = left if forward else -(left + x[i, k, 1])
            if rear >= half:
                w[i, k] = 0.0
            else:
                w[i, k] *= survival
                total += w[i, k]
        alive[i] = total
    return alive


@njit
def _predict(x, w, r, track_direction, ux, uw, nu, sobol, shift, direction, half, survival,
             min_speed, max_speed, min_length, max_length, birth_weight):
    """Step 1 in place: tracks and the Poisson part's first `nu` particles per lane move and
    survive (`_advance`), each track's existence takes its surviving weight and its weights
    are normalised again; the last particles of each lane become the births, cars that
    entered within the last step (front up to one step past the entry). Births are a scrambled
    Sobol set shifted by `shift[lane]` (randomised quasi-Monte Carlo: unbiased like plain
    draws, but it covers the box of (speed, length, entry fraction) more evenly)."""
    alive = _advance(x, w, track_direction, half, survival)
    for i in range(len(r)):
        r[i] *= alive[i]
        scale = alive[i] if alive[i] > 0 else 1.0
        for k in range(w.shape[1]):
            w[i, k] /= scale
    _advance(ux[:, :nu], uw[:, :nu], direction, half, survival)
    lanes, per_lane = uw.shape
    u = np.empty(3)
    for lane in range(lanes):
        d = direction[lane]
        for k in range(nu, per_lane):
            for e in range(3):
                # (a + b) mod 1 for a, b in [0, 1): the subtraction is exact, as fmod is
                u[e] = sobol[k - nu, e] + shift[lane, e]
                if u[e] >= 1.0:
                    u[e] -= 1.0
            speed = min_speed + (max_speed - min_speed) * u[0]
            length = min_length + (max_length - min_length) * u[1]
            front = -half + speed * u[2]
            ux[lane, k, 0] = front - length if d > 0 else -front
            ux[lane, k, 1] = length
            ux[lane, k, 2] = d * speed
            uw[lane, k] = birth_weight


@njit
def _reorder(ux, uw, order):
    """Each lane's particles put in `order[lane]`."""
    for lane in range(uw.shape[0]):
        xs = ux[lane][order[lane]]
        ws = uw[lane][order[lane]]
        ux[lane] = xs
        uw[lane] = ws


@njit
def _window(row, lo, hi):
    """The slice [first, end) of the sorted `row` whose values lie in [lo, hi]."""
    a, b = 0, len(row)
    while a < b:
        mid = (a + b) // 2
        if row[mid] < lo:
            a = mid + 1
        else:
            b = mid
    first = a
    b = len(row)
    while a < b:
        mid = (a + b) // 2
        if row[mid] <= hi:
            a = mid + 1
        else:
            b = mid
    return first, a


@njit
def _associate(x, w, r, lane, ux, uw, visible, hidden, pd, z_lane, z_left, z_right, z_lh,
               z_rh, clutter, sigma, tail, reach, shift):
    """Steps 2-3 after the occlusion handler: miss terms of every particle (flat: the Poisson
    part's particles, then the tracks'), each track's miss weight, the Poisson part's hit
    weights and each measurement's new-object weight, the gated (track, measurement) pairs
    with their particles' hit weights, and the hit weight of every pair.

    The Poisson particles a measurement can have come from are the slice of its lane's
    (sorted by left end) whose left end lies within `reach` of the measured shape: compared
    after adding `shift` times the lane number to both sides, as in the flat search over all
    lanes this replaced. Pairs are those of one lane whose particle ends come within `reach`
    of the measured ends, grouped by track."""
    n, N = w.shape
    lanes, per_lane = uw.shape
    m = len(z_lane)
    inv = 1.0 / sigma
    miss = np.empty(len(visible))
    for k in range(len(visible)):
        pv = pd * visible[k]
        miss[k] = 1.0 - pv + pv * hidden[k]
    base = lanes * per_lane
    row = np.empty(N)
    w_miss = np.empty(n)
    for i in range(n):
        for k in range(N):
            row[k] = w[i, k] * miss[base + i * N + k]
        w_miss[i] = 1.0 - r[i] + r[i] * _row_sum(row)

    # the Poisson part
    first = np.zeros(m, np.int64)
    count = np.zeros(m, np.int64)
    key = np.empty(per_lane)
    for j in range(m):
        lj = z_lane[j]
        off = shift * lj
        for k in range(per_lane):
            key[k] = ux[lj, k, 0] + off
        lo = z_left[j, 0] - reach
        hi = max(z_left[j, 1], z_right[j, 1]) + reach
        a, b = _window(key, lo + off, hi + off)
        first[j] = a
        count[j] = b - a
    width = 1
    for j in range(m):
        width = max(width, count[j])
    hit_u = np.zeros((m, width))
    e = np.empty(m)
    w_new = np.empty(m)
    for j in range(m):
        lj, f0 = z_lane[j], first[j]
        zl0, zl1, lh = z_left[j, 0], z_left[j, 1], z_lh[j]
        zr0, zr1, rh = z_right[j, 0], z_right[j, 1], z_rh[j]
        for k in range(count[j]):
            p = f0 + k
            wv = uw[lj, p] * visible[lj * per_lane + p]
            lo = ux[lj, p, 0]
            if (k > 0 and lo == ux[lj, p - 1, 0] and ux[lj, p, 1] == ux[lj, p - 1, 1]
                    and wv == uw[lj, p - 1] * visible[lj * per_lane + p - 1]):
                hit_u[j, k] = hit_u[j, k - 1]  # a copy (resampling), beside its original
                continue
            hit_u[j, k] = wv * _both_orders(lo, lo + ux[lj, p, 1], zl0, zl1, lh, zr0, zr1, rh,
                                            inv, tail)
        e[j] = pd * _row_sum(hit_u[j])
        # A floor far below any real weight: outside the clutter's support (e.g. a car
        # entering) w_new may be 0, which loopy belief propagation cannot divide by.
        w_new[j] = max(clutter[j] + e[j], 1e-12)

    # the tracks: gate, then score the pairs
    ti = np.empty(n * m, np.int64)
    mj = np.empty(n * m, np.int64)
    pairs = 0
    for i in range(n):
        l_min = l_max = x[i, 0, 0]
        r_min = r_max = x[i, 0, 0] + x[i, 0, 1]
        for k in range(1, N):
            left = x[i, k, 0]
            right = left + x[i, k, 1]
            l_min = min(l_min, left)
            l_max = max(l_max, left)
            r_min = min(r_min, right)
            r_max = max(r_max, right)
        for j in range(m):
            if (lane[i] == z_lane[j] and l_min - reach <= z_left[j, 1]
                    and l_max + reach >= z_left[j, 0] and r_min - reach <= z_right[j, 1]
                    and r_max + reach >= z_right[j, 0]):
                ti[pairs] = i
                mj[pairs] = j
                pairs += 1
    ti, mj = ti[:pairs], mj[:pairs]
    hit_pair = np.empty((pairs, N))
    w_hit = np.zeros((n, m))
    for p in range(pairs):
        i, j = ti[p], mj[p]
        zl0, zl1, lh = z_left[j, 0], z_left[j, 1], z_lh[j]
        zr0, zr1, rh = z_right[j, 0], z_right[j, 1], z_rh[j]
        for k in range(N):
            lo = x[i, k, 0]
            hit_pair[p, k] = (w[i, k] * visible[base + i * N + k]) * _both_orders(
                lo, lo + x[i, k, 1], zl0, zl1, lh, zr0, zr1, rh, inv, tail)
        w_hit[i, j] = r[i] * pd * _row_sum(hit_pair[p])
    return w_miss, miss, w_new, e, first, hit_u, ti, mj, hit_pair, w_hit


@njit
def _update(x, w, r, uw, miss, w_miss, p_miss, p_hit, w_hit, ti, mj, hit_pair, p_new, e,
            w_new, pd):
    """Step 4 in place: each track becomes the marginal-weighted mixture of its miss and hit
    posteriors (existence and normalised weights), the Poisson part keeps its miss term.
    Returns the existence of the track each measurement would start."""
    n, N = w.shape
    lanes, per_lane = uw.shape
    base = lanes * per_lane
    post = np.empty((n, N))
    for i in range(n):
        coef = p_miss[i] * r[i] / max(w_miss[i], 1e-300)
        for k in range(N):
            post[i, k] = coef * w[i, k] * miss[base + i * N + k]
    # A track's pairs are summed as np.add.reduceat summed them: the first pair's term plus
    # the running sum of the others' terms.
    head = np.empty(N)
    rest = np.empty(N)
    pairs = len(ti)
    p = 0
    while p < pairs:
        i = ti[p]
        q = p
        while q < pairs and ti[q] == i:
            j = mj[q]
            scale = p_hit[i, j] / max(w_hit[i, j], 1e-300) * r[i] * pd
            if q == p:
                for k in range(N):
                    head[k] = scale * hit_pair[q, k]
            elif q == p + 1:
                for k in range(N):
                    rest[k] = scale * hit_pair[q, k]
            else:
                for k in range(N):
                    rest[k] += scale * hit_pair[q, k]
            q += 1
        if q == p + 1:
            for k in range(N):
                post[i, k] += head[k]
        else:
            for k in range(N):
                post[i, k] += head[k] + rest[k]
        p = q
    for i in range(n):
        r_post = _row_sum(post[i])
        r[i] = min(max(r_post, 0.0), 1.0)
        scale = r_post if r_post > 0 else 1.0
        for k in range(N):
            w[i, k] = post[i, k] / scale
    for lane in range(lanes):
        for k in range(per_lane):
            uw[lane, k] *= miss[lane * per_lane + k]
    r_born = np.empty(len(e))
    for j in range(len(e)):
        r_born[j] = p_new[j] * e[j] / max(w_new[j], 1e-300)
    return r_born


@njit
def _degenerate(w, r, threshold):
    """Tracks whose effective sample size 1 / sum w^2 is below `threshold` (and r > 0)."""
    n, N = w.shape
    sq = np.empty(N)
    rows = np.empty(n, np.int64)
    count = 0
    for i in range(n):
        for k in range(N):
            sq[k] = w[i, k] * w[i, k]
        if 1.0 / max(_row_sum(sq), 1e-300) < threshold and r[i] > 0:
            rows[count] = i
            count += 1
    return rows[:count]


@njit
def _recycle(ux, uw, nu, u0):
    """The Poisson part's particles of each lane, resampled (systematic) to `nu` of equal
    weight, their total kept."""
    lanes, per_lane = uw.shape
    idx = _systematic(uw, u0, nu)
    for lane in range(lanes):
        total = _row_sum(uw[lane])
        xs = ux[lane][idx[lane]]
        ux[lane, :nu] = xs
        for k in range(nu):
            uw[lane, k] = total / nu


@njit
def _systematic(weights, u0, n_out):
    """Systematic resampling of each row with offset u0[row]: index k is drawn for the points
    (u0 + j) / n_out that fall in its slice of the cumulative weight."""
    rows, n = weights.shape
    idx = np.empty((rows, n_out), np.int64)
    for r in range(rows):
        total = 0.0
        for k in range(n):
            total += weights[r, k]
        scale = 1.0 / total if total > 0 else 0.0
        k = 0
        c = weights[r, 0] * scale
        for j in range(n_out):
            u = (u0[r] + j) / n_out
            while c <= u and k < n - 1:
                k += 1
                c += weights[r, k] * scale
            idx[r, j] = k
    return idx


@njit
def _reflect1(v, lo, hi):
    if v < lo:
        v = 2 * lo - v
    if v > hi:
        v = 2 * hi - v
    return min(max(v, lo), hi)


@njit
def _liu_west(x, w, idx, eps, h, direction, min_length, max_length, min_speed, max_speed):
    rows, n_out = idx.shape
    n = x.shape[1]
    out = np.empty((rows, n_out, 3))
    a = math.sqrt(1.0 - h * h)
    mean = np.empty(3)
    cov = np.empty((3, 3))
    chol = np.zeros((3, 3))
    for r in range(rows):
        total = 0.0
        for k in range(n):
            total += w[r, k]
        mean[:] = 0.0
        for k in range(n):
            for d in range(3):
                mean[d] += w[r, k] * x[r, k, d]
        mean /= total
        cov[:] = 0.0
        for k in range(n):
            wk = w[r, k] / total
            for d in range(3):
                dd = x[r, k, d] - mean[d]
                for e in range(d + 1):
                    cov[d, e] += wk * dd * (x[r, k, e] - mean[e])
        for d in range(3):  # Cholesky of the 3 x 3, lower; the jitter keeps it positive
            for e in range(d + 1):
                t = cov[d, e] + (1e-10 if d == e else 0.0)
                for f in range(e):
                    t -= chol[d, f] * chol[e, f]
                chol[d, e] = math.sqrt(max(t, 0.0)) if d == e else (
                    t / chol[e, e] if chol[e, e] > 0 else 0.0)
        sign = direction[r]
        for j in range(n_out):
            src = idx[r, j]
            for d in range(3):
                move = 0.0
                for e in range(d + 1):
                    move += chol[d, e] * eps[r, j, e]
                out[r, j, d] = a * x[r, src, d] + (1.0 - a) * mean[d] + h * move
            out[r, j, 1] = _reflect1(out[r, j, 1], min_length, max_length)
            out[r, j, 2] = sign * _reflect1(sign * out[r, j, 2], min_speed, max_speed)
    return out


@njit
def _resample_move(x, w, u0, eps, h, direction, min_length, max_length, min_speed, max_speed):
    """`_systematic` then `_liu_west`, in one call."""
    return _liu_west(x, w, _systematic(w, u0, eps.shape[1]), eps, h, direction, min_length,
                     max_length, min_speed, max_speed)
