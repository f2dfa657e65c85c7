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
Bayes after a miss with q > 0, falls after one with q = 0; between frames it relaxes to a
stationary value, the config's or, with an `occludability_learner`, the one learnt from how
often the detector still finds the objects the model calls hidden: a detector trained on
amodal boxes finds most of them, and their misses are then not occlusion;
`occtrack.models.occludability`). With nothing in front, m = 1 - d_k and the object is gone in
a few frames; when its cover walks away, likewise. Three rules keep this honest on real
detections:
- n-of-m confirmation: a Bernoulli is deleted unless it takes a detection (p_hit > 1/2) in
  `confirm_hits` of its first `confirm_window` tracked frames, and occlusion enters the miss
  and hit terms of confirmed objects only (o = 0 for the others): a newborn's broad density
  overlaps the detections around it, and a miss it could blame on them would keep a false
  track alive;
- a missed component's velocity relaxes to zero with `coast_velocity_time` (the motion
  model's Ornstein-Uhlenbeck velocity): people stop and turn behind others;
- `occtrack.tracker` reports an undetected object only while its confidence (existence times
  the probability that its spreading box still overlaps the person) is at least
  `report_min_confidence`; it is kept, unreported, for as long as m holds its existence, so
  its label survives;
- but only while the filter knows where it is: once the standard deviation of its predicted
  centre (its mixture's: each component is a hypothesis of where it is) exceeds
  `identity_spread` (1.2) times its half-size on an axis, the object is recycled into the
  Poisson part (`_recycle_unplaced`): its own box then holds its centre less than 60 % of the
  time, and a detection near it is often someone else's (on MOT17, a track that took a
  detection back after more than a second unseen, at that spread or more, was on the same
  person 23 times in 73: 13 in 57 on the moving MOT17-05, 10 in 16 on MOT17-11; below it 113
  in 180: `benchmarks/retakes.py`). Behind a wide occluder m stays near 1 while the
  prediction keeps spreading (its own motion, the camera's); taken by the old label, the next
  person to come out from behind the occluder would swap two identities. On a still camera the
  spread grows slowly and long occlusions are still bridged; on a moving one the camera's
  uncertainty ends them sooner (docs/occlusion-models.md, "On real detections").

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
could give). The box model's heavy tail (`models.edge_tail`, for tracked objects' components)
is cut at the same gate: beyond it lie pairs more than gate_sigmas / tail_scale (3) of the
tail's standard deviations apart, whose share of the detections is what the tail's weight is
not meant to explain. An association edge with L_ij < EDGE_FLOOR miss_i w_new_j cannot reach
p_hit_ij = EDGE_FLOOR (1e-9), so its hit children fall below `prune_mass` whatever loopy BP
says; leaving such edges out splits a crowd's graph into the clusters that really compete.
`gating = false` computes every pair and keeps every edge, to check that nothing moves
(benchmarks/bench_gating.py: no MOT17 metric moves).

One filter, several measurement models (DESIGN section 3; `interfaces`): the measurement
model gives p(z_j | x_k) on the gated pairs, the clutter density kappa p_F(z_j), the gates,
the update and the survival region; the birth model the Poisson part's new components. The
defaults are the box tracker's (`BoxMeasurement`, the image-edge births with the learnt size
prior); the lidar scan tracker passes `models.scan_segments`' (segments of a scan). An
occlusion model may also give the moments of each component's centre given that its
measurement was hidden (`OcclusionTerms.hidden_centre`): the miss child's density is then
moment-matched to p(x) (1 - d + d o v q(x)) / miss (`children._miss_branch_moments`), the
negative information of section V moving the density as well as the existence; the box
models give none, and the miss child keeps its parent's density.

Hand-written: no maintained library offers a labelled Gaussian-mixture PMB filter with a
pluggable miss term. The loops over components, pairs and cells and the bookkeeping between
them (the `_`-prefixed functions of this package's modules: `labels`, `pool`, `prediction`,
`weights`, `children`) are compiled (Cython: the package's one extension `_gmpmb`, its
source one `.pxi` per module): a frame is too small for numpy's per-call overhead to pay off.
Each reproduces the numpy expression it replaced to the last bit (tests/test_kernels.py,
tests/test_update_kernels.py); where numpy and the C library round differently (a power),
numpy computes it.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from occtrack.association import lbp_sparse
from occtrack.config import TrackerConfig
from occtrack.filters.gmpmb.children import (
    _child_features,
    _children,
    _inherit,
    _kept_children,
    _miss_branch_moments,
)
from occtrack.filters.gmpmb.interfaces import BirthModel, MeasurementModel
from occtrack.filters.gmpmb.labels import (
    _cap_in_place,
    _confirm_in_place,
    _count_in_place,
    _keep_labels,
    _object_moments,
    _open_slots,
    _recycle_unplaced,
)
from occtrack.filters.gmpmb.pool import (
    _append_births,
    _count_sizes,
    _merge_packed,
    _pool_cells,
    _prior_sizes,
    _sort_pool,
)
from occtrack.filters.gmpmb.prediction import _move_in_place, _predict_pool
from occtrack.filters.gmpmb.weights import (
    _all_pairs,
    _association_weights,
    _clipped,
    _hidden_evidence,
    _hit_edges,
    _miss_terms,
    _object_rows,
    _occludable,
)
from occtrack.models.aspect import AspectPrior
from occtrack.models.birth import EdgeBirths
from occtrack.models.box import BoxMeasurement
from occtrack.models.edge_tail import EdgeTail
from occtrack.models.markov import TwoStateMarkov
from occtrack.models.motion import ConstantVelocity
from occtrack.occlusion.base import OcclusionContext, OcclusionModel
from occtrack.spatial import DENSE_PAIRS, overlapping_pairs

N_BIRTH = 5
EDGE_FLOOR = 1e-9  # gating: association edges that cannot reach this p_hit are left out
INITIAL_POOL = 256  # components, when the pool grows with the scene
INITIAL_SLOTS = 32  # label slots, likewise
NO_CLASSES = np.zeros(0, dtype=np.int64)  # (the kernels' "one class")


class GaussianMixturePMB:
    """The filter's state and its step. `config` is already validated."""

    def __init__(self, config: TrackerConfig, occlusion: OcclusionModel,
                 measurement: MeasurementModel | None = None,
                 births: BirthModel | None = None):
        c = config
        self.config = c
        self.occlusion = occlusion
        if measurement is None:
            measurement = BoxMeasurement(c.image_size, c.edge_noise, c.border_margin,
                                         AspectPrior() if c.aspect_prior else None,
                                         c.clutter_rate, c.score_floor, c.clutter_score_power,
                                         EdgeTail(c.tail_weight, c.tail_scale,
                                                  learn=c.learn_tail_weight)
                                         if c.tail_weight > 0 else None,
                                         c.extrapolated_edges)
        self.measurement = measurement
        self.birth_model = births  # None: the box births (edges of the image, learnt sizes)
        self.detectability = TwoStateMarkov(c.stationary_detectability, c.detectability_ratio)
        # optional (means, classes) -> (n,) stationary P_D per component (a class of -1: the
        # Poisson part's), towards which each d_k relaxes in place of the one configured
        # value (`occtrack.models.detection_profile`, set by `tracker.ground`)
        self.detection_profile = None
        self.occludability = TwoStateMarkov(c.occludability, c.occludability_ratio)
        # optional: learns the stationary occludability from the hidden objects' hits and
        # misses (`occtrack.models.occludability`, set by the box tracker); None: the config's
        self.occludability_learner = None
        self._dt_models: dict[float, tuple] = {}
        # the half-size process noise the prediction uses (h / sqrt(s)): the config's, or what
        # the tracker learnt (`models.motion.SizeNoiseLearner`)
        self.size_noise = c.size_noise
        self._use_dt(c.dt)
        self.births = EdgeBirths(c.image_size, c.inward_speed, c.birth_speed_std)
        # the survival region: components whose centre leaves it take exit_survival
        self.image_size = np.ascontiguousarray(measurement.region_size, dtype=float)
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
        self.clutter_probability = np.zeros(0)  # of each detection of the last step
        self.observed = np.zeros((0, 2, 2), dtype=bool)  # and which of its edges were measured
        # running sums of detected half-sizes (count, sum, sum of squares) for the birth prior
        self._size_stats = np.zeros((3, 2))
        self._size_settings = tuple(np.zeros(0) if value is None else
                                    np.ascontiguousarray(value, dtype=float)
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
        observed = self.observed = self.measurement.observed(z)
        if self.birth_model is None:
            self._learn_sizes(z, observed)
        self.measurement.learn(z, observed)
        if camera is not None:
            self.move_image(*camera[:3])
            if len(camera) > 3:
                self.expand_image(*camera[3])
        self._predict()
        self._recycle_unplaced()
        self._add_births(z, observed)
        if classes is not None:  # (the kernels read int64)
            classes = np.ascontiguousarray(classes, dtype=np.int64)
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
        variance = np.zeros(2) if shift_variance is None else np.ascontiguousarray(
            shift_variance, dtype=float)
        _move_in_place(self.mean[:n], self.cov[:n], np.ascontiguousarray(scale, dtype=float),
                       np.ascontiguousarray(shift, dtype=float), variance)

    def expand_image(self, centre: np.ndarray, k: float) -> None:
        """Carry every component along a camera's forward motion: a point at x moves to
        centre + (1 + k h) (x - centre), h the component's box height standing for its
        inverse depth (`tracker.camera.estimate_expansion`); velocity and half-size scale by
        the same 1 + k h, the covariance by its square."""
        n = self.n
        if n == 0 or k == 0.0:
            return
        mean, cov = self.mean[:n], self.cov[:n]
        scale = np.maximum(1.0 + k * 2.0 * mean[:, 1, 2], 0.5)  # (a bad fit cannot fold a box)
        for axis in range(2):
            mean[:, axis, 0] = centre[axis] + scale * (mean[:, axis, 0] - centre[axis])
        mean[:, :, 1:] *= scale[:, None, None]
        cov *= (scale ** 2)[:, None, None, None]

    def _predict(self) -> None:
        n = self.n
        if n == 0:
            return
        Q, coast_Q = self.motion.Q, self.coast_motion.Q
        if self.size_noise != self.config.size_noise:
            Q, coast_Q = Q.copy(), coast_Q.copy()
            Q[2, 2] = coast_Q[2, 2] = self.size_noise**2 * self.dt
        _predict_pool(self.mass[:n], self.mean[:n], self.cov[:n], self.det[:n], self.occ[:n],
                      self.coast[:n], 0.5 * self.dt, self.motion.F, Q, self.coast_motion.F,
                      coast_Q,
                      self.detectability.stationary, self._memories[0],
                      self.occludability.stationary, self._memories[1], self.image_size,
                      self.survival_inside, self.config.exit_survival)
        if self.detection_profile is not None:  # a stationary P_D per component
            label = self.label[:n]
            classes = np.where(label >= 0, self.slot_class[np.maximum(label, 0)], -1)
            stationary = self.detection_profile(self.mean[:n], classes)
            # (the kernel relaxed d towards the one stationary s; towards s_k instead:)
            self.det[:n] = np.clip(self.det[:n] + (1.0 - self._memories[0])
                                   * (stationary - self.detectability.stationary), 0.0, 1.0)
        in_view = getattr(self.measurement, "in_view", None)
        if in_view is not None:  # (optional: a sensor whose view is not the whole region)
            self._leave_view(in_view)

    def _leave_view(self, in_view) -> None:
        """Components inside the region but outside the sensor's view (the measurement
        model's `in_view`) survive as those outside the region do: times exit_survival, not
        the survival inside."""
        n = self.n
        mean = self.mean[:n]
        inside = np.all((mean[:, :, 0] >= 0) & (mean[:, :, 0] <= self.image_size)
                        & (mean[:, :, 2] >= 1.0), axis=1)
        gone = inside & ~in_view(mean)
        if gone.any():
            self.mass[:n][gone] *= self.config.exit_survival / self.survival_inside

    def _recycle_unplaced(self) -> None:
        """Recycle into the Poisson part every object undetected at its last update whose
        predicted centre's standard deviation exceeds `identity_spread` half-sizes (module
        docstring): its mass stays, as undetected intensity, and a detection there starts a
        new identity."""
        n, spread = self.n, self.config.identity_spread
        if n and math.isfinite(spread):
            _recycle_unplaced(self.label[:n], self.mass[:n], self.mean[:n], self.cov[:n],
                              self.slot_used, self.slot_coast, spread)

    def _size_prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Half-size (mean, std) of a newborn, px: the configured values, else those of the
        detections seen so far, else (30, 90) and a third of it."""
        return _prior_sizes(self._size_stats, *self._size_settings)

    def _learn_sizes(self, z: np.ndarray, observed: np.ndarray) -> None:
        _count_sizes(z, observed, self._size_stats)

    def _add_births(self, z=None, observed=None) -> None:
        c = self.config
        if self.birth_model is not None:
            # (a plugin's arrays: the kernels read C-contiguous float64)
            mass, means, covs = (np.ascontiguousarray(a, dtype=float) for a in
                                 self.birth_model.components(z, observed, self.dt, self.steps))
        else:
            spread = c.spread_birth_rate * self.dt + (c.initial_objects if self.steps == 0
                                                      else 0.0)
            size_mean, size_std = self._size_prior()
            mass, means, covs = self.births.components(c.edge_birth_rate * self.dt, spread,
                                                       size_mean, size_std,
                                                       2.0 * size_mean[1])
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
        o = self.occludability.stationary  # (the config's, or the learnt value)
        established, occ, o_seen, r_slot, within = _occludable(
            label, mass, self.occ[:n], self.slot_used, self.slot_hits, c.confirm_hits, o)
        ctx = OcclusionContext(means=mean, covs=cov, weights=within, owner=label,
                               existence=r_slot, measurements=z,
                               measurement_model=self.measurement)
        terms = self.occlusion.terms(ctx)
        # (the occlusion model's and the measurement model's arrays are a plugin's: the
        # kernels read C-contiguous float64)
        v, q, pd, miss = _miss_terms(det, occ, np.ascontiguousarray(terms.visible, dtype=float),
                                     np.ascontiguousarray(terms.hidden, dtype=float))

        seen_hidden = np.zeros(M) if terms.seen_hidden is None else _clipped(
            np.ascontiguousarray(terms.seen_hidden, dtype=float), 0.0, 1.0)
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

        clutter = np.ascontiguousarray(self.measurement.clutter_density(z, observed, scores),
                                       dtype=float)
        # an edge with L_ij < EDGE_FLOOR miss_i w_new_j has p_hit_ij below EDGE_FLOOR (nu_ij
        # <= 1 / w_new_j), so its hit children are below prune_mass whatever BP says; leaving
        # such edges out (gating) splits a crowd's graph into the clusters that really compete
        miss_obj, w_new, strong, s_row, s_col, s_L = _association_weights(
            rows, A, mass, miss, det, occ, v, q, slots, self.slot_hidden, clutter,
            seen_hidden, poisson_hit, o, e_row, e_col, L_edge,
            EDGE_FLOOR if c.gating else 0.0)
        marg = lbp_sparse(s_row, s_col, s_L, miss_obj, w_new, tol=c.lbp_tolerance,
                          max_iter=c.lbp_max_iterations)
        self.iterations = marg.iterations
        # pi_j, the probability that detection j is clutter: new, and of its new weight the
        # clutter's share (what a learnt detector model counts: models.score_model)
        share = clutter * (1.0 - o * seen_hidden)
        self.clutter_probability = np.divide(marg.p_new * share, w_new,
                                             out=np.zeros(M), where=w_new > 0)
        self._count_detections(slots, s_row, s_col, marg.p_hit)
        if self.occludability_learner is not None and self.detectability.stationary > 0:
            self._learn_occludability(label, within, v, q, r_slot)
        learn = getattr(self.measurement, "learn_association", None)
        if learn is not None:  # (what a measurement model learns from the detections taken)
            learn(label, self.slot_detection, self.confirmed(), self.dt)

        # children: one miss child per component, then one hit child per pair
        children = _children(mass, miss, rows, hit, pj, edge_of_pair, strong, marg.p_hit,
                             L_edge, marg.p_new, w_new, marg.p_miss, miss_obj)
        keep, parent, j, new_mass = _kept_children(
            children, self._select(children) if c.capacity else None, c.prune_mass, n, pk, pj,
            M, label, c.max_components_per_object, len(self.slot_used))
        new_mean, new_cov, new_label, h, newborn = _inherit(mean, cov, label, parent, j)
        if terms.hidden_centre is not None:  # the density takes the miss branch too
            _miss_branch_moments(new_mean, new_cov, parent, j, det, occ, v, q, miss,
                                 terms.hidden_centre, terms.hidden_variance)
        new_det, new_occ, new_coast = _child_features(
            parent, j, det, occ, self.occ[:n], established, v, q, miss, seen_hidden, coast,
            self.dt)
        if len(h):
            self.measurement.update_rows(new_mean, new_cov, h, z, observed, j[h])

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
        tracked = getattr(self.measurement, "tracked_components", None)
        if tracked is not None:  # (optional: `interfaces`)
            tracked(rows < A)
        if not c.gating or n * M <= DENSE_PAIRS:
            pk, pj, cand = _all_pairs(n, M, rows, A)
            loglik = self.measurement.loglik_pairs(mean, zhat, S, z, observed, pk, pj)
            return pk, pj, np.ascontiguousarray(loglik, dtype=float), cand
        gates = self.measurement.gates(zhat, S, c.gate_sigmas)
        first = np.ones(n, dtype=bool)
        first[1:] = (rows[1:] != rows[:-1]) | (rows[1:] == A)
        start = np.flatnonzero(first)
        size = np.diff(np.append(start, n))
        unit_gates = np.stack([np.minimum.reduceat(gates[..., 0], start),
                               np.maximum.reduceat(gates[..., 1], start)], axis=-1)
        ui, uj = overlapping_pairs(unit_gates, self.measurement.gate_boxes(z, observed))
        uj = np.ascontiguousarray(uj)  # (np.nonzero's columns are strided; a kernel reads it)
        count = size[ui]
        total = int(count.sum())
        cand_of_pair = np.repeat(np.arange(len(ui)), count)
        pk = np.repeat(start[ui] - (np.cumsum(count) - count), count) + np.arange(total)
        pj = uj[cand_of_pair]
        loglik = np.ascontiguousarray(
            self.measurement.loglik_pairs(mean, zhat, S, z, observed, pk, pj), dtype=float)
        return pk, pj, loglik, (rows[start[ui]], uj, cand_of_pair)

    def _count_detections(self, slots: np.ndarray, row: np.ndarray, col: np.ndarray,
                          p_hit: np.ndarray) -> None:
        """Per-slot bookkeeping of this step's association: an object (row of `slots`) took
        detection j when p_hit_ij > 1/2 (at most one j can); p_hit is given on the pairs
        (row, col)."""
        _count_in_place(self.slot_detection, self.slot_age, self.slot_hits, self.slot_coast,
                        self.slot_used, slots, row, col, p_hit, self.dt)

    def _learn_occludability(self, label: np.ndarray, within: np.ndarray, v: np.ndarray,
                             q: np.ndarray, r_slot: np.ndarray) -> None:
        """Feed this step's hidden confirmed objects, and whether each took a detection, to
        the occludability learner, and relax every o_k towards its new value from the next
        prediction on (`occtrack.models.occludability`)."""
        c, learner = self.config, self.occludability_learner
        evidence, weight = _hidden_evidence(
            label, within, v, q, r_slot, self.slot_used, self.slot_hits, c.confirm_hits,
            self.slot_detection, self.detectability.stationary, learner.hidden)
        learner.add(evidence, weight, self.dt)
        self.occludability = TwoStateMarkov(learner.value, c.occludability_ratio)

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
