"""The one PMB filter takes its measurement and birth models as arguments
(`occtrack.filters.gmpmb.interfaces`): a toy model of point measurements drives it."""

from __future__ import annotations

import numpy as np

from occtrack.config import TrackerConfig
from occtrack.filters.gmpmb import GaussianMixturePMB
from occtrack.occlusion.base import NoOcclusion

REGION = np.array([100.0, 100.0])
NOISE = 1.0  # std of a point's coordinates


class PointMeasurement:
    """z (M, 2): a noisy centre; clutter uniform over the region."""

    region_size = REGION

    def observed(self, z):
        return np.ones(len(z), bool)

    def learn(self, z, observed):
        pass

    def innovation(self, means, covs):
        return means[:, :, 0].copy(), covs[:, :, 0, 0] + NOISE**2

    def gates(self, zhat, S, sigmas):
        sd = np.sqrt(S)
        return np.stack([zhat - sigmas * sd, zhat + sigmas * sd], axis=-1)

    def gate_boxes(self, z, observed):
        return np.stack([z, z], axis=-1)

    def loglik_pairs(self, means, zhat, S, z, observed, k, j):
        r = z[j] - zhat[k]
        return -0.5 * np.sum(r**2 / S[k] + np.log(2 * np.pi * S[k]), axis=1)

    def clutter_density(self, z, observed, scores):
        return np.full(len(z), 1.0 / REGION.prod())

    def update_rows(self, means, covs, rows, z, observed, measurement):
        for k, j in zip(rows, measurement, strict=True):
            for axis in range(2):
                P = covs[k, axis]
                s = P[0, 0] + NOISE**2
                gain = P[:, 0] / s
                means[k, axis] += gain * (z[j, axis] - means[k, axis, 0])
                covs[k, axis] = P - np.outer(gain, P[0])


class PointBirths:
    """One broad still component over the region a step."""

    def components(self, z, observed, dt, step):
        mean = np.zeros((1, 2, 3))
        mean[0, :, 0], mean[0, :, 2] = REGION / 2, 10.0
        cov = np.zeros((1, 2, 3, 3))
        for axis in range(2):
            cov[0, axis] = np.diag([(REGION[axis] / 2) ** 2, 1.0, 1.0])
        return np.array([0.5 if step == 0 else 0.01]), mean, cov


def test_a_toy_measurement_model_drives_the_filter():
    config = TrackerConfig(occlusion="none", fps=10.0, confirm_hits=2, confirm_window=3)
    f = GaussianMixturePMB(config, NoOcclusion(), PointMeasurement(), PointBirths())
    assert f.image_size.tolist() == REGION.tolist()
    rng = np.random.default_rng(0)
    truth = np.array([30.0, 60.0])
    for _ in range(15):
        z = truth + NOISE * rng.standard_normal((1, 2))
        clutter = rng.uniform(0, 100, (rng.poisson(0.5), 2))
        f.step(np.r_[z, clutter], np.ones(1 + len(clutter)))
    r, means = f.object_means()
    best = int(np.argmax(r))
    assert r[best] > 0.9
    assert np.linalg.norm(means[best, :, 0] - truth) < 3 * NOISE  # about the last point
    assert (r > 0.5).sum() == 1  # the clutter started no confirmed object


def test_the_miss_branch_moves_a_hidden_density_and_its_velocity_with_it():
    """A missed component's density moment-matched to p(x) (1 - d + d o v q(x)) / miss:
    the hidden share s = d o v q / miss of it moves to the hidden moments, the velocity by
    its regression on the centre; against the moments of the two-part mixture, by hand."""
    from occtrack.filters.gmpmb.children import _miss_branch_moments

    mean = np.array([[[1.0, 2.0, 0.5], [3.0, 0.0, 0.5]]])
    cov = np.zeros((1, 2, 3, 3))
    for axis in range(2):
        cov[0, axis] = [[4.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 0.01]]
    det, occ, v, q = np.array([0.9]), np.array([1.0]), np.array([1.0]), np.array([0.5])
    miss = 1 - det + det * occ * v * q
    centre, variance = np.array([[0.0, 3.0]]), np.array([[1.0, 4.0]])
    m, P = mean.copy(), cov.copy()
    _miss_branch_moments(m, P, np.array([0]), np.array([-1]), det, occ, v, q, miss, centre,
                         variance)
    s = (det * occ * v * q / miss)[0]
    # axis 0: hidden part N(x; 0, 1) for the centre, velocity by regression (gain 1/4)
    gain = cov[0, 0, :, 0] / 4.0
    hidden_mean = mean[0, 0] + gain * (0.0 - 1.0)
    hidden_cov = cov[0, 0] + np.outer(gain, gain) * (1.0 - 4.0)
    mix = (1 - s) * mean[0, 0] + s * hidden_mean
    mix_cov = ((1 - s) * (cov[0, 0] + np.outer(mean[0, 0] - mix, mean[0, 0] - mix))
               + s * (hidden_cov + np.outer(hidden_mean - mix, hidden_mean - mix)))
    assert np.allclose(m[0, 0], mix) and np.allclose(P[0, 0], mix_cov)
    # axis 1: the centre was already where the hidden part is and as wide: nothing moves
    assert np.allclose(m[0, 1], mean[0, 1]) and np.allclose(P[0, 1], cov[0, 1])
    # a hit child (j >= 0) is left alone
    m2, P2 = mean.copy(), cov.copy()
    _miss_branch_moments(m2, P2, np.array([0]), np.array([0]), det, occ, v, q, miss, centre,
                         variance)
    assert np.array_equal(m2, mean) and np.array_equal(P2, cov)
