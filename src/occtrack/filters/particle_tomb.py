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
are scored. A step is a few compiled loops (Cython, filters/_filters.pyx; predict, associate,
update, resample, recycle), one pass over the particles each: as numpy array expressions it
was about a hundred array calls, whose overhead, not the arithmetic, set the speed. The loops
sum in numpy's order (pairwise), so they give the numbers the array code gave, to the last bit
(tests/test_highway_kernels.py keeps that code as the reference).

Written here because no well-kept library has a track-oriented multi-Bernoulli filter over
particles with a pluggable occlusion step (Stone Soup's particle filters are single-object and
its multi-object trackers Gaussian); the association itself is occtrack's loopy belief
propagation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from occtrack.association import lbp_marginals
from occtrack.config.highway import HighwayTrackerConfig

# The compiled loops (Cython, filters/_filters.pyx): one call per stage of a step, one pass
# over the particles each. _advance, _liu_west, _reflect1, _row_sum and _window are only
# called inside the others (and by the tests).
from occtrack.filters._filters import (  # noqa: F401
    _advance,
    _associate,
    _degenerate,
    _liu_west,
    _predict,
    _recycle,
    _reflect1,
    _reorder,
    _resample_move,
    _row_sum,
    _systematic,
    _update,
    _window,
)
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
