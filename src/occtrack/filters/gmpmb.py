"""Track-oriented Poisson multi-Bernoulli filter over Gaussian mixtures (paper section III).

Objects are a multi-Bernoulli set plus a Poisson part (DESIGN section 1). Bernoulli i has
existence r_i and a Gaussian-mixture density; the Poisson part, objects never detected, is a
Gaussian-mixture intensity. All of them live in one pool of at most `capacity` components:
component k has a mass w_k, a Gaussian (mean, covariance), the probabilities d_k that it is
detectable and o_k that its measurement can be occluded (two-state Markov features), and a
label: the slot of its Bernoulli, or -1 for the Poisson part. A Bernoulli's existence is the
sum of its components' masses, r_i = sum_{k in i} w_k, and its density their normalised mixture.

One step (predict, birth, update):

    occlusion   v_k, q_k (and h_j) from the occlusion model; with occludability o_k only an
                occludable measurement can be hidden, so P_D = d_k (1 - o_k + o_k v_k) and
                miss_k = 1 - P_D + d_k o_k v_k q_k                       (paper sec. IV)
    hit         l_kj = w_k d_k (1 - o_k + o_k v_k (1 - h_j)) p(z_j | x_k)
    objects     L_ij = sum_{k in i} l_kj,  miss_i = 1 - r_i + sum_{k in i} w_k miss_k
    new         L_0j = kappa p_F(z_j) (1 - o h_j) + sum_{k Poisson} l_kj
    association p_hit, p_miss, p_new from loopy belief propagation (Williams and Lau)
    children    miss child of k in i:  w_k miss_k p_miss_i / miss_i  (state kept, d and o
                updated by Bayes), hit child of k by z_j: l_kj p_hit_ij / L_ij (Kalman update,
                d = 1, o updated by Bayes); Poisson components: miss child w_k miss_k, hit child
                l_kj p_new_j / L_0j, which together are the new Bernoulli of measurement j,
                existence p_new_j (L_0j - kappa p_F (1 - o h_j)) / L_0j.

h_j is measurement-wise occlusion's term for a detection that was seen: the probability that
the other visible detections would have hidden an occludable measurement at z_j. Only a
source that was not occludable, or escaped, gives z_j, hence the factor 1 - o h_j (o_k for an
object, the stationary occludability o for clutter). Without the occludability feature this
factor would be one constant for every source and cancel (the paper drops it, and so did the
authors' prototype); with it, it decides between an object seen in front (low o_k) and a
hidden, occludable one that would otherwise claim the detections of the people in front of
it at no cost.

Occlusion without immortality (issue 9). An undetected object's existence follows
r' = r m / (1 - r + r m), its odds multiplied by m = sum_k w_k miss_k / r each missed frame,
with miss_k = 1 - d_k + d_k o_k v_k q_k. m is near 1 only while something explains the miss:
a detection in front of it (q_k, measurement-wise) or a tracked object in front (v_k,
object-wise), and an occludability o_k near 1, which the misses themselves teach (o rises by
Bayes after a miss with q > 0, falls after one with q = 0). With nothing in front, m = 1 - d_k
and the object is gone in a few frames; when its cover walks away, likewise. Three rules keep
this honest on real detections:
- n-of-m confirmation: a Bernoulli is deleted unless it takes a detection (p_hit > 1/2) in
  `confirm_hits` of its first `confirm_window` tracked frames, and occlusion enters the miss
  and hit terms of confirmed objects only (o = 0 for the others): a newborn's broad density
  overlaps the detections around it, and a miss it could blame on them would keep a false
  track alive;
- a missed component's velocity relaxes to zero with `coast_velocity_time` (the motion
  model's Ornstein-Uhlenbeck velocity): people stop and turn behind others;
- `occtrack.tracker` reports an undetected object only while it has been unseen for at most
  `report_coast_time` and its centre is known to within `report_centre_std` box heights; it
  is kept, unreported, for as long as m holds its existence, so its label survives.

Then the children lighter than `prune_mass` are dropped; each Bernoulli keeps at most its
`max_components_per_object` heaviest, rescaled so that its existence is unchanged (only the
tail of its density goes); Bernoullis below `label_min_existence` are recycled into the Poisson
part (their components lose the label, their mass becomes intensity); components of one object
that fall in the same small cell of state space are merged by moment matching. The pool and the
label slots grow with the scene (arrays double when full), so memory follows the number of
people in view and stays flat however long the sequence. A positive `capacity` or `max_labels`
is a hard limit instead (the heaviest children, the strongest Bernoullis are kept), and the
first time it bites a warning says how many were cut.

Gating: a component and a detection can associate only if the detection's box overlaps the
component's gate (its predicted box widened by `gate_sigmas` edge standard deviations, one gate
per object: the union of its components'), found by a sweep (`occtrack.spatial`), so the
likelihoods, the sums L_ij and loopy BP (cluster by cluster, `lbp_sparse`) cost what the pairs
that can interact cost. A pair outside the gate has a likelihood below e^(-gate_sigmas^2 / 2)
of the component's best (with the default 9, e^-40: times the largest ratio of a component's
peak density to the clutter density, about 1e6, still far below `prune_mass` for any child it
could give). An association edge with L_ij < EDGE_FLOOR miss_i w_new_j cannot reach
p_hit_ij = EDGE_FLOOR (1e-9), so its hit children fall below `prune_mass` whatever loopy BP
says; leaving such edges out splits a crowd's graph into the clusters that really compete.
`gating = false` computes every pair and keeps every edge, to check that nothing moves
(benchmarks/bench_gating.py: no MOT17 metric moves).

Hand-written: no maintained library offers a labelled Gaussian-mixture PMB filter with a
pluggable miss term. The loops over components, pairs and cells and the bookkeeping between
them (the `_`-prefixed functions at the end of this module) are compiled (`occtrack.jit`): a
frame is too small for numpy's per-call overhead to pay off. Each reproduces the numpy
expression it replaced to the last bit (tests/test_kernels.py, tests/test_update_kernels.py);
where numpy and the C library round differently (a power), numpy computes it.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from occtrack.association import lbp_sparse
from occtrack.config import TrackerConfig
from occtrack.jit import njit
from occtrack.models.aspect import AspectPrior
from occtrack.models.birth import EdgeBirths
from occtrack.models.box import MIN_HEIGHT, BoxMeasurement
from occtrack.models.markov import TwoStateMarkov
from occtrack.models.motion import ConstantVelocity
from occtrack.occlusion.base import OcclusionContext, OcclusionModel
from occtrack.spatial import DENSE_PAIRS, overlapping_pairs

N_BIRTH = 5
LOG_FLOOR = -300.0
EDGE_FLOOR = 1e-9  # gating: association edges that cannot reach this p_hit are left out
INITIAL_POOL = 256  # components, when the pool grows with the scene
INITIAL_SLOTS = 32  # label slots, likewise
NO_CLASSES = np.zeros(0, dtype=np.int64)  # (the kernels' "one class")


class GaussianMixturePMB:
    """The filter's state and its step. `config` is already validated."""

    def __init__(self, config: TrackerConfig, occlusion: OcclusionModel):
        c = config
        self.config = c
        self.occlusion = occlusion
        self.measurement = BoxMeasurement(c.image_size, c.edge_noise, c.border_margin)
        self.aspect = AspectPrior() if c.aspect_prior else None
        self.detectability = TwoStateMarkov(c.stationary_detectability, c.detectability_ratio)
        self.occludability = TwoStateMarkov(c.occludability, c.occludability_ratio)
        self._dt_models: dict[float, tuple] = {}
        self._use_dt(c.dt)
        self.births = EdgeBirths(c.image_size, c.inward_speed, c.birth_speed_std)
        self.image_size = np.asarray(c.image_size, dtype=float)
        cap = c.capacity or INITIAL_POOL
        L = c.max_labels or INITIAL_SLOTS
        self.n = 0
        self.mass = np.zeros(cap)
        self.mean = np.zeros((cap, 2, 3))
        self.cov = np.zeros((cap, 2, 3, 3))
        self.det = np.zeros(cap)
        self.occ = np.zeros(cap)
        self.label = np.full(cap, -1, dtype=np.int64)
        self.coast = np.zeros(cap)  # seconds since the component's object was last detected
        self.slot_used = np.zeros(L, dtype=bool)
        # per label slot: tracked frames since birth, frames detected, seconds since the last
        # detection, and the detection taken at the last step (-1: missed)
        self.slot_age = np.zeros(L, dtype=np.int64)
        self.slot_hits = np.zeros(L, dtype=np.int64)
        self.slot_coast = np.zeros(L)
        self.slot_detection = np.full(L, -1, dtype=np.int64)
        self.slot_serial = np.full(L, -1, dtype=np.int64)  # unique per Bernoulli ever labelled
        # the class of each Bernoulli (that of the detection it was born from; it never takes
        # a detection of another class), and the probability that its last miss, if it was
        # missed, was occlusion's doing: d o (1 - v + v q) / miss, mass-weighted over its
        # components (0 under no occlusion)
        self.slot_class = np.zeros(L, dtype=np.int64)
        self.slot_hidden = np.zeros(L)
        self._next_serial = 0
        self.steps = 0
        self.iterations = 0  # loopy BP iterations of the last step
        # running sums of detected half-sizes (count, sum, sum of squares) for the birth prior
        self._size_stats = np.zeros((3, 2))
        self._size_settings = tuple(np.zeros(0) if value is None else np.asarray(value, float)
                                    for value in (c.birth_half_size, c.birth_half_size_std))
        self._warned: set[str] = set()  # hard limits already reported

    # -- storage --------------------------------------------------------------------------

    _POOL = ("mass", "mean", "cov", "det", "occ", "label", "coast")
    _SLOTS = ("slot_used", "slot_age", "slot_hits", "slot_coast", "slot_detection",
              "slot_serial", "slot_class", "slot_hidden")

    def _reserve(self, size: int) -> None:
        """Room for `size` components: the pool's arrays at least double when they grow."""
        if size <= len(self.mass):
            return
        new = max(size, 2 * len(self.mass))
        fill = {"label": -1}
        for name in self._POOL:
            old = getattr(self, name)
            arr = np.full((new,) + old.shape[1:], fill.get(name, 0), dtype=old.dtype)
            arr[:self.n] = old[:self.n]
            setattr(self, name, arr)

    def _reserve_slots(self, size: int) -> None:
        """Room for `size` label slots, likewise; a new slot is unused."""
        old_size = len(self.slot_used)
        if size <= old_size:
            return
        new = max(size, 2 * old_size)
        fill = {"slot_detection": -1, "slot_serial": -1}
        for name in self._SLOTS:
            old = getattr(self, name)
            arr = np.full(new, fill.get(name, 0), dtype=old.dtype)
            arr[:old_size] = old
            setattr(self, name, arr)

    def _warn_once(self, what: str, message: str) -> None:
        if what not in self._warned:
            self._warned.add(what)
            # (the caller of Tracker.step: _warn_once, _select or _assign_labels, _update,
            # the filter's step, Tracker.step)
            warnings.warn(message, RuntimeWarning, stacklevel=6)

    # -- public -------------------------------------------------------------------------

    def existence(self) -> np.ndarray:
        """r of every label slot (0 where unused)."""
        n = self.n
        lab = self.label[:n] >= 0
        return np.bincount(self.label[:n][lab], weights=self.mass[:n][lab],
                           minlength=len(self.slot_used))

    def object_means(self) -> tuple[np.ndarray, np.ndarray]:
        """(r, mean state) of every slot: mass-weighted mean of its components' means."""
        r, means, _ = self.object_moments()
        return r, means

    def object_moments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r, mean state, centre standard deviation (L, 2) in px) of every slot: the moments
        of its mixture, spread of the means included."""
        n = self.n
        return _object_moments(self.label[:n], self.mass[:n], self.mean[:n], self.cov[:n],
                               len(self.slot_used))

    def confirmed(self) -> np.ndarray:
        """Which slots have been detected in `confirm_hits` tracked frames."""
        return self.slot_used & (self.slot_hits >= self.config.confirm_hits)

    def step(self, z: np.ndarray, scores: np.ndarray,
             camera: tuple[np.ndarray, ...] | None = None, dt: float | None = None,
             classes: np.ndarray | None = None) -> None:
        """Move with the camera, predict to this frame, add births, update with its
        detections z (M, 2, 2). `camera` is (scale (2,), shift (2,)[, shift variance (2,)]):
        the image point x of the last frame is at scale * x + shift in this one, the shift
        known to within its variance (px^2; `move_image`). `dt` is the time since the last
        step in seconds (default `config.dt`); `classes` (M,) the detections' classes: an
        object takes only detections of its own class (None: one class)."""
        self._use_dt(self.config.dt if dt is None else float(dt))
        observed = self.measurement.observed(z)
        self._learn_sizes(z, observed)
        if self.aspect is not None:
            self.aspect.learn(z, observed)
        if camera is not None:
            self.move_image(*camera)
        self._predict()
        self._add_births()
        self._update(z, observed, scores, classes)
        self.steps += 1

    def _use_dt(self, dt: float) -> None:
        """Motion models and survival for a step of dt seconds (cached per dt: a steady frame
        rate builds them once; the Markov features take dt at each prediction)."""
        models = self._dt_models.get(dt)
        if models is None:
            c = self.config
            if len(self._dt_models) >= 64:  # jittery timestamps: keep the cache bounded
                self._dt_models.clear()
            models = (ConstantVelocity(dt, c.position_noise, c.velocity_noise, c.size_noise,
                                       c.velocity_time),
                      ConstantVelocity(dt, c.position_noise, c.velocity_noise, c.size_noise,
                                       c.coast_velocity_time),
                      float(np.exp(-c.death_rate * dt)),
                      (self.detectability.memory(dt), self.occludability.memory(dt)))
            self._dt_models[dt] = models
        self.dt = dt
        self.motion, self.coast_motion, self.survival_inside, self._memories = models

    # -- prediction -----------------------------------------------------------------------

    def move_image(self, scale: np.ndarray, shift: np.ndarray,
                   shift_variance: np.ndarray | None = None) -> None:
        """Carry every component along an image motion x -> scale * x + shift per axis:
        centres move, velocities and half-sizes scale, covariances scale by scale^2. An
        uncertain shift (its variance per axis, px^2) widens every centre by that variance."""
        n = self.n
        variance = np.zeros(2) if shift_variance is None else np.asarray(shift_variance, float)
        _move_in_place(self.mean[:n], self.cov[:n], np.asarray(scale, dtype=float),
                       np.asarray(shift, dtype=float), variance)

    def _predict(self) -> None:
        n = self.n
        if n == 0:
            return
        _predict_pool(self.mass[:n], self.mean[:n], self.cov[:n], self.det[:n], self.occ[:n],
                      self.coast[:n], 0.5 * self.dt, self.motion.F, self.motion.Q,
                      self.coast_motion.F, self.coast_motion.Q,
                      self.detectability.stationary, self._memories[0],
                      self.occludability.stationary, self._memories[1], self.image_size,
                      self.survival_inside, self.config.exit_survival)

    def _size_prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Half-size (mean, std) of a newborn, px: the configured values, else those of the
        detections seen so far, else (30, 90) and a third of it."""
        return _prior_sizes(self._size_stats, *self._size_settings)

    def _learn_sizes(self, z: np.ndarray, observed: np.ndarray) -> None:
        _count_sizes(z, observed, self._size_stats)

    def _add_births(self) -> None:
        c = self.config
        spread = c.spread_birth_rate * self.dt + (c.initial_objects if self.steps == 0 else 0.0)
        size_mean, size_std = self._size_prior()
        mass, means, covs = self.births.components(c.edge_birth_rate * self.dt, spread,
                                                   size_mean, size_std, 2.0 * size_mean[1])
        self._reserve(self.n + len(mass))
        self.n = _append_births(self.n, mass, means, covs, c.birth_detectability,
                                c.birth_occludability, self.mass, self.mean, self.cov, self.det,
                                self.occ, self.label, self.coast)

    # -- update ---------------------------------------------------------------------------

    def _update(self, z: np.ndarray, observed: np.ndarray, scores: np.ndarray,
                classes: np.ndarray | None = None) -> None:
        c = self.config
        self._sort_by_label()
        n, M = self.n, len(z)
        mass, mean, cov = self.mass[:n], self.mean[:n], self.cov[:n]
        det, label, coast = self.det[:n], self.label[:n], self.coast[:n]
        # occlusion explains the misses of confirmed objects only: a newborn's broad density
        # overlaps the detections around it, and a miss it could blame on them would keep a
        # false track alive; the others are treated as not occludable (o = 0)
        established, occ, o_seen, r_slot, within = _occludable(
            label, mass, self.occ[:n], self.slot_used, self.slot_hits, c.confirm_hits,
            c.occludability)
        ctx = OcclusionContext(means=mean, covs=cov, weights=within, owner=label,
                               existence=r_slot, measurements=z,
                               measurement_model=self.measurement)
        terms = self.occlusion.terms(ctx)
        v, q, pd, miss = _miss_terms(det, occ, terms.visible, terms.hidden)

        seen_hidden = np.zeros(M) if terms.seen_hidden is None else _clipped(
            terms.seen_hidden, 0.0, 1.0)
        # objects: rows 0..A-1 are the used slots, row A the Poisson part; components are
        # sorted by label, so each object's sums are sums over one contiguous run
        slots, rows = _object_rows(label, self.slot_used)
        A = len(slots)

        # hit weights l_kj of the pairs (component pk, detection pj) that can associate
        pk, pj, log_hit, (cand_row, cand_col, cand_of_pair) = self._pairs(
            mean, cov, z, observed, rows, A)
        # o_seen: a source not yet confirmed is weighed like clutter, with the stationary o:
        # were it taken as never occludable, a detection in a crowd would start a new track
        # more easily than it is called clutter
        pk, pj, hit, edge_of_pair, poisson_hit, e_row, e_col, L_edge = _hit_edges(
            pk, pj, log_hit, cand_of_pair, cand_row, cand_col, rows, A, M, mass, det, o_seen,
            v, seen_hidden, pd, bool(seen_hidden.any()), label, self.slot_class,
            NO_CLASSES if classes is None else classes)

        W, H = self.image_size
        # (numpy's power, not libm's: they differ in the last bit)
        score_term = _clipped(scores, c.score_floor, 1.0) ** (-c.clutter_score_power)
        # an edge with L_ij < EDGE_FLOOR miss_i w_new_j has p_hit_ij below EDGE_FLOOR (nu_ij
        # <= 1 / w_new_j), so its hit children are below prune_mass whatever BP says; leaving
        # such edges out (gating) splits a crowd's graph into the clusters that really compete
        miss_obj, w_new, strong, s_row, s_col, s_L = _association_weights(
            rows, A, mass, miss, det, occ, v, q, slots, self.slot_hidden, z, score_term,
            seen_hidden, poisson_hit, c.clutter_rate, W * H, c.occludability, e_row, e_col,
            L_edge, EDGE_FLOOR if c.gating else 0.0)
        marg = lbp_sparse(s_row, s_col, s_L, miss_obj, w_new, tol=c.lbp_tolerance,
                          max_iter=c.lbp_max_iterations)
        self.iterations = marg.iterations
        self._count_detections(slots, s_row, s_col, marg.p_hit)

        # children: one miss child per component, then one hit child per pair
        children = _children(mass, miss, rows, hit, pj, edge_of_pair, strong, marg.p_hit,
                             L_edge, marg.p_new, w_new, marg.p_miss, miss_obj)
        keep, parent, j, new_mass = _kept_children(
            children, self._select(children) if c.capacity else None, c.prune_mass, n, pk, pj,
            M, label, c.max_components_per_object, len(self.slot_used))
        new_mean, new_cov, new_label, h, newborn = _inherit(mean, cov, label, parent, j)
        new_det, new_occ, new_coast = _child_features(
            parent, j, det, occ, self.occ[:n], established, v, q, miss, seen_hidden, coast,
            self.dt)
        if len(h):
            self.measurement.update_rows(new_mean, new_cov, h, z, observed, j[h])
            if self.aspect is not None:
                self.aspect.update_rows(new_mean, new_cov, h, observed, j[h])

        new_label = self._assign_labels(new_mass, new_label, newborn, M, classes)
        new_mass, new_mean, new_cov, new_det, new_occ, new_coast, new_label = self._merge(
            new_mass, new_mean, new_cov, new_det, new_occ, new_coast, new_label)
        alive = self._confirm_or_delete(new_label)

        if not alive.all():
            new_mass, new_mean, new_cov = new_mass[alive], new_mean[alive], new_cov[alive]
            new_det, new_occ, new_coast = new_det[alive], new_occ[alive], new_coast[alive]
            new_label = new_label[alive]
        k = len(new_mass)
        self.n = 0  # (nothing of the old pool is kept)
        self._reserve(k)
        self.n = k
        self.mass[:k], self.mean[:k], self.cov[:k] = new_mass, new_mean, new_cov
        self.det[:k], self.occ[:k] = _clipped(new_det, 0.0, 1.0), _clipped(new_occ, 0.0, 1.0)
        self.coast[:k], self.label[:k] = new_coast, new_label
        self._cap_existence()

    def _pairs(self, mean: np.ndarray, cov: np.ndarray, z: np.ndarray, observed: np.ndarray,
               rows: np.ndarray, A: int):
        """The (component, detection) pairs that can associate and log p(z_j | x_k) on them:
        (pk, pj, loglik, candidates). Small problems and `gating = false` list every pair,
        and every (object, detection) pair is a candidate edge. Otherwise the pairs
        whose gates overlap: one gate per object row (the union of its components' gates, so
        each object is looked up once), one per Poisson component, and the candidates are
        the (object row, detection) pairs found. Candidates are (row, column, candidate of each
        listed pair)."""
        n, M = len(mean), len(z)
        c = self.config
        zhat, S = self.measurement.innovation(mean, cov)
        if not c.gating or n * M <= DENSE_PAIRS:
            pk, pj, cand = _all_pairs(n, M, rows, A)
            return pk, pj, self.measurement.loglik_pairs(mean, zhat, S, z, observed, pk, pj), cand
        gates = self.measurement.gates(zhat, S, c.gate_sigmas)
        first = np.ones(n, dtype=bool)
        first[1:] = (rows[1:] != rows[:-1]) | (rows[1:] == A)
        start = np.flatnonzero(first)
        size = np.diff(np.append(start, n))
        unit_gates = np.stack([np.minimum.reduceat(gates[..., 0], start),
                               np.maximum.reduceat(gates[..., 1], start)], axis=-1)
        boxes = z
        unmeasured = ~observed.any(axis=2)  # both edges of an axis on the border: no gate
        if unmeasured.any():
            boxes = z.copy()
            boxes[unmeasured] = [-np.inf, np.inf]
        ui, uj = overlapping_pairs(unit_gates, boxes)
        count = size[ui]
        total = int(count.sum())
        cand_of_pair = np.repeat(np.arange(len(ui)), count)
        pk = np.repeat(start[ui] - (np.cumsum(count) - count), count) + np.arange(total)
        pj = uj[cand_of_pair]
        loglik = self.measurement.loglik_pairs(mean, zhat, S, z, observed, pk, pj)
        return pk, pj, loglik, (rows[start[ui]], uj, cand_of_pair)

    def _count_detections(self, slots: np.ndarray, row: np.ndarray, col: np.ndarray,
                          p_hit: np.ndarray) -> None:
        """Per-slot bookkeeping of this step's association: an object (row of `slots`) took
        detection j when p_hit_ij > 1/2 (at most one j can); p_hit is given on the pairs
        (row, col)."""
        _count_in_place(self.slot_detection, self.slot_age, self.slot_hits, self.slot_coast,
                        self.slot_used, slots, row, col, p_hit, self.dt)

    def _confirm_or_delete(self, label: np.ndarray) -> np.ndarray:
        """Delete the Bernoullis that can no longer be detected in `confirm_hits` of their
        first `confirm_window` tracked frames (n-of-m confirmation): a false detection that
        repeats for a frame or two starts one, and it must not live on. Returns the mask of
        components kept."""
        c = self.config
        return _confirm_in_place(self.slot_used, self.slot_age, self.slot_hits, label,
                                 c.confirm_window, c.confirm_hits)

    def _sort_by_label(self) -> None:
        """Order the pool by label, Poisson part first (births arrive at the end)."""
        n = self.n
        _sort_pool(self.mass[:n], self.mean[:n], self.cov[:n], self.det[:n], self.occ[:n],
                   self.coast[:n], self.label[:n])

    def _select(self, flat: np.ndarray) -> np.ndarray:
        """Indices (sorted) of the children above the pruning mass; under a hard `capacity`
        the heaviest of them, leaving room for the next step's births (the first time it
        bites, a warning gives the count)."""
        keep = np.flatnonzero(flat > self.config.prune_mass)
        capacity = self.config.capacity
        room = capacity - N_BIRTH
        if capacity and len(keep) > room:
            order = np.argpartition(-flat[keep], room - 1)
            lost = flat[keep[order[room:]]]
            self._warn_once("capacity", (
                f"capacity = {capacity} Gaussian components reached at step {self.steps + 1}: "
                f"{len(keep)} were above prune_mass, the {len(lost)} lightest (mass up to "
                f"{lost.max():.3g}) were dropped; set capacity = 0 to let the pool grow with "
                f"the scene (reported once)"))
            keep = keep[order[:room]]
            keep.sort()
        return keep

    def _assign_labels(self, mass: np.ndarray, label: np.ndarray, newborn: np.ndarray,
                       M: int, classes: np.ndarray | None = None) -> np.ndarray:
        """Keep a label for every Bernoulli (existing and new) above the label threshold
        (under a hard `max_labels`, for the strongest that many: the first time that recycles
        one above the threshold, a warning gives the count); recycle the others into the
        Poisson part."""
        limit = self.config.max_labels
        label, meas, lost, held = _keep_labels(label, mass, newborn, self.slot_used, M,
                                               self.config.label_min_existence, limit)
        if len(lost):
            self._warn_once("labels", (
                f"max_labels = {limit} reached at step {self.steps + 1}: {held} "
                f"Bernoullis held existence >= {self.config.label_min_existence:g}, the "
                f"{len(lost)} weakest (existence up to {lost.max():.3g}; "
                f"{int((lost > self.config.report_existence).sum())} of them above "
                f"report_existence) were recycled into the Poisson part and lose their tracks; "
                f"set max_labels = 0 to let labels grow with the scene (reported once)"))
        if len(meas):
            self._reserve_slots(int(self.slot_used.sum()) + len(meas))
            label = _open_slots(label, newborn, meas, M, self._next_serial,
                                self.slot_used, self.slot_serial, self.slot_age,
                                self.slot_hits, self.slot_coast, self.slot_detection,
                                self.slot_class, NO_CLASSES if classes is None else classes)
            self._next_serial += len(meas)
        return label

    def _merge(self, mass, mean, cov, det, occ, coast, label):
        """Merge components of one label that fall in the same cell of (centre, velocity,
        half-size) space by moment matching: masses add, the mean and covariance are those of
        the pooled mixture (spread of the means included), d, o and the coasting time are
        mass-weighted averages. Cells are `merge_position` / `merge_velocity` box heights
        wide, the height rounded to a power of two so that similar boxes share a grid."""
        if len(mass) < 2:
            return mass, mean, cov, det, occ, coast, label
        c = self.config
        cell = np.array([c.merge_position, c.merge_velocity, c.merge_position] * 2)
        # one integer per cell (mixed radix, label first) when it fits: one sort instead of
        # lexsort's eight, the same order
        fits, key, pooled = _merge_packed(mean, label, cell, mass, cov, det, occ, coast)
        if fits:
            return pooled
        order = np.lexsort(key.T[::-1])
        key = key[order]
        start = np.ones(len(order), dtype=bool)
        start[1:] = (key[1:] != key[:-1]).any(axis=1)
        if start.all():
            return mass, mean, cov, det, occ, coast, label
        return _pool_cells(order, start, mass, mean, cov, det, occ, coast, label)

    def _cap_existence(self) -> None:
        """Guard against r exceeding 1 by rounding: scale such an object's masses down."""
        n = self.n
        _cap_in_place(self.mass[:n], self.label[:n], len(self.slot_used))



@njit
def _label_sums(label, mass, L):
    """r_i = sum of w_k over the components with label i, for i < L (label -1: none)."""
    r = np.zeros(L)
    for k in range(len(label)):
        if label[k] >= 0:
            r[label[k]] += mass[k]
    return r


@njit
def _rank_bernoullis(label, mass, newborn, used, M, min_existence):
    """(used slots, measurements with a newborn Bernoulli, the existence of each of those
    in that order, their indices strongest first among those at min_existence or above)."""
    r_old = _label_sums(label, mass, len(used))
    r_new = _label_sums(newborn, mass, M)
    old = np.flatnonzero(used)
    new = np.flatnonzero(r_new > 0)
    r_all = np.concatenate((r_old[old], r_new[new]))
    ranked = np.argsort(-r_all, kind="mergesort")
    return old, new, r_all, ranked[r_all[ranked] >= min_existence]


@njit
def _keep_labels(label, mass, newborn, used, M, min_existence, limit):
    """`GaussianMixturePMB._assign_labels` up to the opening of new slots: the strongest
    Bernoullis at min_existence or above keep (or will get) a label, at most `limit` of them
    when limit > 0; the other used slots are freed in place and their components' labels set
    to -1. Returns (labels, the measurements whose newborn gets a slot (ascending), the
    existences cut by the limit, how many Bernoullis were at min_existence or above)."""
    old, new, r_all, ranked = _rank_bernoullis(label, mass, newborn, used, M, min_existence)
    held = len(ranked)
    lost = np.empty(0)
    if limit and held > limit:
        lost = r_all[ranked[limit:]]
        ranked = ranked[:limit]
    keep_old, keep_new = _split_ranked(ranked, len(old))
    gone = np.zeros(len(used), dtype=np.bool_)
    for i in range(len(old)):
        if not keep_old[i]:
            used[old[i]] = False
            gone[old[i]] = True
    out = label.copy()
    for k in range(len(label)):
        if label[k] >= 0 and gone[label[k]]:
            out[k] = -1
    return out, new[keep_new], lost, held


@njit
def _split_ranked(ranked, n_old):
    """Which of the n_old existing Bernoullis keep their label, and the new ones that get
    one (indices among the new, ascending)."""
    keep_old = np.zeros(n_old, dtype=np.bool_)
    count = 0
    for i in ranked:
        if i < n_old:
            keep_old[i] = True
        else:
            count += 1
    keep_new = np.empty(count, np.int64)
    count = 0
    for i in ranked:
        if i >= n_old:
            keep_new[count] = i - n_old
            count += 1
    keep_new.sort()
    return keep_old, keep_new


@njit
def _open_slots(label, newborn, meas, M, serial0, used, serial, age, hits, coast, detection,
                cls, classes):
    """Give the newborn Bernoullis of measurements `meas` the first free slots (in place on
    the slot arrays): serials from serial0, one hit at age 1, their measurement's class
    (`classes`, empty: one class). Returns the components' labels."""
    slot_of_meas = np.full(M, -1, dtype=np.int64)
    i = 0
    for s in range(len(used)):
        if i == len(meas):
            break
        if not used[s]:
            used[s] = True
            slot_of_meas[meas[i]] = s
            serial[s] = serial0 + i
            age[s] = 1
            hits[s] = 1
            coast[s] = 0.0
            detection[s] = meas[i]
            cls[s] = classes[meas[i]] if len(classes) else 0
            i += 1
    out = label.copy()
    for k in range(len(label)):
        if newborn[k] >= 0:
            out[k] = slot_of_meas[newborn[k]]
    return out


@njit
def _occludable(label, mass, occ_all, used, hits, confirm_hits, stationary):
    """(established, o, o_seen, r per slot, w_k / r of its object) of each component:
    occlusion is for the components of confirmed objects (`GaussianMixturePMB.confirmed`: used
    slots with `confirm_hits` hits; o = 0 for the others; o_seen, the
    o that weighs a detection's source, is the `stationary` occludability for them); the
    Poisson part's components keep w_k."""
    n = len(label)
    r = _label_sums(label, mass, len(used))
    established = np.zeros(n, dtype=np.bool_)
    occ, o_seen, within = np.zeros(n), np.full(n, stationary), np.empty(n)
    for k in range(n):
        i = label[k]
        if i >= 0:
            established[k] = used[i] and hits[i] >= confirm_hits
            if established[k]:
                occ[k] = occ_all[k]
                o_seen[k] = occ_all[k]
            within[k] = mass[k] / max(r[i], 1e-300)
        else:
            within[k] = mass[k]
    return established, occ, o_seen, r, within


@njit
def _miss_terms(det, occ, visible, hidden):
    """(v, q, P_D, miss) per component, v and q clipped to [0, 1]: P_D = d (1 - o + o v) and
    miss = 1 - P_D + d o v q (the module docstring's occlusion line)."""
    n = len(det)
    v, q, pd, miss = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        v[k] = min(max(visible[k], 0.0), 1.0)
        q[k] = min(max(hidden[k], 0.0), 1.0)
        pd[k] = det[k] * (1.0 - occ[k] + occ[k] * v[k])
        miss[k] = 1.0 - pd[k] + det[k] * occ[k] * v[k] * q[k]
    return v, q, pd, miss


@njit
def _sort_pool(mass, mean, cov, det, occ, coast, label):
    """Stable sort of the pool's arrays (views of its first n entries) by label, in place.
    The usual pool is sorted but for the births appended at its end (label -1): then the
    stable sort is a rotation that moves them in front of the labelled components."""
    n = len(label)
    t = n
    while t > 0 and label[t - 1] == -1:
        t -= 1
    p = 0
    while p < t and label[p] == -1:
        p += 1
    for k in range(p + 1, t):
        if label[k] < label[k - 1]:
            break
    else:
        if p < t < n:
            for a in (mass, det, occ, coast):
                _rotate(a, p, t)
            _rotate(mean, p, t)
            _rotate(cov, p, t)
            _rotate(label, p, t)
        return
    order = np.argsort(label, kind="mergesort")
    for i in range(len(order)):
        if order[i] != i:
            break
    else:
        return
    mass[:] = mass[order]
    mean[:] = mean[order]
    cov[:] = cov[order]
    det[:] = det[order]
    occ[:] = occ[order]
    coast[:] = coast[order]
    label[:] = label[order]


@njit
def _rotate(a, p, t):
    """a[p:] becomes a[t:] followed by a[p:t]."""
    tail = a[p:].copy()
    a[p:p + len(a) - t] = tail[t - p:]
    a[p + len(a) - t:] = tail[:t - p]


@njit
def _count_in_place(detection, age, hits, coast, used, slots, row, col, p_hit, dt):
    """`GaussianMixturePMB._count_detections` on the slot arrays, in place."""
    detection[:] = -1
    for e in range(len(p_hit)):
        if p_hit[e] > 0.5:
            detection[slots[row[e]]] = col[e]
    for i in range(len(used)):
        hit = detection[i] >= 0
        if used[i]:
            age[i] += 1
            if not hit:
                coast[i] += dt
        if hit:
            hits[i] += 1
            coast[i] = 0.0


@njit
def _confirm_in_place(used, age, hits, label, window, needed):
    """`GaussianMixturePMB._confirm_or_delete`: frees the doomed slots in place and returns
    which components are kept."""
    doomed = np.zeros(len(used), dtype=np.bool_)
    any_doomed = False
    for i in range(len(used)):
        if used[i] and hits[i] + max(window - age[i], 0) < needed:
            doomed[i] = True
            used[i] = False
            any_doomed = True
    keep = np.ones(len(label), dtype=np.bool_)
    if any_doomed:
        for k in range(len(label)):
            if label[k] >= 0 and doomed[label[k]]:
                keep[k] = False
    return keep


@njit
def _cap_in_place(mass, label, L):
    """`GaussianMixturePMB._cap_existence` in place: an object whose masses sum above 1
    (rounding) has them scaled by 1 / r."""
    r = _label_sums(label, mass, L)
    for k in range(len(label)):
        i = label[k]
        if i >= 0 and r[i] > 1.0:
            mass[k] *= 1.0 / max(r[i], 1e-300)


@njit
def _merge_packed(mean, label, cell, mass, cov, det, occ, coast):
    """(fits, cell keys, the pool merged): `_cell_keys`, then `_packed_order` and
    `_pool_cells` when the packed keys fit (else the pool comes back as given, for the
    lexsort path), and the pool as given when no two components share a cell."""
    key = _cell_keys(mean, label, cell)
    fits, order, start = _packed_order(key)
    if fits:
        for i in range(len(start)):
            if not start[i]:
                return True, key, _pool_cells(order, start, mass, mean, cov, det, occ, coast,
                                              label)
    return fits, key, (mass, mean, cov, det, occ, coast, label)


@njit
def _pool_cells(order, start, mass, mean, cov, det, occ, coast, label):
    """Moment matching of the runs of `order` that `start` opens (one run a cell): mass
    W = sum w_k, mean mu = sum s_k m_k and covariance sum s_k (P_k + (m_k - mu)(m_k - mu)')
    with shares s_k = w_k / W; d, o and the coasting time are share-weighted means. A
    component alone in its cell comes out unchanged."""
    G = 0
    for i in range(len(start)):
        G += start[i]
    B, d = mean.shape[1], mean.shape[2]
    out_mass, out_mean, out_cov = np.zeros(G), np.zeros((G, B, d)), np.zeros((G, B, d, d))
    out_det, out_occ, out_coast = np.zeros(G), np.zeros(G), np.zeros(G)
    out_label = np.empty(G, dtype=label.dtype)
    first = np.empty(G + 1, dtype=np.int64)
    g = -1
    for i in range(len(order)):
        if start[i]:
            g += 1
            first[g] = i
        out_mass[g] += mass[order[i]]
    first[G] = len(order)
    for g in range(G):
        total = out_mass[g]
        out_label[g] = label[order[first[g]]]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    out_mean[g, b, r] += share * mean[k, b, r]
            out_det[g] += share * det[k]
            out_occ[g] += share * occ[k]
            out_coast[g] += share * coast[k]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    dev_r = mean[k, b, r] - out_mean[g, b, r]
                    for c in range(d):
                        dev_c = mean[k, b, c] - out_mean[g, b, c]
                        out_cov[g, b, r, c] += share * (cov[k, b, r, c] + dev_r * dev_c)
    return out_mass, out_mean, out_cov, out_det, out_occ, out_coast, out_label


@njit
def _predict_in_place(mean, cov, coasting, F, Q, F_coast, Q_coast):
    """m <- F m, P <- F P F' + h^2 Q per component and axis, with h its box height (the
    unit of the motion noises, `ConstantVelocity.predict`) and (F, Q) the coasting model's
    for a component whose object was missed."""
    d = mean.shape[2]
    m, FP = np.empty(d), np.empty((d, d))
    for k in range(len(mean)):
        A, Qk = (F_coast, Q_coast) if coasting[k] else (F, Q)
        unit2 = max(2.0 * mean[k, 1, 2], MIN_HEIGHT) ** 2
        for b in range(mean.shape[1]):
            for r in range(d):
                m[r] = 0.0
                for c in range(d):
                    m[r] += A[r, c] * mean[k, b, c]
                    FP[r, c] = 0.0
                    for i in range(d):
                        FP[r, c] += A[r, i] * cov[k, b, i, c]
            for r in range(d):
                mean[k, b, r] = m[r]
                for c in range(d):
                    total = 0.0
                    for i in range(d):
                        total += FP[r, i] * A[c, i]
                    cov[k, b, r, c] = total + unit2 * Qk[r, c]


@njit
def _object_moments(label, mass, mean, cov, L):
    """`GaussianMixturePMB.object_moments` of components with these labels: per slot the
    existence, the mass-weighted mean state and the centre's standard deviation."""
    r = _label_sums(label, mass, L)
    means = np.zeros((L,) + mean.shape[1:])
    var = np.zeros((L, 2))
    for k in range(len(label)):
        i = label[k]
        if i >= 0:
            share = mass[k] / max(r[i], 1e-300)
            for b in range(mean.shape[1]):
                for c in range(mean.shape[2]):
                    means[i, b, c] += share * mean[k, b, c]
    for k in range(len(label)):
        i = label[k]
        if i >= 0:
            share = mass[k] / max(r[i], 1e-300)
            for a in range(2):
                var[i, a] += share * (cov[k, a, 0, 0] + (mean[k, a, 0] - means[i, a, 0]) ** 2)
    return r, means, np.sqrt(var)


@njit
def _all_pairs(n, M, rows, A):
    """Every (component, detection) pair, component-major (pk, pj), and every (object row,
    detection) pair of the A object rows as a candidate edge: (row, column, candidate of each
    pair; the Poisson part's pairs point past the A M candidates, where nothing reads)."""
    pk, pj = np.empty(n * M, np.int64), np.empty(n * M, np.int64)
    cand_of_pair = np.empty(n * M, np.int64)
    for k in range(n):
        for j in range(M):
            pk[k * M + j] = k
            pj[k * M + j] = j
            cand_of_pair[k * M + j] = rows[k] * M + j
    cand_row, cand_col = np.empty(A * M, np.int64), np.empty(A * M, np.int64)
    for i in range(A):
        for j in range(M):
            cand_row[i * M + j] = i
            cand_col[i * M + j] = j
    return pk, pj, (cand_row, cand_col, cand_of_pair)


@njit
def _object_rows(label, used):
    """(the used slots, each component's object row): rows 0..A-1 are the used slots in
    order, row A the Poisson part."""
    slots = np.flatnonzero(used)
    A = len(slots)
    row_of_slot = np.full(len(used), A, dtype=np.int64)
    for a in range(A):
        row_of_slot[slots[a]] = a
    rows = np.empty(len(label), dtype=np.int64)
    for k in range(len(label)):
        rows[k] = row_of_slot[label[k]] if label[k] >= 0 else A
    return slots, rows


@njit
def _association_weights(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden, z,
                         score_term, seen_hidden, poisson_hit, rate, area, occludability,
                         e_row, e_col, L_edge, floor):
    """`_object_misses`, `_new_weights` and `_strong_edges` in one call: (miss_i, L_0j, and
    the strong edges: mask, rows, columns, L_ij)."""
    miss_obj = _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden)
    w_new = _new_weights(z, score_term, seen_hidden, poisson_hit, rate, area, occludability)
    strong, s_row, s_col, s_L = _strong_edges(e_row, e_col, L_edge, miss_obj, w_new, floor)
    return miss_obj, w_new, strong, s_row, s_col, s_L


@njit
def _object_misses(rows, A, mass, miss, det, occ, v, q, slots, slot_hidden):
    """miss_i = 1 - r_i + sum_{k in i} w_k miss_k of each object row (floored at 1e-300),
    and, in place, each slot's probability that occlusion caused a miss:
    sum w_k d_k o_k (1 - v_k + v_k q_k) / sum w_k miss_k."""
    r, miss_mass, hidden_mass = np.zeros(A + 1), np.zeros(A + 1), np.zeros(A + 1)
    for k in range(len(rows)):
        r[rows[k]] += mass[k]
        miss_mass[rows[k]] += mass[k] * miss[k]
        hidden_mass[rows[k]] += mass[k] * (det[k] * occ[k] * (1.0 - v[k] + v[k] * q[k]))
    slot_hidden[:] = 0.0
    miss_obj = np.empty(A)
    for a in range(A):
        slot_hidden[slots[a]] = hidden_mass[a] / max(miss_mass[a], 1e-300)
        miss_obj[a] = max(1.0 - r[a] + miss_mass[a], 1e-300)
    return miss_obj


@njit
def _new_weights(z, score_term, seen_hidden, poisson_hit, rate, area, occludability):
    """L_0j = kappa p_F(z_j) (1 - o h_j) + the Poisson part's hit weights, with kappa p_F =
    rate / (W H w h) / score^power (`config.TrackerConfig`), W H the image's `area` and
    score^-power given as `score_term`."""
    w_new = np.empty(len(z))
    for j in range(len(z)):
        size = max((z[j, 0, 1] - z[j, 0, 0]) * (z[j, 1, 1] - z[j, 1, 0]), 1.0)
        w_new[j] = (rate / (area * size) * score_term[j]
                    * (1.0 - occludability * seen_hidden[j]) + poisson_hit[j])
    return w_new


@njit
def _inherit(mean, cov, label, parent, j):
    """Each child's copy of its parent's mean, covariance and label, the hit children (j >= 0)
    and the detection each child of the Poisson part was born from (-1 for the others)."""
    K = len(parent)
    new_mean, new_cov = mean[parent], cov[parent]
    new_label = np.empty(K, dtype=label.dtype)
    newborn = np.full(K, -1, dtype=np.int64)
    hits = 0
    for c in range(K):
        new_label[c] = label[parent[c]]
        if j[c] >= 0:
            hits += 1
            if new_label[c] < 0:
                newborn[c] = j[c]
    h = np.empty(hits, dtype=np.int64)
    hits = 0
    for c in range(K):
        if j[c] >= 0:
            h[hits] = c
            hits += 1
    return new_mean, new_cov, new_label, h, newborn


@njit
def _clipped(x, low, high):
    """np.clip(x, low, high) as a new array (numpy's clip costs more than the loop here)."""
    out = np.empty_like(x)
    for i in range(len(x)):
        out[i] = min(max(x[i], low), high)
    return out


@njit
def _learnt_sizes(count, total, squares):
    """Mean half-size of the detections counted and its standard deviation (at least 1 px)."""
    mean = total / count
    return mean, np.sqrt(np.maximum(squares / count - mean ** 2, 1.0))


@njit
def _prior_sizes(stats, setting_mean, setting_std):
    """`GaussianMixturePMB._size_prior` from the running count, sum and sum of squares
    `stats` (3, 2) and the configured mean and std (empty: not set)."""
    learnt = stats[0, 0] >= 2
    learnt_mean, learnt_std = np.zeros(2), np.zeros(2)
    if learnt:
        learnt_mean, learnt_std = _learnt_sizes(stats[0], stats[1], stats[2])
    if len(setting_mean):
        mean = setting_mean.copy()
    else:
        mean = learnt_mean if learnt else np.array([30.0, 90.0])
    if len(setting_std):
        std = setting_std.copy()
    else:
        std = learnt_std if learnt else mean / 3.0
    return mean, np.maximum(std, 1.0)


@njit
def _append_births(n, mass, means, covs, det, occ, pool_mass, pool_mean, pool_cov, pool_det,
                   pool_occ, pool_label, pool_coast):
    """Append the birth components of positive mass to the pool after its first n (the
    Poisson part: label -1, never missed, d and o the births'); returns the new n."""
    for b in range(len(mass)):
        if mass[b] > 0:
            pool_mass[n], pool_mean[n], pool_cov[n] = mass[b], means[b], covs[b]
            pool_det[n], pool_occ[n], pool_label[n], pool_coast[n] = det, occ, -1, 0.0
            n += 1
    return n


@njit
def _strong_edges(row, col, L_edge, miss_obj, w_new, floor):
    """The edges with L_ij >= floor miss_i w_new_j (floor 0: every edge): (mask, their rows,
    columns and L_ij)."""
    strong = np.empty(len(L_edge), dtype=np.bool_)
    count = 0
    for e in range(len(L_edge)):
        strong[e] = floor == 0.0 or L_edge[e] >= floor * miss_obj[row[e]] * w_new[col[e]]
        count += strong[e]
    s_row, s_col, s_L = np.empty(count, np.int64), np.empty(count, np.int64), np.empty(count)
    i = 0
    for e in range(len(L_edge)):
        if strong[e]:
            s_row[i], s_col[i], s_L[i] = row[e], col[e], L_edge[e]
            i += 1
    return strong, s_row, s_col, s_L


@njit
def _children(mass, miss, rows, hit, pj, edge_of_pair, strong, p_hit, L_edge, p_new, w_new,
              p_miss, miss_obj):
    """The children's masses: the miss child of each component, w_k miss_k p_miss_i / miss_i
    (the Poisson part's: w_k miss_k), then the hit child of each pair, l_kj p_hit_ij / L_ij
    (Poisson: l_kj p_new_j / L_0j). p_hit is given on the `strong` edges, in order."""
    n, P, A = len(mass), len(hit), len(miss_obj)
    edge_factor = np.zeros(len(L_edge))
    s = 0
    for e in range(len(L_edge)):
        if strong[e]:
            edge_factor[e] = p_hit[s] / L_edge[e]
            s += 1
    out = np.empty(n + P)
    for k in range(n):
        factor = p_miss[rows[k]] / miss_obj[rows[k]] if rows[k] < A else 1.0
        out[k] = mass[k] * miss[k] * factor
    for p in range(P):
        e = edge_of_pair[p]
        out[n + p] = hit[p] * (edge_factor[e] if e >= 0 else p_new[pj[p]] / w_new[pj[p]])
    return out


@njit
def _child_parents(keep, n, pk, pj, M, children):
    """(kept children, their parent component, their detection (-1: miss), their mass) in
    the order of the parents, a miss child before its hit children."""
    K = len(keep)
    parent, j, key = np.empty(K, np.int64), np.empty(K, np.int64), np.empty(K, np.int64)
    for c in range(K):
        if keep[c] < n:
            parent[c], j[c] = keep[c], -1
        else:
            parent[c], j[c] = pk[keep[c] - n], pj[keep[c] - n]
        key[c] = parent[c] * (M + 1) + j[c] + 1
    order = np.argsort(key, kind="mergesort")
    keep, parent, j = keep[order], parent[order], j[order]
    return keep, parent, j, children[keep]


@njit
def _kept_children(children, selected, prune_mass, n, pk, pj, M, label, cap, L):
    """The children kept, as `_child_parents` gives them: those `selected` (None: those
    heavier than prune_mass), then, when cap > 0, at most cap per object (`_trim`, masses
    rescaled)."""
    keep = np.flatnonzero(children > prune_mass) if selected is None else selected
    keep, parent, j, mass = _child_parents(keep, n, pk, pj, M, children)
    if cap:
        trim = _trim(mass, label[parent], j, cap, L)
        if not trim.all():
            keep, parent, j, mass = keep[trim], parent[trim], j[trim], mass[trim]
    return keep, parent, j, mass


@njit
def _child_features(parent, j, det, occ, occ_all, established, v, q, miss, seen_hidden, coast,
                    dt):
    """d, o and the coasting time of each child (of component parent[c], by detection j[c],
    -1 for the miss child), by Bayes. Missed: P(D=1 | miss) = d o (1 - v + v q) / miss and
    P(O=1 | miss) = o (1 - d + d (1 - v + v q)) / miss. Hit by z_j: D = 1 and
    P(O=1 | hit) = o v (1 - h_j) / (1 - o + o v (1 - h_j)). `occ` is 0 for the components of
    objects not confirmed, whose o (`occ_all`) is carried unchanged."""
    C = len(parent)
    new_det, new_occ, new_coast = np.empty(C), np.empty(C), np.empty(C)
    for c in range(C):
        k = parent[c]
        d, o, vv, mm = det[k], occ[k], v[k], max(miss[k], 1e-300)
        hidden_if_occludable = 1.0 - vv + vv * q[k]
        if j[c] >= 0:
            new_det[c] = 1.0
            escaped = vv * (1.0 - seen_hidden[j[c]])
            seen_o = o * escaped / max(1.0 - o + o * escaped, 1e-300)
            new_occ[c] = seen_o if established[k] else occ_all[k]
            new_coast[c] = 0.0
        else:
            new_det[c] = d * o * hidden_if_occludable / mm
            missed_o = o * (1.0 - d + d * hidden_if_occludable) / mm
            new_occ[c] = missed_o if established[k] else occ_all[k]
            new_coast[c] = coast[k] + dt
    return new_det, new_occ, new_coast


@njit
def _hit_edges(pk, pj, log_hit, cand_of_pair, cand_row, cand_col, rows, A, M, mass, det,
               o_seen, v, seen_hidden, pd, use_seen, label, slot_class, classes):
    """The hit weights l_kj = w_k d_k (1 - o_k + o_k v_k (1 - h_j)) p(z_j | x_k) of the pairs
    that are possible (l_kj > e^LOG_FLOOR: below, a pair is impossible, and cutting there
    keeps slow subnormal numbers out; and an object never takes a detection of another
    class, `classes` empty: one class), summed into the association's weights: L_0j of the
    Poisson part, and L_ij on the candidate edges (object row, detection) that any pair
    reaches. Returns the kept pairs (pk, pj, l, edge of each pair, -1 for the Poisson part's),
    L_0j and the edges (row, column, L_ij)."""
    P = len(pk)
    keep = np.zeros(P, dtype=np.bool_)
    hit = np.empty(P)
    floor = math.exp(LOG_FLOOR)
    for e in range(P):
        k, j = pk[e], pj[e]
        if use_seen:
            o = o_seen[k]
            weight = mass[k] * det[k] * (1.0 - o + o * v[k] * (1.0 - seen_hidden[j]))
        else:
            weight = mass[k] * pd[k]
        value = math.exp(log_hit[e]) * max(weight, 1e-300)
        if value > floor and (len(classes) == 0 or label[k] < 0
                              or slot_class[label[k]] == classes[j]):
            keep[e] = True
            hit[e] = value
    poisson_hit = np.zeros(M)
    L_cand = np.zeros(len(cand_row))
    for e in range(P):
        if keep[e]:
            if rows[pk[e]] < A:
                L_cand[cand_of_pair[e]] += hit[e]
            else:
                poisson_hit[pj[e]] += hit[e]
    edge_of_cand = np.full(len(cand_row), -1, dtype=np.int64)
    E = 0
    for i in range(len(cand_row)):
        if L_cand[i] > 0:
            edge_of_cand[i] = E
            E += 1
    e_row, e_col, L_edge = (np.empty(E, dtype=np.int64), np.empty(E, dtype=np.int64),
                            np.empty(E))
    for i in range(len(cand_row)):
        if edge_of_cand[i] >= 0:
            e_row[edge_of_cand[i]] = cand_row[i]
            e_col[edge_of_cand[i]] = cand_col[i]
            L_edge[edge_of_cand[i]] = L_cand[i]
    K = 0
    for e in range(P):
        K += keep[e]
    out_k, out_j = np.empty(K, dtype=np.int64), np.empty(K, dtype=np.int64)
    out_hit, out_edge = np.empty(K), np.empty(K, dtype=np.int64)
    i = 0
    for e in range(P):
        if keep[e]:
            out_k[i], out_j[i], out_hit[i] = pk[e], pj[e], hit[e]
            out_edge[i] = edge_of_cand[cand_of_pair[e]] if rows[pk[e]] < A else -1
            i += 1
    return out_k, out_j, out_hit, out_edge, poisson_hit, e_row, e_col, L_edge


@njit
def _predict_pool(mass, mean, cov, det, occ, coast, coasting_after, F, Q, F_coast, Q_coast,
                  det_stationary, det_memory, occ_stationary, occ_memory, image_size,
                  survival_inside, exit_survival):
    """The prediction of every component, in place: motion (the coasting model for one
    unseen longer than `coasting_after` s), the Markov features d and o, survival."""
    _predict_in_place(mean, cov, coast > coasting_after, F, Q, F_coast, Q_coast)
    _relax_in_place(det, det_stationary, det_memory)
    _relax_in_place(occ, occ_stationary, occ_memory)
    _survive_in_place(mass, mean, image_size, survival_inside, exit_survival)


@njit
def _relax_in_place(p, stationary, memory):
    """`TwoStateMarkov.predict`: p <- stationary + memory (p - stationary)."""
    for k in range(len(p)):
        p[k] = stationary + memory * (p[k] - stationary)


@njit
def _survive_in_place(mass, mean, image_size, survival_inside, exit_survival):
    """Masses times the survival of a component whose centre is in the image (and whose box
    is at least 2 px wide and tall), else times `exit_survival`."""
    for k in range(len(mass)):
        inside = True
        for axis in range(2):
            centre = mean[k, axis, 0]
            if not (centre >= 0 and centre <= image_size[axis] and mean[k, axis, 2] >= 1.0):
                inside = False
        mass[k] *= survival_inside if inside else exit_survival


@njit
def _move_in_place(mean, cov, scale, shift, shift_variance):
    """x -> scale x + shift per axis: centres move, velocities and half-sizes scale,
    covariances scale by scale^2; the shift's own variance adds to every centre's."""
    for k in range(len(mean)):
        for axis in range(2):
            for r in range(mean.shape[2]):
                mean[k, axis, r] *= scale[axis]
                for c in range(mean.shape[2]):
                    cov[k, axis, r, c] *= scale[axis] ** 2
            mean[k, axis, 0] += shift[axis]
            cov[k, axis, 0, 0] += shift_variance[axis]


@njit
def _count_sizes(z, observed, stats):
    """Add the half-sizes of the detections with every edge measured to the running count,
    sum and sum of squares `stats` (3, 2)."""
    for j in range(len(z)):
        full = True
        for axis in range(2):
            full = full and observed[j, axis, 0] and observed[j, axis, 1]
        if full:
            for axis in range(2):
                half = 0.5 * (z[j, axis, 1] - z[j, axis, 0])
                stats[0, axis] += 1.0
                stats[1, axis] += half
                stats[2, axis] += half * half


@njit
def _cell_keys(mean, label, cell):
    """Per component (label, octave, the six cell indices): octave = round(log2 h) of its box
    height h, cell index = floor(state / (cell width 2^octave))."""
    n = len(mean)
    key = np.empty((n, 8), dtype=np.int64)
    for k in range(n):
        octave = np.round(np.log2(max(2.0 * mean[k, 1, 2], MIN_HEIGHT)))
        scale = np.exp2(octave)
        key[k, 0], key[k, 1] = label[k], np.int64(octave)
        for axis in range(2):
            for r in range(3):
                key[k, 2 + 3 * axis + r] = np.int64(
                    math.floor(mean[k, axis, r] / (cell[3 * axis + r] * scale)))
    return key


@njit
def _packed_order(key):
    """(fits, order, start): the rows of `key` sorted (stable) by packing each into one
    integer of mixed radix, and where a new key starts; fits is False when the packed
    integers would not fit in 62 bits."""
    n, width = key.shape
    low, span = key[0].copy(), np.ones(width, dtype=np.int64)
    high = key[0].copy()
    for k in range(n):
        for c in range(width):
            low[c] = min(low[c], key[k, c])
            high[c] = max(high[c], key[k, c])
    bits = 0.0
    for c in range(width):
        span[c] = high[c] - low[c] + 1
        bits += math.log2(float(span[c]))
    if not bits < 62:
        return False, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.bool_)
    packed = np.zeros(n, dtype=np.int64)
    for k in range(n):
        for c in range(width):
            packed[k] = packed[k] * span[c] + (key[k, c] - low[c])
    order = np.argsort(packed, kind="mergesort")
    start = np.ones(n, dtype=np.bool_)
    for i in range(1, n):
        start[i] = packed[order[i]] != packed[order[i - 1]]
    return True, order, start


@njit
def _trim(mass, label, measurement, cap, L):
    """Which children to keep when each Bernoulli keeps at most `cap` (its heaviest): the
    mask, the kept ones' masses scaled in place so that its existence is unchanged (only its
    density loses the tail). An object is a label (< L), or, born this step, the Poisson
    part's hit children of one measurement, keyed L + j; the Poisson part's miss children
    (key -1) are an intensity and are not trimmed."""
    n = len(mass)
    key = np.empty(n, dtype=np.int64)
    top = -1
    for c in range(n):
        key[c] = label[c] if label[c] >= 0 else (L + measurement[c] if measurement[c] >= 0
                                                 else -1)
        top = max(top, key[c])
    keep = np.ones(n, dtype=np.bool_)
    counts = np.zeros(top + 2, dtype=np.int64)
    over = False
    for c in range(n):
        if key[c] >= 0:
            counts[key[c]] += 1
            over = over or counts[key[c]] > cap
    if not over:
        return keep
    order = np.argsort(key, kind="mergesort")
    first = 0
    while first < n:
        last = first
        while last < n and key[order[last]] == key[order[first]]:
            last += 1
        if key[order[first]] >= 0 and last - first > cap:
            members = order[first:last]
            ranked = members[np.argsort(-mass[members], kind="mergesort")]
            total, kept_total = 0.0, 0.0
            for rank in range(len(ranked)):
                total += mass[ranked[rank]]
                if rank < cap:
                    kept_total += mass[ranked[rank]]
                else:
                    keep[ranked[rank]] = False
            scale = total / max(kept_total, 1e-300)
            for c in members:
                mass[c] *= scale
        first = last
    return keep
