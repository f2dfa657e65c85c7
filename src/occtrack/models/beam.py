"""The scanning range sensor's beam model and its separable likelihood (paper section V).

A scanning lidar gives one range z per beam. With deterministic restricted measurement-wise
occlusion, the return at z hides every return farther along its beam; clutter returns are
Poisson with `clutter_rate` per beam, uniform over [0, max_range]; an object at range x on the
beam returns N(x, sigma^2) with probability P_D. The sensor reports the nearest return, or
max_range when there is none.

For one object at x, the measurement-wise terms of paper eq. "new_individual_MM" are

    hit   P_D N(z; x, sigma^2)
    miss  1 - P_D + P_D q(x),   q(x) = P(its return lies beyond z) = 1 - Phi((z - x) / sigma)

and the clutter terms shared by "object" and "no object" cancel, so the beam's likelihood
ratio of an object at x against no object there is

    L(z | x) = P_D N(z; x, sigma^2) / kappa + 1 - P_D Phi((z - x) / sigma),

with kappa = clutter_rate / max_range, and L = 1 - P_D for a beam with no return. Its shape is
the hand-made occlusion-tolerant lidar likelihood of Thrun et al.: high where z meets the
object (a hit), about 1 - P_D just beyond it (the beam passed where the object would be:
negative information) and about 1 well short of it (the object is hidden: no information). The
three regimes of the paper's simplification are `regime`.

The Bernoulli update with it is `occtrack.filters.beam_bernoulli`; simulated beams are
`occtrack.scenarios.lidar`. Written here because it is the paper's derivation itself; scipy
supplies the normal density and CDF.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

SQRT_2PI = np.sqrt(2 * np.pi)


@dataclass(frozen=True)
class BeamModel:
    """p_d: P_D of an object on the beam; sigma: range noise std (m); clutter_rate: expected
    clutter returns per beam; max_range: the range reported when nothing returns (m)."""

    p_d: float = 0.9
    sigma: float = 0.3
    clutter_rate: float = 0.2
    max_range: float = 50.0

    def __post_init__(self) -> None:
        if not 0 <= self.p_d <= 1:
            raise ValueError("p_d must lie in [0, 1]")
        if self.sigma <= 0 or self.clutter_rate <= 0 or self.max_range <= 0:
            raise ValueError("sigma, clutter_rate and max_range must be positive")

    @property
    def kappa(self) -> float:
        """Clutter intensity per metre of range."""
        return self.clutter_rate / self.max_range


def hidden_probability(z: np.ndarray, x: np.ndarray, model: BeamModel) -> np.ndarray:
    """q: probability that an object at x returns beyond z, where the return at z hides it.
    Zero for a beam with no return (nothing hides anything)."""
    z, x = np.broadcast_arrays(np.asarray(z, float), np.asarray(x, float))
    q = 1.0 - ndtr((z - x) / model.sigma)
    return np.where(z >= model.max_range, 0.0, q)


def likelihood_ratio(z: np.ndarray, x: np.ndarray, model: BeamModel) -> np.ndarray:
    """L(z | x): the beam's likelihood with an object at range x over that without it."""
    z, x = np.broadcast_arrays(np.asarray(z, float), np.asarray(x, float))
    hit = model.p_d * np.exp(-0.5 * ((z - x) / model.sigma) ** 2) / (SQRT_2PI * model.sigma)
    miss = 1.0 - model.p_d + model.p_d * hidden_probability(z, x, model)
    return np.where(z >= model.max_range, 1.0 - model.p_d, hit / model.kappa + miss)


def gaussian_likelihood_ratio(z: float, mean: np.ndarray, var: np.ndarray,
                              model: BeamModel) -> np.ndarray:
    """E[L(z | x)] for x ~ N(mean, var), in closed form (Kalman-friendly)."""
    mean, var = np.asarray(mean, float), np.asarray(var, float)
    if z >= model.max_range:
        return np.full(np.broadcast(mean, var).shape, 1.0 - model.p_d)
    s = np.sqrt(var + model.sigma**2)
    hit = model.p_d * np.exp(-0.5 * ((z - mean) / s) ** 2) / (SQRT_2PI * s)
    return hit / model.kappa + 1.0 - model.p_d * ndtr((z - mean) / s)


def regime(z_hat: np.ndarray, z: float, model: BeamModel, width: float = 3.0) -> np.ndarray:
    """The paper's simplification for well-separated objects, by predicted range z_hat:
    "hit" (z_hat close to z: normal update), "passed" (z_hat nearer than z: the miss branch)
    or "hidden" (z_hat beyond z: no information)."""
    z_hat = np.asarray(z_hat, float)
    near = np.abs(z_hat - z) <= width * model.sigma
    return np.where(near, "hit", np.where(z_hat < z, "passed", "hidden"))
