"""Constant-velocity motion, one block per image axis.

Each axis carries (centre, velocity, half-size); centre moves with the velocity, velocity and
half-size drift as random walks. Over a step of dt seconds

    F = [[1, dt, 0], [0, 1, 0], [0, 0, 1]]      Q = diag(q_c^2, q_v^2, q_s^2) dt

with q the noise of each feature per square-root second, so that the same settings describe
tracking at any frame rate (the paper tracked MOT17-04 at 15 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.densities import gaussian


@dataclass(frozen=True)
class ConstantVelocity:
    dt: float
    position_noise: float
    velocity_noise: float
    size_noise: float

    @property
    def F(self) -> np.ndarray:
        return np.array([[1.0, self.dt, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])

    @property
    def Q(self) -> np.ndarray:
        q = np.array([self.position_noise, self.velocity_noise, self.size_noise])
        return np.diag(q**2 * self.dt)

    def predict(self, means: np.ndarray, covs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return gaussian.predict(means, covs, self.F, self.Q)
