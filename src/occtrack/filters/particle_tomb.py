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
operations over particles and (track, measurement) pairs vectorised with numpy. Only pairs in
the same lane whose particle ends come within 6 sigma of the measured ends are scored.

Written here because no well-kept library has a track-oriented multi-Bernoulli filter over
particles with a pluggable occlusion step (Stone Soup's particle filters are single-object and
its multi-object trackers Gaussian); the association itself is occtrack's loopy belief
propagation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.stats import qmc

from occtrack.association import lbp_marginals
from occtrack.config.highway import HighwayTrackerConfig
from occtrack.models.highway_sensor import MeasurementModel, Scan
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
        self.x = np.zeros((s, n, 3))
        self.w = np.zeros((s, n))
        self.r = np.zeros(s)
        self.lane = np.zeros(s, np.int64)
        self.label = np.zeros(s, np.int64)
        self.n = 0
        self.next_label = 0
        nu, nb = c.undetected_particles, c.birth_particles
        self.ux = np.zeros((self.n_lanes, nu + nb, 3))
        self.uw = np.zeros((self.n_lanes, nu + nb))
        self._lanes_u = np.repeat(np.arange(self.n_lanes), nu + nb)
        self._sobol = qmc.Sobol(3, scramble=True, seed=self.rng).random(nb)
        self.last_iterations = 0

    # -- model pieces -------------------------------------------------------------------------
    def _births(self) -> np.ndarray:
        """Cars that entered within the last step: front up to one step past the entry. Drawn
        as a randomly shifted scrambled Sobol set (randomised quasi-Monte Carlo): unbiased like
        plain draws, but it covers the box of (speed, length, entry fraction) more evenly."""
        c, rng = self.config, self.rng
        u = (self._sobol[None] + rng.random((self.n_lanes, 1, 3))) % 1.0
        speed = c.min_speed + (c.max_speed - c.min_speed) * u[..., 0]
        length = c.min_length + (c.max_length - c.min_length) * u[..., 1]
        front = -c.road.half_length + speed * u[..., 2]
        d = self.direction[:, None]
        left = np.where(d > 0, front - length, -front)
        return np.stack([left, length, d * speed], axis=-1)

    # -- one step -----------------------------------------------------------------------------
    def step(self, scan: Scan) -> Estimates:
        c = self.config
        pd = c.detection_probability
        n, N = self.n, c.particles
        x, w, r, lane = self.x[:n], self.w[:n], self.r[:n], self.lane[:n]
        nu = c.undetected_particles

        # 1. Predict.
        alive = _advance(x, w, self.direction[lane], c.road.half_length, c.survival)
        r *= alive
        w /= np.where(alive > 0, alive, 1.0)[:, None]
        ux, uw = self.ux, self.uw
        _advance(ux[:, :nu], uw[:, :nu], self.direction, c.road.half_length, c.survival)
        ux[:, nu:] = self._births()
        uw[:, nu:] = c.birth_rate / c.birth_particles
        order = np.argsort(ux[..., 0], axis=1)
        rows = np.arange(self.n_lanes)[:, None]
        ux[:], uw[:] = ux[rows, order], uw[rows, order]

        # 2. Occlusion terms of every particle.
        ctx = HighwayContext(
            means=np.concatenate([x.reshape(-1, 3), ux.reshape(-1, 3)]),
            covs=None,
            weights=np.concatenate([w.ravel(), uw.ravel()]),
            owner=np.concatenate([np.repeat(np.arange(n), N), np.full(uw.size, -1)]),
            existence=r.copy(),
            measurements=scan,
            measurement_model=self.model,
            lane=np.concatenate([np.repeat(lane, N), self._lanes_u]),
        )
        terms = self.occlusion.terms(ctx)
        v = terms.visible
        miss = 1.0 - pd * v + pd * v * terms.hidden
        v_t, v_u = v[: n * N].reshape(n, N), v[n * N:].reshape(ux.shape[:2])
        miss_t, miss_u = miss[: n * N].reshape(n, N), miss[n * N:].reshape(ux.shape[:2])
        m = len(scan)
        w_miss = 1.0 - r + r * np.sum(w * miss_t, axis=1)

        # 3. Association weights and marginals.
        mlane = scan.lane
        if m:
            first_u, count_u, hit_u = self._undetected_hits(scan, uw * v_u)
            e = pd * hit_u.sum(axis=1)
            # A floor far below any real weight: outside the clutter's support (e.g. a car
            # entering) w_new may be 0, which loopy belief propagation cannot divide by.
            w_new = np.maximum(c.clutter_rate * self.model.clutter_density(scan) + e, 1e-12)
        if m and n:
            ti, mj = self._pairs(x, lane, scan)
            # hit_pair[p, k] = w v p(z | x) of track ti[p]'s particle k and measurement mj[p]
            hit_pair = self.model.hit_weights(x, w * v_t, ti, np.zeros_like(ti),
                                              np.full_like(ti, N), N, scan, mj)
            w_hit = np.zeros((n, m))
            w_hit[ti, mj] = r[ti] * pd * hit_pair.sum(axis=1)
            marg = lbp_marginals(w_hit, w_miss, w_new, c.lbp_tol, c.lbp_max_iter)
            self.last_iterations = marg.iterations
            p_hit, p_miss, p_new = marg.p_hit, marg.p_miss, marg.p_new
        else:
            p_miss = np.ones(n)
            p_new = np.ones(m)

        # 4. Update tracks, the Poisson part, and start new tracks.
        post = (p_miss * r / np.maximum(w_miss, 1e-300))[:, None] * w * miss_t
        if m and n and len(ti):
            gain = p_hit[ti, mj] / np.maximum(w_hit[ti, mj], 1e-300)
            # Pairs come grouped by track (np.nonzero order): add each group's rows at once.
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
                # the Poisson particles each measurement saw (padding has weight 0)
                width = hit_u.shape[1]
                at = np.minimum(first_u[born, None] + np.arange(width), ux.shape[1] - 1)
                self._start_tracks(ux[mlane[born, None], at], hit_u[born], r_born[born],
                                   mlane[born])

        # 5. Resample, regularise, prune; recycle the Poisson particles.
        self._resample_tracks()
        self._resample_undetected()
        self._prune()
        return self.estimates()

    def _undetected_hits(self, scan: Scan, wv_u: np.ndarray):
        """For each measurement, the Poisson particles of its lane whose left end lies within
        6 sigma of the measured shape (a slice of the lane's particles, sorted by left end):
        the slice's first index and length, and the hit weights w v p(z | x) (m, width),
        0 past each slice's end."""
        reach = MeasurementModel.tail * self.config.noise_std
        per_lane = self.ux.shape[1]
        lane = scan.lane
        lo = scan.left[:, 0] - reach
        hi = np.maximum(scan.left[:, 1], scan.right[:, 1]) + reach
        # Rows are sorted; a lane offset far beyond the road makes the whole array sorted.
        shift = 1e3 * (self.config.road.half_length + self.config.max_length + reach)
        keys = (self.ux[..., 0] + shift * np.arange(self.n_lanes)[:, None]).ravel()
        key = lane * per_lane
        first = np.searchsorted(keys, lo + shift * lane) - key
        count = np.searchsorted(keys, hi + shift * lane, side="right") - key - first
        width = max(int(np.max(count)), 1)
        hit = self.model.hit_weights(self.ux, wv_u, lane, first, count, width, scan,
                                     np.arange(len(scan)))
        return first, count, hit

    def _pairs(self, x: np.ndarray, lane: np.ndarray, scan: Scan):
        """(track, measurement) pairs of one lane whose ends can match, grouped by track."""
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
        idx = systematic_resample(weights, c.particles, self.rng)
        s = slice(self.n, self.n + k)
        self.x[s] = self._regularise(idx, particles, weights, lane)
        self.w[s] = 1.0 / c.particles
        self.r[s], self.lane[s] = existence, lane
        self.label[s] = self.next_label + np.arange(k)
        self.next_label += k
        self.n += k

    def _resample_tracks(self) -> None:
        n, c = self.n, self.config
        if n == 0:
            return
        w = self.w[:n]
        ess = 1.0 / np.maximum(np.sum(w * w, axis=1), 1e-300)
        rows = np.flatnonzero((ess < c.resample_threshold * c.particles) & (self.r[:n] > 0))
        if len(rows) == 0:
            return
        x, wr, lane = self.x[rows], w[rows], self.lane[rows]
        idx = systematic_resample(wr, c.particles, self.rng)
        self.x[rows] = self._regularise(idx, x, wr, lane)
        self.w[rows] = 1.0 / c.particles

    def _regularise(self, idx: np.ndarray, x: np.ndarray, w: np.ndarray,
                    lane: np.ndarray) -> np.ndarray:
        """The particles x[row, idx] resampled from the weighted clouds (x, w), moved by the
        Liu-West kernel: xs <- a xs + (1 - a) mean + h chol(cov) eps, a = sqrt(1 - h^2), with
        the mean and covariance of the cloud before resampling (less noisy); then back into
        the prior's support."""
        c = self.config
        h = c.kernel_bandwidth
        if h == 0:
            return x[np.arange(len(x))[:, None], idx]
        eps = self.rng.standard_normal(idx.shape + (3,), dtype=np.float32)
        return _liu_west(np.ascontiguousarray(x, dtype=float),
                         np.ascontiguousarray(w, dtype=float), idx, eps, h,
                         self.direction[lane].astype(float), c.min_length, c.max_length,
                         c.min_speed, c.max_speed)

    def _resample_undetected(self) -> None:
        c = self.config
        nu = c.undetected_particles
        total = self.uw.sum(axis=1)
        idx = systematic_resample(self.uw, nu, self.rng)
        self.ux[:, :nu] = self.ux[np.arange(self.n_lanes)[:, None], idx]
        self.uw[:, :nu] = (total / nu)[:, None]

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


# -- compiled loops (numba): prediction, resampling and the kernel move, one pass per track ---

@njit(cache=True)
def _advance(x, w, direction, half, survival):
    """Constant speed for one step, then P_S: `survival` while the rear is on the section, else
    0, applied to the weights in place. Returns each row's surviving weight."""
    rows, n = w.shape
    alive = np.zeros(rows)
    for i in range(rows):
        for k in range(n):
            x[i, k, 0] += x[i, k, 2]
            rear = x[i, k, 0] if direction[i] > 0 else -(x[i, k, 0] + x[i, k, 1])
            if rear >= half:
                w[i, k] = 0.0
            else:
                w[i, k] *= survival
                alive[i] += w[i, k]
    return alive


@njit(cache=True)
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


@njit(cache=True, inline="always")
def _reflect1(v, lo, hi):
    if v < lo:
        v = 2 * lo - v
    if v > hi:
        v = 2 * hi - v
    return min(max(v, lo), hi)


@njit(cache=True)
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
