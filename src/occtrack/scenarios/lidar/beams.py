"""Simulated lidar beams (paper section V): an object's return, clutter returns, the nearest
reported; and the Monte Carlo check of the derived beam likelihood."""

from __future__ import annotations

import numpy as np

from occtrack.models.beam import BeamModel, likelihood_ratio


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


def probe_bins(x: float, sigma: float) -> tuple[np.ndarray, float, np.ndarray]:
    """Where the derived ratio is checked for an object at x: five returns z (halfway to it,
    3 sigma before, on it, 2 and 6 sigma past it: every regime of section V), the half-width
    of the bin about each (sigma / 4) and the bins' edges (a bin about each z, the gaps
    between them bins too)."""
    probes = np.array([x / 2, x - 3 * sigma, x, x + 2 * sigma, x + 6 * sigma])
    half = sigma / 4
    return probes, half, np.sort(np.concatenate([probes - half, probes + half]))


def binned_ratio(probes: np.ndarray, half: float, x: float, model: BeamModel) -> np.ndarray:
    """The derived L(z | x) averaged over each probe's bin (201 points), as a histogram of
    simulated returns measures it."""
    return np.array([np.mean(likelihood_ratio(np.linspace(z - half, z + half, 201), x, model))
                     for z in probes])


def empirical_ratio(model: BeamModel, x: float, edges: np.ndarray, n: int,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Histogram ratio of simulated beams with and without the object at x, per bin of
    `edges`, and its standard error: the Monte Carlo check of `likelihood_ratio`."""
    with_obj = np.histogram(simulate_beams(x, model, n, rng), edges)[0]
    without = np.histogram(simulate_beams(None, model, n, rng), edges)[0]
    ratio = with_obj / np.maximum(without, 1)
    se = ratio * np.sqrt(1 / np.maximum(with_obj, 1) + 1 / np.maximum(without, 1))
    return ratio, se
