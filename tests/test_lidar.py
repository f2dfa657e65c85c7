"""The separable lidar likelihood (paper section V) against simulated beams and quadrature."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.filters.beam_bernoulli import update_bernoulli
from occtrack.models.beam import (
    BeamModel,
    gaussian_likelihood_ratio,
    hidden_probability,
    likelihood_ratio,
    regime,
)
from occtrack.scenarios.lidar import simulate_beams

MODEL = BeamModel(p_d=0.8, sigma=0.5, clutter_rate=0.5, max_range=40.0)


def test_density_of_the_nearest_return_matches_simulation():
    """With an object at x the reported range has density L(z | x) kappa e^(-kappa z)."""
    x, n = 15.0, 300_000
    z = simulate_beams(x, MODEL, n, np.random.default_rng(7))
    edges = np.linspace(0, 30, 61)
    counts = np.histogram(z, edges)[0]
    grid = np.linspace(0, 30, 60 * 200 + 1)
    density = likelihood_ratio(grid, x, MODEL) * MODEL.kappa * np.exp(-MODEL.kappa * grid)
    cum = np.concatenate([[0], np.cumsum((density[1:] + density[:-1]) / 2 * np.diff(grid))])
    expected = n * np.diff(cum[::200])
    se = np.sqrt(expected * (1 - expected / n))
    assert np.all(np.abs(counts - expected) < 4.5 * se + 1)
    no_return = np.mean(z >= MODEL.max_range)
    p = (1 - MODEL.p_d) * np.exp(-MODEL.clutter_rate)
    assert abs(no_return - p) < 4 * np.sqrt(p * (1 - p) / n)


def test_three_regimes():
    x = 20.0
    assert likelihood_ratio(5.0, x, MODEL) == pytest.approx(1.0, abs=1e-9)
    assert likelihood_ratio(x + 8 * MODEL.sigma, x, MODEL) == pytest.approx(1 - MODEL.p_d)
    assert likelihood_ratio(MODEL.max_range, x, MODEL) == pytest.approx(1 - MODEL.p_d)
    assert likelihood_ratio(x, x, MODEL) > 10
    assert regime([10.0, 20.1, 30.0], 20.0, MODEL).tolist() == ["passed", "hit", "hidden"]


@pytest.mark.parametrize("z", [8.0, 11.3, 12.0, 14.0, MODEL.max_range])
def test_gaussian_closed_form_equals_quadrature(z):
    mean, var = 12.0, 0.7**2
    x = np.linspace(mean - 10, mean + 10, 40001)
    pdf = np.exp(-0.5 * (x - mean) ** 2 / var) / np.sqrt(2 * np.pi * var)
    f = likelihood_ratio(z, x, MODEL) * pdf
    numeric = np.sum((f[1:] + f[:-1]) / 2 * np.diff(x))
    assert gaussian_likelihood_ratio(z, mean, var, MODEL) == pytest.approx(numeric, rel=1e-6)


def test_bernoulli_update_by_regime():
    rng = np.random.default_rng(0)
    particles = rng.normal(20.0, 0.3, 5000)
    weights = np.full(5000, 1 / 5000)
    r = 0.6
    passed, _ = update_bernoulli(r, particles, weights, 25.0, MODEL)
    hidden, w_hidden = update_bernoulli(r, particles, weights, 10.0, MODEL)
    hit, w_hit = update_bernoulli(r, particles, weights, 20.2, MODEL)
    assert passed == pytest.approx(r * 0.2 / (1 - r + r * 0.2), rel=1e-6)
    assert hidden == pytest.approx(r, abs=1e-9)
    np.testing.assert_allclose(w_hidden, weights, atol=1e-12)
    g = float(gaussian_likelihood_ratio(20.2, 20.0, 0.3**2, MODEL))
    assert hit == pytest.approx(r * g / (1 - r + r * g), rel=0.01)
    assert hit > r
    assert np.sum(w_hit * particles) > np.sum(weights * particles)


def test_cli_prints_derived_and_simulated(capsys):
    assert main(["lidar", "--samples", "20000"]) == 0
    out = capsys.readouterr().out
    assert "hidden" in out and "passed" in out and "no return: L = 1 - P_D = 0.100" in out


def test_cli_rejects_bad_settings(capsys):
    assert main(["lidar", "--p-d", "1.5"]) == 1
    assert "p_d must lie in [0, 1]" in capsys.readouterr().err
    assert main(["lidar", "--range", "80"]) == 1
    assert "--range must lie inside" in capsys.readouterr().err


def test_a_beam_with_no_return_says_only_that_nothing_was_detected():
    """z = max_range (nothing returned): nothing hides anything (q = 0) and the ratio is the
    miss probability 1 - p_d wherever the object is, even right at max_range; the Gaussian
    form has the broadcast shape of mean and variance."""
    far = MODEL.max_range
    x = np.array([far - 0.1, far, far + 1.0])
    assert hidden_probability(far, x, MODEL).tolist() == [0.0, 0.0, 0.0]
    assert likelihood_ratio(far, x, MODEL).tolist() == [1 - MODEL.p_d] * 3
    assert hidden_probability(far - 1e-9, far + 1.0, MODEL) > 0.9
    got = gaussian_likelihood_ratio(far, np.full((3, 1), far), np.full(4, 0.25), MODEL)
    assert got.shape == (3, 4) and (got == 1 - MODEL.p_d).all()
    assert gaussian_likelihood_ratio(far, far, np.full(2, 0.25), MODEL).shape == (2,)
    assert gaussian_likelihood_ratio(far - 1e-9, far, 0.25, MODEL) > 1


def test_regime_boundary_is_a_hit():
    """|z_hat - z| exactly width sigma is still "hit" (0.5 and 1.5 are exact in binary)."""
    assert regime([8.5, 11.5, 8.4, 11.6], 10.0, MODEL).tolist() == [
        "hit", "hit", "passed", "hidden"]


@pytest.mark.parametrize("settings,message", [
    (dict(p_d=-0.1), r"^p_d must lie in \[0, 1\]$"),
    (dict(p_d=1.1), r"^p_d must lie in \[0, 1\]$"),
    (dict(sigma=0.0), "^sigma, clutter_rate and max_range must be positive$"),
    (dict(clutter_rate=0.0), "^sigma, clutter_rate and max_range must be positive$"),
    (dict(max_range=0.0), "^sigma, clutter_rate and max_range must be positive$"),
])
def test_beam_model_refuses_bad_settings(settings, message):
    with pytest.raises(ValueError, match=message):
        BeamModel(**settings)


def test_beam_model_accepts_the_ends_of_its_ranges():
    for p_d in (0.0, 1.0):
        assert BeamModel(p_d=p_d).p_d == p_d
    small = BeamModel(sigma=1e-3, clutter_rate=1e-3, max_range=0.5)
    assert small.kappa == pytest.approx(2e-3, rel=1e-15)


def test_bernoulli_update_takes_unnormalised_weights_and_returns_normalised_ones():
    rng = np.random.default_rng(1)
    particles = rng.normal(20.0, 0.3, 500)
    weights = rng.uniform(0.5, 1.5, 500)
    r, w = update_bernoulli(0.6, particles, weights, 20.2, MODEL)
    r_unit, w_unit = update_bernoulli(0.6, particles, weights / weights.sum(), 20.2, MODEL)
    assert r == pytest.approx(r_unit, rel=1e-12) and w.sum() == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(w, w_unit, rtol=1e-12)
    lik = likelihood_ratio(20.2, particles, MODEL)
    mean_lik = np.sum(weights * lik) / weights.sum()
    assert r == pytest.approx(0.6 * mean_lik / (0.4 + 0.6 * mean_lik), rel=1e-12)
