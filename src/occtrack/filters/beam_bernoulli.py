"""The Bernoulli update of one object's range particles by one lidar beam, with the separable
likelihood of paper section V (`occtrack.models.beam`): exact, because the beam's clutter terms
cancel between "object" and "no object"."""

from __future__ import annotations

import numpy as np

from occtrack.models.beam import BeamModel, likelihood_ratio


def update_bernoulli(r: float, particles: np.ndarray, weights: np.ndarray, z: float,
                     model: BeamModel) -> tuple[float, np.ndarray]:
    """Exact Bernoulli update of an object's range particles by one beam: existence
    r' = r E[L] / (1 - r + r E[L]) and weights w' proportional to w L."""
    lik = likelihood_ratio(z, particles, model)
    weighted = np.asarray(weights, float) * lik
    mean_lik = weighted.sum() / np.sum(weights)
    r_new = r * mean_lik / (1.0 - r + r * mean_lik)
    return float(r_new), weighted / weighted.sum()
