"""The aspect-ratio step (occtrack.models.aspect): what it learns, the Kalman update it makes,
and what it does for a person the image border cuts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.models.aspect import MIN_BOXES, AspectPrior, _aspect_update
from occtrack.models.box import BoxMeasurement, edges_from_ltwh
from occtrack.tracker import Tracker, TrackerConfig


def _random_states(rng, K):
    means = np.empty((K, 2, 3))
    means[:, :, 0] = rng.uniform(50, 600, (K, 2))
    means[:, :, 1] = rng.normal(0, 5, (K, 2))
    means[:, 0, 2] = rng.uniform(10, 40, K)
    means[:, 1, 2] = rng.uniform(30, 120, K)
    root = rng.normal(0, 3, (K, 2, 3, 3))
    covs = root @ np.swapaxes(root, -1, -2) + 0.5 * np.eye(3)
    return means, covs


def test_learns_log_aspect_of_whole_boxes_only():
    rng = np.random.default_rng(1)
    boxes = np.c_[rng.uniform(5, 500, 40), rng.uniform(5, 300, 40), rng.uniform(10, 60, 40),
                  rng.uniform(40, 160, 40)]
    boxes[:7, 1] = 1.0  # on the top border: not whole
    boxes[7:12, 0] = 640.0 - boxes[7:12, 2] + 0.5  # past the right border
    z = edges_from_ltwh(boxes)
    observed = BoxMeasurement((640.0, 480.0)).observed(z)
    prior = AspectPrior()
    prior.learn(z, observed[:, :, :])
    whole = observed.reshape(len(z), -1).all(axis=1)
    assert whole.sum() == 28
    ratio = np.log(boxes[whole, 2] / boxes[whole, 3])
    mu, sigma = prior.moments()
    assert prior.stats[0] == 28
    assert mu == pytest.approx(ratio.mean(), rel=1e-12)
    assert sigma == pytest.approx(ratio.std(), rel=1e-9)


def test_nothing_before_enough_boxes():
    prior = AspectPrior()
    z = edges_from_ltwh(np.array([[10.0, 10.0, 20.0, 60.0]] * (MIN_BOXES - 1)))
    prior.learn(z, np.ones(z.shape, bool))
    assert prior.moments() is None
    # the measurement model then updates a cut box as it does without the prior
    means, covs = _random_states(np.random.default_rng(0), 3)
    observed = np.ones((1, 2, 2), bool)
    observed[0, 1, 1] = False
    cut = edges_from_ltwh(np.array([[300.0, 400.0, 40.0, 81.0]])).repeat(3, 0)
    args = np.arange(3), cut, observed.repeat(3, 0), np.zeros(3, np.int64)
    with_prior, without = (means.copy(), covs.copy()), (means.copy(), covs.copy())
    BoxMeasurement((640.0, 480.0), aspect=prior).update_rows(*with_prior, *args)
    BoxMeasurement((640.0, 480.0)).update_rows(*without, *args)
    assert np.array_equal(with_prior[0], without[0]) and np.array_equal(with_prior[1], without[1])
    prior.learn(z[:1], np.ones((1, 2, 2), bool))
    assert prior.moments() is not None


@pytest.mark.parametrize("seed", range(5))
def test_update_is_the_scalar_kalman_update(seed):
    """Against the textbook form: H picks the cut axis's half-size, R the variance of the
    module docstring; rows whose box is whole or cut on both axes are left as they were."""
    rng = np.random.default_rng(seed)
    K, M = 12, 6
    means, covs = _random_states(rng, K)
    observed = np.ones((M, 2, 2), bool)
    observed[0, 1, 1] = False            # bottom cut: the height from the width
    observed[1, 0, 0] = False            # left cut: the width from the height
    observed[2, 1, 0] = observed[2, 1, 1] = False  # both vertical edges cut
    observed[3, 0, 1] = observed[3, 1, 1] = False  # a corner: left alone
    # detection 4 whole: left alone; detection 5 bottom cut again
    observed[5, 1, 1] = False
    rows = rng.permutation(K)[:M]
    prior = AspectPrior()
    mu, sigma = -1.05, 0.14
    prior.stats[:] = (MIN_BOXES, MIN_BOXES * mu, MIN_BOXES * (mu * mu + sigma * sigma))
    new_means, new_covs = means.copy(), covs.copy()
    got_mu, got_sigma = prior.moments()
    _aspect_update(new_means, new_covs, rows, observed, np.arange(M), got_mu, got_sigma)
    for j, k in enumerate(rows):
        whole = observed[j].all(axis=1)
        if whole[0] == whole[1]:
            assert np.array_equal(new_means[k], means[k]) and np.array_equal(new_covs[k], covs[k])
            continue
        w, cut = (0, 1) if whole[0] else (1, 0)
        scale = math.exp(-got_mu if cut == 1 else got_mu)
        value = means[k, w, 2] * scale
        R = value ** 2 * got_sigma ** 2 + scale ** 2 * covs[k, w, 2, 2]
        H = np.array([[0.0, 0.0, 1.0]])
        P = covs[k, cut]
        S = H @ P @ H.T + R
        G = P @ H.T / S
        expected = means[k, cut] + G[:, 0] * (value - means[k, cut, 2])
        np.testing.assert_allclose(new_means[k, cut], expected, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(new_covs[k, cut], (np.eye(3) - G @ H) @ P, rtol=1e-9,
                                   atol=1e-9)
        assert np.array_equal(new_means[k, w], means[k, w])
        assert np.array_equal(new_covs[k, w], covs[k, w])


def _leaving_walker(aspect_prior: bool) -> float:
    """A person walks down out of a 640 x 480 image, growing as they near the camera (.8 % a
    frame at 14 fps) until their feet are .7 box heights below it, beside two people seen whole
    (who teach the aspect ratio). Returns the
    median shortfall of the reported bottom edge under the true one while the border cuts it,
    in true box heights."""
    config = TrackerConfig(occlusion="none", image_size=(640.0, 480.0), fps=14.0,
                           camera_motion="none", aspect_prior=aspect_prior)
    tracker = Tracker(config)
    rng = np.random.default_rng(7)
    others = np.array([[40.0, 60.0, 30.0, 80.0], [520.0, 80.0, 34.0, 90.0]])
    gaps = []
    for t in range(120):
        height, top = 150.0 * 1.008 ** t, 250.0 + t
        walker = np.array([300.0 - 0.37 * height / 2, top, 0.37 * height, height])
        clipped = walker.copy()
        clipped[3] = min(top + height, 481.0) - top  # MOTChallenge boxes end at 481
        tracks = tracker.step(np.vstack([others + rng.normal(0, 1.0, others.shape), clipped]))
        if top + height > 490.0:
            box = tracks.boxes[tracks.detection_index == 2][0]
            gaps.append((top + height - box[1] - box[3]) / height)
    return float(np.median(gaps))


def test_hidden_bottom_edge_follows_the_shape():
    """Without the step the hidden bottom edge is known only to lie past the border and falls
    behind a growing person (by .16 box heights); with it the width carries the height (what is
    left is the lag of a size model without a growth rate, width and height alike)."""
    without, with_ = _leaving_walker(False), _leaving_walker(True)
    assert without > 0.15
    assert abs(with_) < 0.1
