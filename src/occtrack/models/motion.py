"""Nearly constant velocity motion, one block per image axis.

Each axis carries (centre, velocity, half-size); centre moves with the velocity, half-size drifts
as a random walk, and velocity drifts as a random walk that, with a time constant tau, relaxes
towards zero (an Ornstein-Uhlenbeck velocity: a walker keeps its pace for a while, then turns
or stops, so a prediction made without measurements travels at most about v tau). Over a step
of dt seconds, with a = exp(-dt / tau),

    F = [[1, tau (1 - a), 0], [0, a, 0], [0, 0, 1]]
    Q = diag(q_c^2 dt, q_v^2 tau (1 - a^2) / 2, q_s^2 dt)

with q the noise of each feature per square-root second, so that the same settings describe
tracking at any frame rate (the paper tracked MOT17-04 at 15 Hz). The noises may be given in
units of a per-component length (the box tracker's box height h_k), Q_k = h_k^2 Q: a person
near the camera moves and changes size by more pixels than one far away. tau = inf (the default) is
the constant-velocity model, F = [[1, dt, 0], [0, 1, 0], [0, 0, 1]], Q = diag(q^2) dt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from occtrack.densities import gaussian
from occtrack.models._models import _median_of_squares  # (np.median(np.square(x)), exact)


@dataclass(frozen=True)
class ConstantVelocity:
    dt: float
    position_noise: float
    velocity_noise: float
    size_noise: float
    velocity_time: float = math.inf  # tau, seconds; inf: constant velocity

    def __post_init__(self) -> None:
        if not self.velocity_time > 0:
            raise ValueError(f"velocity_time must be positive, not {self.velocity_time}")

    @cached_property
    def F(self) -> np.ndarray:
        tau = self.velocity_time
        travel = self.dt if math.isinf(tau) else -tau * math.expm1(-self.dt / tau)
        return np.array([[1.0, travel, 0.0], [0.0, math.exp(-self.dt / tau), 0.0],
                         [0.0, 0.0, 1.0]])

    @cached_property
    def Q(self) -> np.ndarray:
        tau = self.velocity_time
        spread = self.dt if math.isinf(tau) else -tau * math.expm1(-2.0 * self.dt / tau) / 2.0
        return np.diag([self.position_noise**2 * self.dt, self.velocity_noise**2 * spread,
                        self.size_noise**2 * self.dt])

    def predict(self, means: np.ndarray, covs: np.ndarray,
                scale: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Predict every component; `scale` (K,), if given, is each one's unit of length."""
        Q = self.Q if scale is None else scale[:, None, None, None] ** 2 * self.Q
        return gaussian.predict(means, covs, self.F, Q)


class SizeNoiseLearner:
    """The half-size process noise learnt from the detections the tracks take (method of
    moments over two lags, as an Allan variance separates drift from noise).

    An object's measured half-size s (in units of its box height h) is its true half-size,
    a random walk of noise q per square-root second, plus detection noise. Between two
    detections k tracked frames apart (dt seconds a frame) the relative change
    d_k = (s_{t+k} - s_t) / h has

        E[d_k^2] = q^2 k dt + 2 sigma^2,

    sigma the noise of one measured half-size, so two lags give q without knowing sigma:
    q^2 = (V_L - V_1) / ((L - 1) dt). A car the camera drives up to grows by tens of percent
    a second; a pedestrian beside a camera hardly changes size. The variances are taken
    robustly (median of d^2 / 0.4549, the median of a chi-square with one degree of freedom;
    a detection that is another object's, or cut by an occluder, is an outlier) from the
    most recent `memory` differences of each lag, so the estimate follows the scene and its
    memory is bounded. The prior q0 is a floor, and until `prior_weight` differences are in
    the estimate leans on it: q^2 = q0^2 + n / (n0 + n) max(q_hat^2 - q0^2, 0). A floor,
    because one q stands for every object and the median follows the majority: beside a
    still camera most people keep their size while the few who walk towards it grow (the
    prior was calibrated on such scenes). Only edges not on the image border count.

    Hand-written: this is a few lines of moment estimation on the tracker's own bookkeeping,
    which no tracking library exposes.
    """

    CHI2_MEDIAN = 0.45493642311957283  # median of chi-square(1)

    def __init__(self, prior: float, lag: int = 3, memory: int = 2000,
                 prior_weight: int = 200):
        if lag < 2:
            raise ValueError(f"lag must be at least 2, not {lag}")
        self.prior, self.lag, self.memory, self.prior_weight = prior, lag, memory, prior_weight
        self._diffs = {1: np.zeros(memory), lag: np.zeros(memory)}
        self._count = {1: 0, lag: 0}

    def add(self, lag: int, diffs: np.ndarray) -> None:
        """Relative half-size changes (in box heights) over `lag` tracked frames."""
        diffs = np.asarray(diffs, dtype=float).ravel()
        diffs = diffs[np.isfinite(diffs)][-self.memory:]
        n = len(diffs)
        if not n:
            return
        start = self._count[lag] % self.memory
        ring = self._diffs[lag]
        first = min(n, self.memory - start)
        ring[start:start + first] = diffs[:first]
        ring[:n - first] = diffs[first:]
        self._count[lag] += n

    @property
    def full(self) -> bool:
        """Whether both lags' buffers hold `memory` differences."""
        return min(self._count.values()) >= self.memory

    def noise(self, dt: float) -> float:
        """q in box heights per square-root second: the prior, raised by the estimate."""
        n = min(self._count[1], self._count[self.lag], self.memory)
        if n < 2:
            return self.prior
        v1, vl = (_median_of_squares(self._diffs[k][:min(self._count[k], self.memory)])
                  / self.CHI2_MEDIAN for k in (1, self.lag))
        q2 = max(vl - v1, 0.0) / ((self.lag - 1) * dt)
        excess = max(q2 - self.prior**2, 0.0)
        return math.sqrt(self.prior**2 + n / (self.prior_weight + n) * excess)
