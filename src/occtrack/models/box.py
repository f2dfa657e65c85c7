"""Image boxes measured by their edges, with edges on the image border left unmeasured.

State per image axis (horizontal, vertical): centre c, velocity v, half-size s. A box's edges
are linear in it,

    low edge = c - s,  high edge = c + s,   H = [[1, 0, -1], [1, 0, 1]],  R_k = (e h_k)^2 I

with e the noise of each edge in units of the box's height h_k = 2 s_vertical of component k
(the paper's 12 px is e = 0.069 at MOT17-04's median height of 175 px): a detector's error
grows with the object's image size, so one e serves near and far people and every camera.
A detector clips boxes to the image, so an edge lying on the border (within `border_margin`
pixels) says only that the true edge is at or beyond it: the likelihood of a border edge is
the probability that the object's edge lies beyond the border, Phi((border - zhat) / sqrt(S))
for a low edge, scaled by the noise's peak density 1 / (sqrt(2 pi) e h_k) so that censored and
measured edges share the units of the clutter density (a border edge counts as a measured edge
that matched as well as it could have). The update (`update_rows`) takes the measured edges by
Kalman, then what a cut detection still says: the cut axis's half-size through the boxes'
aspect ratio (`occtrack.models.aspect`) and that each border edge lies beyond the border, by the
moments of the Gaussian times that same Phi (`_beyond_update`). Without the last two the
hidden edge stays where the last whole box put it, and a person walking out of the image
keeps a box too short (the hidden bottom edge of tracked boxes, median: MOT17-05 .17 box
heights inside the true one, with both steps .04 past it; MOT17-04 .36 and .10 inside).

Measurements travel as edge arrays z of shape (M, 2, 2): z[:, axis, 0] is the low edge and
z[:, axis, 1] the high edge, axis 0 horizontal and 1 vertical.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import log_ndtr

from occtrack.densities import gaussian
from occtrack.jit import njit
from occtrack.models.aspect import AspectPrior, _aspect_update

H_EDGES = np.array([[1.0, 0.0, -1.0], [1.0, 0.0, 1.0]])
MIN_HEIGHT = 4.0  # px: the scale of a degenerate box


def heights(means: np.ndarray) -> np.ndarray:
    """Box height 2 s_vertical of states (..., 2, 3), at least MIN_HEIGHT px: the unit of the
    tracker's lengths."""
    return np.maximum(2.0 * means[..., 1, 2], MIN_HEIGHT)


def edges_from_ltwh(boxes: np.ndarray) -> np.ndarray:
    """(M, 4) left, top, width, height -> (M, 2, 2) edges."""
    return _edges_of_boxes(np.asarray(boxes, dtype=float).reshape(-1, 4))


def ltwh_from_edges(edges: np.ndarray) -> np.ndarray:
    """(..., 2, 2) edges -> (..., 4) left, top, width, height."""
    low, high = edges[..., 0], edges[..., 1]
    return np.concatenate([low, high - low], axis=-1)


def ltwh_from_states(means: np.ndarray) -> np.ndarray:
    """(K, 2, 3) states -> (K, 4) boxes."""
    c, s = means[..., 0], means[..., 2]
    return np.concatenate([c - s, 2.0 * s], axis=-1)


class BoxMeasurement:
    """The box measurement model of DESIGN section 2.2 for an image of `image_size` (W, H),
    edge noise `edge_noise` box heights."""

    H = H_EDGES

    def __init__(self, image_size: tuple[float, float], edge_noise: float = 0.069,
                 border_margin: float = 1.0, aspect: AspectPrior | None = None,
                 clutter_rate: float = 5.0, score_floor: float = 0.05,
                 clutter_score_power: float = 2.0):
        self.image_size = np.asarray(image_size, dtype=float)
        self.region_size = self.image_size  # the filter's survival region: the image
        self.clutter_rate = float(clutter_rate)
        self.score_floor = float(score_floor)
        self.clutter_score_power = float(clutter_score_power)
        self.edge_noise = float(edge_noise)
        self.border_margin = float(border_margin)
        self.aspect = aspect
        W, H = self.image_size
        self._border = np.array([[self.border_margin, W - self.border_margin],
                                 [self.border_margin, H - self.border_margin]])

    def learn(self, z: np.ndarray, observed: np.ndarray) -> None:
        """Learn from a frame's detections what the model learns online (the aspect ratio)."""
        if self.aspect is not None:
            self.aspect.learn(z, observed)

    def noise_std(self, means: np.ndarray) -> np.ndarray:
        """Edge noise std of each component, px (K,)."""
        return self.edge_noise * heights(means)

    def R(self, means: np.ndarray) -> np.ndarray:
        """Measurement noise covariance of each component, (K, 1, 2, 2) (both axes alike)."""
        return self.noise_std(means)[:, None, None, None] ** 2 * np.eye(2)

    def predicted_edges(self, means: np.ndarray) -> np.ndarray:
        """Each component's noise-free box edges, (K, 2, 2): H m (`_edges`)."""
        return _edges(means)

    def observed(self, z: np.ndarray) -> np.ndarray:
        """Which edges of measurements z (M, 2, 2) were measured (not on the border)."""
        W, H = self.image_size
        return _inside_margin(z, self.border_margin, W - self.border_margin,
                              H - self.border_margin)

    def clutter_density(self, z: np.ndarray, observed: np.ndarray,
                        scores: np.ndarray) -> np.ndarray:
        """kappa p_F(z_j) of each detection (M,): clutter_rate / (W H w h) / score^power
        (`config.TrackerConfig`): a false box falls anywhere in the image with a scale-free
        size; scores are clipped to [score_floor, 1] first."""
        W, H = self.image_size
        # (numpy's power, not libm's: they differ in the last bit)
        score_term = _clip(scores, self.score_floor, 1.0) ** (-self.clutter_score_power)
        return _box_clutter(z, score_term, self.clutter_rate, W * H)

    @staticmethod
    def gate_boxes(z: np.ndarray, observed: np.ndarray) -> np.ndarray:
        """Each detection's extent (M, 2, 2) for gating against `gates`: its box, an axis
        with both edges on the border unbounded (no gate on it)."""
        unmeasured = ~observed.any(axis=2)
        if unmeasured.any():
            z = z.copy()
            z[unmeasured] = [-np.inf, np.inf]
        return z

    def loglik(self, means: np.ndarray, covs: np.ndarray, z: np.ndarray,
               observed: np.ndarray) -> np.ndarray:
        """log p(z_j | component k) for all pairs, (K, M), censored edges included."""
        zhat, S, _ = gaussian.innovation(means, covs, self.H, self.R(means))
        out = gaussian.loglik_from_innovation(zhat, S, z, observed)
        if observed.all() or len(means) == 0:
            return out
        sd = np.sqrt(np.diagonal(S, axis1=-2, axis2=-1))
        border = np.stack([np.full(2, self.border_margin),
                           self.image_size - self.border_margin], axis=-1)
        sign = np.array([1.0, -1.0])
        log_peak = -0.5 * np.log(2.0 * np.pi * self.noise_std(means) ** 2)
        # log P(edge beyond border) per component, axis and edge: (K, 2, 2)
        beyond = log_ndtr(sign * (border - zhat) / sd) + log_peak[:, None, None]
        censored = ~observed
        rows = np.flatnonzero(censored.reshape(len(z), -1).any(axis=1))
        flat = censored[rows].reshape(len(rows), -1).astype(float)
        out[:, rows] += beyond.reshape(len(means), -1) @ flat.T
        return out

    def innovation(self, means: np.ndarray,
                   covs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predicted edges zhat (K, 2, 2) and innovation covariances S (K, 2, 2, 2):
        `gaussian.innovation` for this H, written out (`_innovation`)."""
        return _innovation(means, covs, self.edge_noise)

    @staticmethod
    def gates(zhat: np.ndarray, S: np.ndarray, sigmas: float) -> np.ndarray:
        """Each component's gate (K, 2, 2): its predicted box widened on each axis by `sigmas`
        standard deviations of that axis's less certain edge. The two axes are independent
        blocks and a Mahalanobis distance is at least any one coordinate's distance in its own
        standard deviations, so a detection whose box misses the gate lies more than `sigmas`
        standard deviations off on a measured edge (an axis with one edge on the border has
        the other measured): its log-likelihood is more than sigmas^2 / 2 below the best the
        component can give."""
        sd = np.sqrt(np.maximum(S[:, :, 0, 0], S[:, :, 1, 1]))
        low = np.minimum(zhat[..., 0], zhat[..., 1]) - sigmas * sd
        high = np.maximum(zhat[..., 0], zhat[..., 1]) + sigmas * sd
        return np.stack([low, high], axis=-1)

    def loglik_pairs(self, means: np.ndarray, zhat: np.ndarray, S: np.ndarray, z: np.ndarray,
                     observed: np.ndarray, k: np.ndarray, j: np.ndarray) -> np.ndarray:
        """log p(z_j | component k) of the pairs (k[e], j[e]) only, censored edges included:
        the numbers `loglik` gives for those pairs."""
        k, j = np.asarray(k, dtype=np.int64), np.asarray(j, dtype=np.int64)
        if _every_edge_measured(observed):
            return _loglik_pairs(zhat, S, z, observed, k, j, np.zeros((len(zhat), 0)),
                                 np.zeros(len(zhat)))
        # log P(edge beyond the border) of every component, as in `loglik`, on the edges
        # (axis, low or high) that some detection has on the border only
        W, H = self.image_size
        log_peak = -0.5 * np.log(2.0 * np.pi * self.noise_std(means) ** 2)
        scores = _beyond_scores(zhat, S, self.border_margin, W - self.border_margin,
                                H - self.border_margin, observed)
        return _loglik_pairs(zhat, S, z, observed, k, j, log_ndtr(scores), log_peak)

    def update_edges(self, means: np.ndarray, covs: np.ndarray, z: np.ndarray,
                     observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Kalman update of aligned (component, measurement) pairs with the measured edges:
        `gaussian.update` (Joseph form) written out for this H, element by element (see
        `_update_pairs`)."""
        new_means, new_covs = means.copy(), covs.copy()
        pairs = np.arange(len(means))
        _update_pairs(new_means, new_covs, pairs, z, observed, pairs, self.edge_noise)
        return new_means, new_covs

    def update(self, means: np.ndarray, covs: np.ndarray, z: np.ndarray,
               observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`update_rows` of aligned (component, measurement) pairs, on copies."""
        new_means, new_covs = means.copy(), covs.copy()
        pairs = np.arange(len(means))
        self.update_rows(new_means, new_covs, pairs, z, observed, pairs)
        return new_means, new_covs

    def update_rows(self, means: np.ndarray, covs: np.ndarray, rows: np.ndarray,
                    z: np.ndarray, observed: np.ndarray, measurement: np.ndarray) -> None:
        """The update, in place, of component rows[i] (distinct rows) by measurement
        measurement[i], the other components left as they are: the measured edges
        (`update_edges`), then what a detection cut by the border still says: the cut axis's
        half-size through the aspect ratio (`occtrack.models.aspect`, when given) and that
        each border edge lies beyond the border (`_beyond_update`, the censored likelihood
        `loglik` weighs the component by)."""
        rows = np.asarray(rows, dtype=np.int64)
        measurement = np.asarray(measurement, dtype=np.int64)
        moments = None if self.aspect is None else self.aspect.moments()
        mu, sigma = (0.0, 0.0) if moments is None else moments
        _update_rows(means, covs, rows, z, observed, measurement, self.edge_noise, self._border,
                     moments is not None, mu, sigma)


@njit
def _loglik_pairs(zhat, S, z, observed, k, j, log_phi, log_peak):
    """log N of the measured edges of z_j under component k, per pair, plus the log
    probability log_phi[k, c] + log_peak[k] of each edge on the border, c the edge's column
    among the censored ones (`_censored(observed)`, in (axis, low or high) order); S^-1 and
    the log-determinants in closed form per component and axis, once."""
    K = len(zhat)
    censored = _censored(observed)
    column = np.zeros((2, 2), dtype=np.int64)
    count = 0
    for axis in range(2):
        for side in range(2):
            if censored[axis, side]:
                column[axis, side] = count
                count += 1
    log_det, log_a, log_c = np.empty((K, 2)), np.empty((K, 2)), np.empty((K, 2))
    for i in range(K):
        for axis in range(2):
            a, b, c = S[i, axis, 0, 0], S[i, axis, 0, 1], S[i, axis, 1, 1]
            log_det[i, axis] = math.log(a * c - b * b) + 2.0 * gaussian.LOG_2PI
            log_a[i, axis] = math.log(a) + gaussian.LOG_2PI
            log_c[i, axis] = math.log(c) + gaussian.LOG_2PI
    out = np.empty(len(k))
    for e in range(len(k)):
        ke, je = k[e], j[e]
        total = 0.0
        for axis in range(2):
            a, b, c = S[ke, axis, 0, 0], S[ke, axis, 0, 1], S[ke, axis, 1, 1]
            o0, o1 = observed[je, axis, 0], observed[je, axis, 1]
            r0 = z[je, axis, 0] - zhat[ke, axis, 0]
            r1 = z[je, axis, 1] - zhat[ke, axis, 1]
            if o0 and o1:
                total += (c * r0 * r0 - 2.0 * b * r0 * r1 + a * r1 * r1) / (a * c - b * b) + (
                    log_det[ke, axis])
                continue
            if o0:
                total += r0 * r0 / a + log_a[ke, axis]
            else:
                total -= 2.0 * (log_phi[ke, column[axis, 0]] + log_peak[ke])
            if o1:
                total += r1 * r1 / c + log_c[ke, axis]
            else:
                total -= 2.0 * (log_phi[ke, column[axis, 1]] + log_peak[ke])
        out[e] = -0.5 * total
    return out


@njit
def _update_pairs(means, covs, rows, z, observed, measurement, edge_noise):
    """Kalman update, in place, of component rows[i] by measurement j = measurement[i], per
    axis. With u = P h0', w = P h1' (h0 = [1, 0, -1], h1 = [1, 0, 1] the edge rows, zero when
    the edge is not measured), S the innovation covariance and gains g0, g1 (the columns of
    P H' S^-1), the Joseph form (I - G H) P (I - G H)' + G R G' expands to
    P - g0 u' - u g0' - g1 w' - w g1' + g0 h0' + g1 h1',  h0 = S00 g0 + S01 g1,
    h1 = S01 g0 + S11 g1, which spares thousands of tiny matrix products in a crowd."""
    u, w, g0, g1, h0, h1 = (np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3),
                            np.empty(3))
    P, m = np.empty((3, 3)), np.empty(3)
    for i in range(len(rows)):
        k, j = rows[i], measurement[i]
        var = (edge_noise * max(2.0 * means[k, 1, 2], MIN_HEIGHT)) ** 2
        for axis in range(2):
            P[:] = covs[k, axis]
            m[:] = means[k, axis]
            m0 = 1.0 if observed[j, axis, 0] else 0.0
            m1 = 1.0 if observed[j, axis, 1] else 0.0
            for a in range(3):
                u[a] = (P[a, 0] - P[a, 2]) * m0
                w[a] = (P[a, 0] + P[a, 2]) * m1
            s00 = m0 * (P[0, 0] - 2.0 * P[0, 2] + P[2, 2] + var) + (1.0 - m0)
            s11 = m1 * (P[0, 0] + 2.0 * P[0, 2] + P[2, 2] + var) + (1.0 - m1)
            s01 = m0 * m1 * (P[0, 0] - P[2, 2])
            det = s00 * s11 - s01 * s01
            for a in range(3):
                g0[a] = (u[a] * s11 - w[a] * s01) / det
                g1[a] = (w[a] * s00 - u[a] * s01) / det
                h0[a] = g0[a] * s00 + g1[a] * s01
                h1[a] = g0[a] * s01 + g1[a] * s11
            r0 = (z[j, axis, 0] - m[0] + m[2]) * m0
            r1 = (z[j, axis, 1] - m[0] - m[2]) * m1
            for a in range(3):
                means[k, axis, a] = m[a] + g0[a] * r0 + g1[a] * r1
                for b in range(a, 3):
                    value = (P[a, b] - g0[a] * u[b] - u[a] * g0[b] - g1[a] * w[b]
                             - w[a] * g1[b] + g0[a] * h0[b] + g1[a] * h1[b])
                    covs[k, axis, a, b] = value
                    covs[k, axis, b, a] = value


@njit
def _edges_of_boxes(boxes):
    """(M, 4) left, top, width, height -> (M, 2, 2) edges [[left, right], [top, bottom]]."""
    out = np.empty((len(boxes), 2, 2))
    for j in range(len(boxes)):
        for axis in range(2):
            out[j, axis, 0] = boxes[j, axis]
            out[j, axis, 1] = boxes[j, axis] + boxes[j, 2 + axis]
    return out


@njit
def _inside_margin(z, margin, right, bottom):
    """Which edges of z (M, 2, 2) lie inside the image by more than the margin: a low edge
    above `margin`, a high one below `right` (x) or `bottom` (y)."""
    out = np.empty(z.shape, dtype=np.bool_)
    for j in range(len(z)):
        out[j, 0, 0] = z[j, 0, 0] > margin
        out[j, 1, 0] = z[j, 1, 0] > margin
        out[j, 0, 1] = z[j, 0, 1] < right
        out[j, 1, 1] = z[j, 1, 1] < bottom
    return out


@njit
def _censored(observed):
    """(2, 2): which edges (axis, low or high) some detection of `observed` (M, 2, 2) has on
    the border."""
    out = np.zeros((2, 2), dtype=np.bool_)
    for j in range(len(observed)):
        for axis in range(2):
            for side in range(2):
                if not observed[j, axis, side]:
                    out[axis, side] = True
    return out


@njit
def _every_edge_measured(observed):
    return not _censored(observed).any()


@njit
def _beyond_scores(zhat, S, margin, right, bottom, observed):
    """Standard scores (K, c) of the image border under the c censored edges
    (`_censored(observed)`, in (axis, low or high) order) of each predicted box: the edge lies
    beyond the border with probability Phi(score): (margin - zhat) / sd for a low edge,
    (zhat - right or bottom) / sd for a high one, sd the edge's standard deviation."""
    censored = _censored(observed)
    out = np.empty((len(zhat), censored.sum()))
    for k in range(len(zhat)):
        c = 0
        for axis in range(2):
            high = right if axis == 0 else bottom
            if censored[axis, 0]:
                out[k, c] = (margin - zhat[k, axis, 0]) / np.sqrt(S[k, axis, 0, 0])
                c += 1
            if censored[axis, 1]:
                out[k, c] = -(high - zhat[k, axis, 1]) / np.sqrt(S[k, axis, 1, 1])
                c += 1
    return out


@njit
def _edges(means):
    """H m per component and axis, H = [[1, 0, -1], [1, 0, 1]]: low edge c - s, high c + s."""
    out = np.empty((len(means), 2, 2))
    for k in range(len(means)):
        for axis in range(2):
            out[k, axis, 0] = means[k, axis, 0] - means[k, axis, 2]
            out[k, axis, 1] = means[k, axis, 0] + means[k, axis, 2]
    return out


@njit
def _innovation(means, covs, edge_noise):
    """zhat = H m and S = H P H' + R per component and axis, with H = [[1, 0, -1], [1, 0, 1]]
    (low edge c - s, high edge c + s) and R = (e h_k)^2 I."""
    K = len(means)
    zhat, S = np.empty((K, 2, 2)), np.empty((K, 2, 2, 2))
    for k in range(K):
        var = (edge_noise * max(2.0 * means[k, 1, 2], MIN_HEIGHT)) ** 2
        for axis in range(2):
            m, P = means[k, axis], covs[k, axis]
            zhat[k, axis, 0] = m[0] - m[2]
            zhat[k, axis, 1] = m[0] + m[2]
            S[k, axis, 0, 0] = P[0, 0] - P[0, 2] - P[2, 0] + P[2, 2] + var
            S[k, axis, 1, 1] = P[0, 0] + P[0, 2] + P[2, 0] + P[2, 2] + var
            S[k, axis, 0, 1] = P[0, 0] + P[0, 2] - P[2, 0] - P[2, 2]
            S[k, axis, 1, 0] = P[0, 0] - P[0, 2] + P[2, 0] - P[2, 2]
    return zhat, S


@njit
def _update_rows(means, covs, rows, z, observed, measurement, edge_noise, border, use_aspect,
                 mu, sigma):
    """`update_rows` in one call: the measured edges (`_update_pairs`), then `_cut_update`."""
    _update_pairs(means, covs, rows, z, observed, measurement, edge_noise)
    _cut_update(means, covs, rows, observed, measurement, edge_noise, border, use_aspect, mu,
                sigma)


@njit
def _cut_update(means, covs, rows, observed, measurement, edge_noise, border, use_aspect, mu,
                sigma):
    """`update_rows`' steps after the edges: the aspect ratio's
    (`occtrack.models.aspect._aspect_update`, when `use_aspect`), then `_beyond_update`."""
    if _every_edge_measured(observed):
        return
    if use_aspect:
        _aspect_update(means, covs, rows, observed, measurement, mu, sigma)
    _beyond_update(means, covs, rows, observed, measurement, edge_noise, border)


@njit
def _beyond_update(means, covs, rows, observed, measurement, edge_noise, border):
    """The moments of N(x; m, P) Phi(+-(h x - b) / sqrt(R)) for each border edge of measurement
    j (h its row of H, b the border it lies beyond: `border` (axis, low or high); + for a high
    edge, - for a low one), applied edge after edge. With s^2 = h P h' + R and
    alpha = +-(b - h m) / s, lambda = phi(alpha) / Phi(-alpha) (the inverse Mills ratio):
    m' = m +- P h' lambda / s and P' = P - P h' h P lambda (lambda - alpha) / s^2 (the probit
    update; Phi(-alpha) is the border edge's likelihood in `loglik`)."""
    u = np.empty(3)
    for i in range(len(rows)):
        k, j = rows[i], measurement[i]
        R = (edge_noise * max(2.0 * means[k, 1, 2], MIN_HEIGHT)) ** 2
        for axis in range(2):
            for side in range(2):
                if observed[j, axis, side]:
                    continue
                P, m = covs[k, axis], means[k, axis]
                sign = 1.0 if side == 1 else -1.0  # h = [1, 0, sign]
                for a in range(3):
                    u[a] = P[a, 0] + sign * P[a, 2]  # P h'
                s2 = u[0] + sign * u[2] + R
                s = math.sqrt(s2)
                alpha = sign * (border[axis, side] - (m[0] + sign * m[2])) / s
                tail = 0.5 * math.erfc(alpha / math.sqrt(2.0))  # Phi(-alpha)
                if tail < 1e-300:
                    continue
                lam = math.exp(-0.5 * alpha * alpha) / math.sqrt(2.0 * math.pi) / tail
                shrink = lam * (lam - alpha) / s2
                for a in range(3):
                    m[a] += sign * u[a] * lam / s
                for a in range(3):
                    for b in range(3):
                        P[a, b] -= u[a] * u[b] * shrink


@njit
def _box_clutter(z, score_term, rate, area):
    """`BoxMeasurement.clutter_density`: rate / (W H w h) * score_term per detection, W H
    the image's `area` and score^-power given as `score_term`."""
    out = np.empty(len(z))
    for j in range(len(z)):
        size = max((z[j, 0, 1] - z[j, 0, 0]) * (z[j, 1, 1] - z[j, 1, 0]), 1.0)
        out[j] = rate / (area * size) * score_term[j]
    return out


@njit
def _clip(x, low, high):
    """np.clip(x, low, high) as a new array (numpy's clip costs more than the loop here)."""
    out = np.empty_like(x)
    for i in range(len(x)):
        out[i] = min(max(x[i], low), high)
    return out
