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
