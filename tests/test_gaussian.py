"""Vectorised Gaussian components against plain one-at-a-time matrix Kalman filtering."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import log_ndtr
from scipy.stats import multivariate_normal

from occtrack.densities import gaussian
from occtrack.models.birth import EdgeBirths
from occtrack.models.box import BoxMeasurement, edges_from_ltwh, ltwh_from_edges, ltwh_from_states
from occtrack.models.markov import TwoStateMarkov
from occtrack.models.motion import ConstantVelocity

H = np.array([[1.0, 0.0, -1.0], [1.0, 0.0, 1.0]])


def random_components(rng, k):
    means = rng.normal(0, 200, (k, 2, 3)) + np.array([500.0, 10.0, 60.0])
    a = rng.normal(0, 1, (k, 2, 3, 3))
    covs = a @ np.swapaxes(a, -1, -2) * 30 + np.eye(3) * 5
    return means, covs


def full(means, covs):
    """Block-diagonal 6-D state and covariance of one component, order (x block, y block)."""
    P = np.zeros((6, 6))
    P[:3, :3], P[3:, 3:] = covs
    return means.reshape(6), P


def plain_update(x, P, z, observed, R):
    """Textbook Kalman update with the unobserved rows deleted from H, z and R."""
    Hf = np.zeros((4, 6))
    Hf[:2, :3], Hf[2:, 3:] = H, H
    Rf = np.kron(np.eye(2), R)
    rows = np.flatnonzero(observed.reshape(4))
    Hf, Rf, zf = Hf[rows], Rf[np.ix_(rows, rows)], z.reshape(4)[rows]
    S = Hf @ P @ Hf.T + Rf
    K = P @ Hf.T @ np.linalg.inv(S)
    x_new = x + K @ (zf - Hf @ x)
    P_new = (np.eye(6) - K @ Hf) @ P
    loglik = multivariate_normal(Hf @ x, S).logpdf(zf) if len(rows) else 0.0
    return x_new, P_new, loglik


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_update_and_loglik_equal_plain_matrix_kalman(seed):
    rng = np.random.default_rng(seed)
    means, covs = random_components(rng, 7)
    z = rng.normal(0, 200, (5, 2, 2)) + 500
    observed = rng.random((5, 2, 2)) > 0.25
    R = np.eye(2) * 144.0
    ll = gaussian.loglik(means, covs, H, R, z, observed)
    assert ll.shape == (7, 5)
    k_idx, j_idx = np.meshgrid(np.arange(7), np.arange(5), indexing="ij")
    k_idx, j_idx = k_idx.ravel(), j_idx.ravel()
    new_means, new_covs = gaussian.update(means[k_idx], covs[k_idx], H, R, z[j_idx],
                                          observed[j_idx])
    for n, (k, j) in enumerate(zip(k_idx, j_idx, strict=True)):
        x, P = full(means[k], covs[k])
        x_ref, P_ref, ll_ref = plain_update(x, P, z[j], observed[j], R)
        x_got, P_got = full(new_means[n], new_covs[n])
        np.testing.assert_allclose(x_got, x_ref, rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(P_got, P_ref, rtol=1e-8, atol=1e-8)
        assert ll[k, j] == pytest.approx(ll_ref, rel=1e-10, abs=1e-9)


def test_predict_equals_F_P_Ft_plus_Q():
    rng = np.random.default_rng(3)
    means, covs = random_components(rng, 4)
    motion = ConstantVelocity(dt=0.2, position_noise=3.0, velocity_noise=5.0, size_noise=1.0)
    m2, P2 = motion.predict(means, covs)
    F, Q = motion.F, motion.Q
    assert F[0, 1] == 0.2
    np.testing.assert_allclose(np.diag(Q), [9 * 0.2, 25 * 0.2, 0.2])
    for k in range(4):
        for b in range(2):
            np.testing.assert_allclose(m2[k, b], F @ means[k, b])
            np.testing.assert_allclose(P2[k, b], F @ covs[k, b] @ F.T + Q)


def test_velocity_relaxing_to_zero_travels_v_tau_and_settles_at_stationary_spread():
    """Ornstein-Uhlenbeck velocity: after t seconds unseen the centre has moved
    v0 tau (1 - exp(-t / tau)) and the velocity variance tends to q_v^2 tau / 2; a time
    constant far beyond the step is the constant-velocity model."""
    tau, dt, qv = 1.5, 0.1, 40.0
    motion = ConstantVelocity(dt=dt, position_noise=3.0, velocity_noise=qv, size_noise=1.0,
                              velocity_time=tau)
    mean = np.zeros((1, 2, 3))
    mean[0, :, 1] = [30.0, -12.0]
    cov = np.tile(np.eye(3), (1, 2, 1, 1))
    for _ in range(25):
        mean, cov = motion.predict(mean, cov)
    v0, t = np.array([30.0, -12.0]), 25 * dt
    np.testing.assert_allclose(mean[0, :, 0], v0 * tau * (1 - np.exp(-t / tau)))
    np.testing.assert_allclose(mean[0, :, 1], v0 * np.exp(-t / tau))
    for _ in range(500):
        mean, cov = motion.predict(mean, cov)
    assert cov[0, 0, 1, 1] == pytest.approx(qv**2 * tau / 2, rel=1e-9)
    slow = ConstantVelocity(dt, 3.0, qv, 1.0, velocity_time=1e9)
    plain = ConstantVelocity(dt, 3.0, qv, 1.0)
    np.testing.assert_allclose(slow.F, plain.F, atol=1e-8)
    np.testing.assert_allclose(slow.Q, plain.Q, rtol=1e-6)
    assert plain.F[1, 1] == 1.0 and plain.F[0, 1] == dt


def test_updated_covariances_stay_symmetric_positive_definite():
    rng = np.random.default_rng(4)
    means, covs = random_components(rng, 200)
    z = rng.normal(0, 200, (200, 2, 2)) + 500
    _, P = gaussian.update(means, covs, H, np.eye(2) * 144.0, z)
    np.testing.assert_array_equal(P, np.swapaxes(P, -1, -2))
    assert (np.linalg.eigvalsh(P) > 0).all()


def test_box_edges_round_trip_and_border_edges():
    boxes = np.array([[0.0, 10.0, 50.0, 100.0], [1900.0, 990.0, 20.0, 90.0]])
    edges = edges_from_ltwh(boxes)
    np.testing.assert_array_equal(edges[1], [[1900.0, 1920.0], [990.0, 1080.0]])
    np.testing.assert_array_equal(ltwh_from_edges(edges), boxes)
    model = BoxMeasurement((1920, 1080), edge_noise=0.075, border_margin=1.0)
    np.testing.assert_array_equal(model.observed(edges),
                                  [[[False, True], [True, True]], [[True, False], [True, False]]])
    # an edge exactly at the margin is on the border; the defaults: 0.069 h, 1 px
    at_margin = np.array([[[1.0, 1918.5], [1.5, 1078.5]], [[1.5, 1919.0], [1.0, 1079.0]]])
    np.testing.assert_array_equal(BoxMeasurement((1920, 1080)).observed(at_margin),
                                  [[[False, True], [True, True]], [[True, False], [False, False]]])
    default = BoxMeasurement((1920, 1080))
    assert (default.edge_noise, default.border_margin) == (0.069, 1.0)


def test_edges_beyond_the_border_are_measured_unless_switched_off():
    """An edge within the margin of the border is censored (a clipping detector's cut); one
    beyond it by more than the margin is the detector's estimate of the unseen part and is
    measured, unless `extrapolated_edges` is off (then censored, as before)."""
    # left -0.5 (on the border), top -100 (beyond), right 1921 (on), bottom 1200 (beyond);
    # then left -1.5, top 1.0 (on), right 1921.5, bottom 1080
    z = np.array([[[-0.5, 1921.0], [-100.0, 1200.0]], [[-1.5, 1921.5], [1.0, 1080.0]]])
    got = BoxMeasurement((1920, 1080)).observed(z)
    np.testing.assert_array_equal(got, [[[False, False], [True, True]],
                                        [[True, True], [False, False]]])
    off = BoxMeasurement((1920, 1080), extrapolated_edges=False).observed(z)
    assert not off.any()


def test_border_edge_likelihood_is_probability_beyond_border_times_peak_density():
    """A left edge on the border: the right edge is scored as usual, the left one by
    Phi((border - predicted edge) / sd) / (sqrt(2 pi) sigma), sigma = 0.075 of the 160 px
    height = 12 px."""
    model = BoxMeasurement((1920, 1080), edge_noise=0.075, border_margin=1.0)
    means = np.array([[[20.0, 0.0, 30.0], [500.0, 0.0, 80.0]]])
    covs = np.tile(np.diag([100.0, 50.0, 25.0]), (1, 2, 1, 1))
    z = edges_from_ltwh(np.array([[0.0, 430.0, 52.0, 165.0]]))
    observed = model.observed(z)
    got = model.loglik(means, covs, z, observed)[0, 0]
    zhat, S, _ = gaussian.innovation(means, covs, H, np.eye(2) * 144.0)
    sd_left = np.sqrt(S[0, 0, 0, 0])
    expected = (multivariate_normal(zhat[0, 1], S[0, 1]).logpdf(z[0, 1])
                + multivariate_normal(zhat[0, 0, 1], S[0, 0, 1, 1]).logpdf(z[0, 0, 1])
                + log_ndtr((1.0 - zhat[0, 0, 0]) / sd_left) - 0.5 * np.log(2 * np.pi * 144.0))
    assert got == pytest.approx(expected, rel=1e-12)


def test_markov_feature_forgets_its_ratio_every_half_second():
    chain = TwoStateMarkov(stationary=0.8, half_second_ratio=0.9)
    assert chain.predict(1.0, 0.5) == pytest.approx(0.8 + 0.1 * 0.2)
    p = 0.0
    for _ in range(4):
        p = chain.predict(p, 0.125)
    assert p == pytest.approx(0.8 - 0.1 * 0.8)
    with pytest.raises(ValueError, match="outside"):
        TwoStateMarkov(1.5, 0.5)


def test_box_conversions_keep_their_shapes_and_give_floats():
    """ltwh <-> edges for one box (2, 2), a grid of them (K, M, 2, 2), and states to boxes:
    left = c - s, width = 2 s per axis. Integer boxes give float edges."""
    edges = edges_from_ltwh([[10, 20, 30, 40]])
    assert edges.dtype == float and edges.tolist() == [[[10.0, 40.0], [20.0, 60.0]]]
    # single-precision boxes are summed in double: the right edge of 0.1f + 0.8f is not
    # float32's rounded sum
    single = np.array([[0.1, 0.2, 0.8, 0.7]], dtype=np.float32)
    low, size = single[0, :2].astype(float), single[0, 2:].astype(float)
    assert edges_from_ltwh(single)[0].tolist() == np.stack([low, low + size], -1).tolist()
    assert float(np.float32(0.1) + np.float32(0.8)) != float(np.float32(0.1)) + float(
        np.float32(0.8))
    assert ltwh_from_edges(edges[0]).tolist() == [10.0, 20.0, 30.0, 40.0]
    grid = np.tile(edges[0], (3, 2, 1, 1))
    assert ltwh_from_edges(grid).shape == (3, 2, 4)
    states = np.array([[[100.0, 5.0, 20.0], [300.0, -2.0, 60.0]]])
    assert ltwh_from_states(states).tolist() == [[80.0, 240.0, 40.0, 120.0]]


def test_gates_widen_the_predicted_box_by_the_less_certain_edge():
    """Per axis: [min(low, high) - k sd, max(low, high) + k sd] with sd the larger of the two
    edges' standard deviations (the cross term plays no part)."""
    zhat = np.array([[[100.0, 140.0], [50.0, 170.0]], [[140.0, 100.0], [170.0, 50.0]]])
    S = np.tile(np.array([[[25.0, 20.0], [20.0, 9.0]], [[4.0, -3.0], [-3.0, 16.0]]]),
                (2, 1, 1, 1))
    gates = BoxMeasurement.gates(zhat, S, 3.0)
    # the second box is inside out (low edge above the high one): the same gate
    np.testing.assert_array_equal(gates, [[[85.0, 155.0], [38.0, 182.0]]] * 2)


def test_edge_births_default_speed_unit_is_one_pixel():
    births = EdgeBirths((640.0, 480.0), inward_speed=12.0, speed_std=3.0)
    _, means, covs = births.components(1.0, 2.0, np.array([10.0, 30.0]), np.array([2.0, 5.0]))
    assert means[0, 0, 1] == 12.0 and means[1, 0, 1] == -12.0
    assert covs[4, 0, 1, 1] == 9.0


@pytest.mark.parametrize("stationary,ratio,message", [
    (-0.1, 0.5, r"^stationary probability -0.1 is outside \[0, 1\]$"),
    (1.5, 0.5, r"^stationary probability 1.5 is outside \[0, 1\]$"),
    (0.5, -0.2, r"^half-second ratio -0.2 is outside \[0, 1\]$"),
    (0.5, 1.2, r"^half-second ratio 1.2 is outside \[0, 1\]$"),
])
def test_markov_feature_refuses_probabilities_outside_zero_one(stationary, ratio, message):
    with pytest.raises(ValueError, match=message):
        TwoStateMarkov(stationary, ratio)


def test_markov_feature_accepts_the_ends_of_zero_one():
    """Ratio 0: the feature never forgets; 1: it is back at the stationary value at once."""
    for p in (0.0, 1.0):
        assert TwoStateMarkov(p, 0.5).predict(0.5, 0.5) == pytest.approx(0.5 * p + 0.25)
    assert TwoStateMarkov(0.8, 0.0).predict(0.3, 2.0) == pytest.approx(0.3, rel=1e-15)
    assert TwoStateMarkov(0.8, 1.0).predict(0.3, 0.5) == 0.8


def test_motion_refuses_a_velocity_time_that_is_not_positive():
    for tau in (0.0, -1.0):
        with pytest.raises(ValueError, match=f"^velocity_time must be positive, not {tau}$"):
            ConstantVelocity(0.1, 1.0, 1.0, 1.0, velocity_time=tau)


def test_predict_with_one_model_per_block_equals_the_plain_form():
    """F and Q given per block (B, d, d): block b of every component moves with F_b, Q_b."""
    rng = np.random.default_rng(5)
    means, covs = random_components(rng, 4)
    F = np.stack([np.eye(3) + rng.normal(0, 0.1, (3, 3)) for _ in range(2)])
    Q = np.stack([np.diag(rng.uniform(1, 3, 3)) for _ in range(2)])
    m2, P2 = gaussian.predict(means, covs, F, Q)
    for k in range(4):
        for b in range(2):
            np.testing.assert_allclose(m2[k, b], F[b] @ means[k, b], rtol=1e-13)
            np.testing.assert_allclose(P2[k, b], F[b] @ covs[k, b] @ F[b].T + Q[b], rtol=1e-12)


@pytest.mark.parametrize("p,blocks", [(1, 2), (2, 1), (3, 2)])
def test_inv_logdet_equals_linalg_for_every_size(p, blocks):
    """Stacks (K, B, p, p) with B != p: the closed forms (p = 1, 2) and the general one."""
    rng = np.random.default_rng(p)
    a = rng.normal(size=(4, blocks, p, p))
    S = a @ np.swapaxes(a, -1, -2) + np.eye(p)
    inv, logdet = gaussian.inv_logdet(S)
    np.testing.assert_allclose(inv, np.linalg.inv(S), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(logdet, np.linalg.slogdet(S)[1], rtol=1e-12)


def test_loglik_of_three_blocks_without_a_mask_sums_the_blocks():
    """B = 3 blocks of p = 2 rows, `observed` left out (all measured): the sum over blocks of
    log N(z_b; H m_b, H P_b H' + R)."""
    rng = np.random.default_rng(6)
    means = rng.normal(0, 50, (3, 3, 3)) + 200
    a = rng.normal(size=(3, 3, 3, 3))
    covs = a @ np.swapaxes(a, -1, -2) * 10 + np.eye(3)
    z = rng.normal(200, 50, (4, 3, 2))
    R = np.eye(2) * 25.0
    got = gaussian.loglik(means, covs, H, R, z)
    np.testing.assert_allclose(got, gaussian.loglik(means, covs, H, R, z,
                                                    np.ones(z.shape, dtype=bool)), rtol=1e-13)
    for k in range(3):
        for j in range(4):
            expected = sum(multivariate_normal(H @ means[k, b], H @ covs[k, b] @ H.T + R)
                           .logpdf(z[j, b]) for b in range(3))
            assert got[k, j] == pytest.approx(expected, rel=1e-10)
