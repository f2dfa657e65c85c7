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
