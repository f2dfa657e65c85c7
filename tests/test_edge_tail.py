"""The heavy-tailed edge likelihood (occtrack.models.edge_tail): the closed form against the
mixture density itself, the EM for its weight against known truth, and its place in the box
model and the tracker."""

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from occtrack import Tracker, TrackerConfig
from occtrack.models.box import BoxMeasurement
from occtrack.models.edge_tail import EdgeTail, mahalanobis


def _problem(rng, K=5, M=6, censor=False):
    """Components (K, 2, 3) with covariances and detections (M, 2, 2) around them."""
    means = np.zeros((K, 2, 3))
    means[:, :, 0] = rng.uniform(300, 700, (K, 2))
    means[:, :, 1] = rng.normal(0, 20, (K, 2))
    means[:, :, 2] = rng.uniform(20, 60, (K, 2))
    A = rng.normal(0, 1, (K, 2, 3, 3))
    covs = A @ np.swapaxes(A, -1, -2) + 4 * np.eye(3)
    z = np.sort(rng.uniform(200, 800, (M, 2, 2)), axis=-1)
    if censor:
        z[0, 0, 0] = 0.0  # on the left border
        z[1, 1, 1] = 1000.0  # on the bottom border
    return means, covs, z


def _mixture_log_ratio(zhat, S, z, observed, eps, kappa):
    """log((1 - eps) N(S) + eps N(kappa^2 S)) - log N(S) over the measured edges, by scipy."""
    idx = np.flatnonzero(observed.ravel())
    if len(idx) == 0:
        return 0.0
    full = np.zeros((4, 4))
    full[:2, :2], full[2:, 2:] = S[0], S[1]
    cov = full[np.ix_(idx, idx)]
    x, mu = z.ravel()[idx], zhat.ravel()[idx]
    core = multivariate_normal(mu, cov).logpdf(x)
    tail = multivariate_normal(mu, kappa ** 2 * cov).logpdf(x)
    return np.logaddexp(math.log1p(-eps) + core, math.log(eps) + tail) - core


@pytest.mark.parametrize("censor", [False, True])
def test_the_correction_is_the_mixture_density_over_the_core(censor):
    rng = np.random.default_rng(1)
    means, covs, z = _problem(rng, censor=censor)
    model = BoxMeasurement((1000, 1000))
    observed = model.observed(z)
    zhat, S = model.innovation(means, covs)
    tail = EdgeTail(0.07, 2.5)
    k, j = np.divmod(np.arange(len(means) * len(z)), len(z))
    got = tail.correction(zhat, S, z, observed, k, j)
    for e in range(len(k)):
        want = _mixture_log_ratio(zhat[k[e]], S[k[e]], z[j[e]], observed[j[e]], 0.07, 2.5)
        assert got[e] == pytest.approx(want, rel=1e-9, abs=1e-9)


def test_mahalanobis_counts_the_measured_edges_only():
    zhat = np.array([[[0.0, 10.0], [0.0, 20.0]]])
    S = np.tile(np.diag([4.0, 4.0]), (1, 2, 1, 1))
    z = np.array([[[2.0, 14.0], [0.0, 26.0]]])
    observed = np.array([[[True, True], [False, True]]])
    d2, m = mahalanobis(zhat, S, z, observed, np.array([0]), np.array([0]))
    assert d2[0] == pytest.approx((4 + 16 + 36) / 4)
    assert m[0] == 3


def test_the_box_model_adds_the_tail_to_the_pairs_and_to_every_pair_alike():
    rng = np.random.default_rng(2)
    means, covs, z = _problem(rng, censor=True)
    plain = BoxMeasurement((1000, 1000))
    heavy = BoxMeasurement((1000, 1000), tail=EdgeTail(0.05, 3.0))
    observed = plain.observed(z)
    zhat, S = plain.innovation(means, covs)
    k, j = np.divmod(np.arange(len(means) * len(z)), len(z))
    base = plain.loglik_pairs(means, zhat, S, z, observed, k, j)
    got = heavy.loglik_pairs(means, zhat, S, z, observed, k, j)
    extra = EdgeTail(0.05, 3.0).correction(zhat, S, z, observed, k, j)
    np.testing.assert_allclose(got, base + extra, rtol=1e-12)
    # the tail only ever adds: log(1 - eps + eps a) >= log(1 - eps), and far pairs gain most
    assert (got - base >= math.log1p(-0.05) - 1e-12).all()
    np.testing.assert_allclose(heavy.loglik(means, covs, z, observed).ravel(), got, rtol=1e-9)


def test_only_the_tracked_objects_components_take_the_tail():
    """`tracked_components` (the filter says which components are a Bernoulli's) limits the
    tail to those for the next likelihoods; the Poisson part keeps the Gaussian. The mark
    holds for one call."""
    rng = np.random.default_rng(4)
    means, covs, z = _problem(rng)
    plain = BoxMeasurement((1000, 1000))
    heavy = BoxMeasurement((1000, 1000), tail=EdgeTail(0.05, 3.0))
    observed = plain.observed(z)
    zhat, S = plain.innovation(means, covs)
    k, j = np.divmod(np.arange(len(means) * len(z)), len(z))
    labelled = np.array([True, False, True, False, False])
    heavy.tracked_components(labelled)
    got = heavy.loglik_pairs(means, zhat, S, z, observed, k, j)
    base = plain.loglik_pairs(means, zhat, S, z, observed, k, j)
    extra = EdgeTail(0.05, 3.0).correction(zhat, S, z, observed, k, j)
    np.testing.assert_allclose(got, base + np.where(labelled[k], extra, 0.0), rtol=1e-12)
    np.testing.assert_allclose(heavy.loglik_pairs(means, zhat, S, z, observed, k, j),
                               base + extra, rtol=1e-12)


def test_em_finds_the_tail_weight_of_innovations_drawn_from_the_mixture():
    """Innovations drawn from (1 - eps) N(S) + eps N(kappa^2 S) with every edge measured: the
    online EM's weight, after many frames and with a weak prior, is the true eps within three
    of its standard errors (sqrt(eps (1 - eps) / n) inflated by the responsibilities' overlap;
    the bound below is that of the exact counts, times 2)."""
    rng = np.random.default_rng(3)
    eps_true, kappa, per_frame, frames = 0.12, 3.0, 40, 250
    tail = EdgeTail(0.05, kappa, memory=1e9, prior_weight=1.0)
    zhat = np.zeros((per_frame, 2, 2))
    S = np.tile(np.eye(2), (per_frame, 2, 1, 1))
    observed = np.ones((per_frame, 2, 2), dtype=bool)
    label = np.arange(per_frame)
    everyone = np.ones(per_frame, dtype=bool)
    for _ in range(frames):
        wide = rng.random(per_frame) < eps_true
        z = rng.standard_normal((per_frame, 2, 2)) * np.where(wide, kappa, 1.0)[:, None, None]
        k = j = np.arange(per_frame)
        tail.correction(zhat, S, z, observed, k, j)
        tail.learn(label, np.arange(per_frame), everyone, 0.1)
    n = per_frame * frames
    se = 2 * math.sqrt(eps_true * (1 - eps_true) / n)
    assert abs(tail.weight - eps_true) < 3 * se


def test_em_learns_from_confirmed_tracks_and_the_detections_they_took_only():
    tail = EdgeTail(0.05, 3.0, memory=1e9, prior_weight=1.0)
    zhat = np.zeros((3, 2, 2))
    S = np.tile(np.eye(2), (3, 2, 1, 1))
    observed = np.ones((1, 2, 2), dtype=bool)
    z = np.full((1, 2, 2), 30.0)  # far off: all tail
    k, j = np.arange(3), np.zeros(3, dtype=np.int64)
    tail.correction(zhat, S, z, observed, k, j)
    # component 0 is slot 0 (not confirmed), 1 is slot 1 (took nothing), 2 Poisson
    tail.learn(np.array([0, 1, -1]), np.array([0, -1]), np.array([False, True]), 0.1)
    assert tail.count == 0 and tail.weight == pytest.approx(0.05)


def test_a_tracker_without_the_tail_is_the_gaussian_one():
    """tail_weight = 0 builds no tail: the box model's likelihood is the Gaussian of
    models.box; with the default tail the outputs differ only where a detection lies far."""
    cfg = TrackerConfig(image_size=(640, 480), fps=10, tail_weight=0.0)
    tracker = Tracker(cfg)
    assert tracker.filter.measurement.tail is None
    assert Tracker(TrackerConfig(image_size=(640, 480), fps=10)).filter.measurement.tail.weight \
        == TrackerConfig().tail_weight


def test_a_jump_of_many_standard_deviations_stays_the_tracks_with_the_tail():
    """A box that jumps 40 % of its height sideways in one frame (a car the camera passes):
    with the Gaussian alone it starts a second track (a twin, then a switch), with the tail it
    stays the first's."""
    def ids(tail_weight):
        t = Tracker(TrackerConfig(image_size=(1000, 600), fps=10, tail_weight=tail_weight,
                                  occlusion="none"))
        box = np.array([[400.0, 200.0, 120.0, 100.0]])
        seen = []
        for f in range(12):
            shift = 40.0 if f >= 8 else 0.0
            tracks = t.step(box + [shift, 0, 0, 0], np.ones(1))
            seen.append(tuple(tracks.ids))
        return seen
    assert set(ids(0.05)[5:]) == {(1,)}
    assert ids(0.0)[-1] == (2,)


@pytest.mark.parametrize("field, value, message", [
    ("tail_weight", 0.6, "tail_weight must be in"),
    ("tail_weight", -0.1, "tail_weight must be in"),
    ("tail_scale", 1.0, "tail_scale must be a number above 1"),
    ("tail_scale", math.inf, "tail_scale must be a number above 1"),
])
def test_bad_tail_settings_are_refused_by_name(field, value, message):
    with pytest.raises(ValueError, match=message):
        TrackerConfig(**{field: value})
