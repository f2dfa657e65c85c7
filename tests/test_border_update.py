"""A detection's border edge in the update (`occtrack.models.box._beyond_update`): the moments
of the Gaussian times the censored likelihood the weights use, checked by quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from occtrack.models.box import BoxMeasurement, _beyond_update


def _state(rng):
    mean = np.array([[rng.uniform(200, 400), rng.normal(0, 20), rng.uniform(20, 40)],
                     [rng.uniform(300, 420), rng.normal(0, 20), rng.uniform(60, 120)]])
    root = rng.normal(0, 4, (2, 3, 3))
    return mean, root @ np.swapaxes(root, -1, -2) + 2.0 * np.eye(3)


def _by_quadrature(m, P, sign, border, R):
    """Posterior moments of x ~ N(m, P) times Phi(sign (h x - border) / sqrt(R)), h = [1, 0,
    sign]: the likelihood acts on e = h x alone, so its 1-D posterior moments (on a fine grid)
    carry over to x along P h' / var(e)."""
    h = np.array([1.0, 0.0, sign])
    mu, var = h @ m, h @ P @ h
    e = np.linspace(mu - 12 * np.sqrt(var), mu + 12 * np.sqrt(var), 400_001)
    w = norm.pdf(e, mu, np.sqrt(var)) * norm.cdf(sign * (e - border) / np.sqrt(R))
    w /= w.sum()
    mean_e = (w * e).sum()
    var_e = (w * (e - mean_e) ** 2).sum()
    gain = P @ h / var
    return m + gain * (mean_e - mu), P + np.outer(gain, gain) * (var_e - var)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("side", [0, 1])
def test_one_border_edge_gives_the_exact_moments(seed, side):
    rng = np.random.default_rng(seed)
    mean, cov = _state(rng)
    edge_noise, H = 0.069, 480.0
    border = np.array([[1.0, 639.0], [1.0, H - 1.0]])
    sign = 1.0 if side else -1.0
    # the border near the predicted edge, inside or out
    edge = mean[1, 0] + sign * mean[1, 2]
    border[1, side] = edge + rng.normal(0, 1.5) * np.sqrt(cov[1, 0, 0] + cov[1, 2, 2])
    observed = np.ones((1, 2, 2), bool)
    observed[0, 1, side] = False
    means, covs = mean[None].copy(), cov[None].copy()
    _beyond_update(means, covs, np.array([0]), observed, np.array([0]), edge_noise, border)
    R = (edge_noise * 2.0 * mean[1, 2]) ** 2
    m, P = _by_quadrature(mean[1], cov[1], sign, border[1, side], R)
    np.testing.assert_allclose(means[0, 1], m, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(covs[0, 1], P, rtol=1e-5, atol=1e-5)
    assert np.array_equal(means[0, 0], mean[0]) and np.array_equal(covs[0, 0], cov[0])
    # the variance along the edge shrinks, and the edge moves out past the border's side
    h = np.array([1.0, 0.0, sign])
    assert h @ covs[0, 1] @ h < h @ cov[1] @ h
    assert sign * (h @ means[0, 1] - h @ mean[1]) > 0


def test_measured_edges_are_left_alone_and_rows_elsewhere_too():
    rng = np.random.default_rng(3)
    states = [_state(rng) for _ in range(4)]
    means = np.stack([s[0] for s in states])
    covs = np.stack([s[1] for s in states])
    observed = np.ones((2, 2, 2), bool)
    observed[1, 0, 1] = False
    before = means.copy(), covs.copy()
    border = np.array([[1.0, 639.0], [1.0, 479.0]])
    _beyond_update(means, covs, np.array([2, 0]), observed, np.array([0, 1]), 0.069, border)
    for k in (1, 2, 3):  # row 2 took a whole detection, rows 1 and 3 none
        assert np.array_equal(means[k], before[0][k]) and np.array_equal(covs[k], before[1][k])
    assert not np.array_equal(means[0, 0], before[0][0, 0])


def test_update_rows_equals_update_on_the_rows_it_is_given():
    """`BoxMeasurement.update` is `update_rows` on copies, border steps included."""
    rng = np.random.default_rng(5)
    model = BoxMeasurement((640, 480), 0.069, 1.0)
    states = [_state(rng) for _ in range(6)]
    means = np.stack([s[0] for s in states])
    covs = np.stack([s[1] for s in states])
    z = np.stack([np.stack([m[:, 0] - m[:, 2], m[:, 0] + m[:, 2]], axis=-1) for m in means])
    z = np.clip(z + rng.normal(0, 3, z.shape), 1.0, [[640.0], [480.0]])
    observed = model.observed(z)
    assert not observed.all()
    new = model.update(means, covs, z, observed)
    in_place = means.copy(), covs.copy()
    model.update_rows(*in_place, np.arange(6), z, observed, np.arange(6))
    np.testing.assert_array_equal(in_place[0], new[0])
    np.testing.assert_array_equal(in_place[1], new[1])
    edges = model.update_edges(means, covs, z, observed)
    assert not np.array_equal(edges[0], new[0])  # the border edges said something more
