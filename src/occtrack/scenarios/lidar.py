"""Simulated lidar beams (paper section V): an object's return, clutter returns, the nearest
reported; and the Monte Carlo check of the derived beam likelihood."""

from __future__ import annotations

import numpy as np

from occtrack.models.beam import BeamModel


def simulate_beams(x: float | None, model: BeamModel, n: int,
                   rng: np.random.Generator) -> np.ndarray:
    """n independent readings of a beam with an object at x (None: no object): the nearest of
    the object's return and the clutter returns, or max_range."""
    best = np.full(n, model.max_range)
    if x is not None:
        hit = rng.random(n) < model.p_d
        ret = rng.normal(x, model.sigma, n)
        ok = hit & (ret >= 0) & (ret < model.max_range)
        best[ok] = ret[ok]
    counts = rng.poisson(model.clutter_rate, n)
    if counts.any():
        owner = np.repeat(np.arange(n), counts)
        np.minimum.at(best, owner, rng.uniform(0, model.max_range, counts.sum()))
    return best


def empirical_ratio(model: BeamModel, x: float, edges: np.ndarray, n: int,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Histogram ratio of simulated beams with and without the object at x, per bin of
    `edges`, and its standard error: the Monte Carlo check of `likelihood_ratio`."""
    with_obj = np.histogram(simulate_beams(x, model, n, rng), edges)[0]
    without = np.histogram(simulate_beams(None, model, n, rng), edges)[0]
    ratio = with_obj / np.maximum(without, 1)
    se = ratio * np.sqrt(1 / np.maximum(with_obj, 1) + 1 / np.maximum(without, 1))
    return ratio, se
