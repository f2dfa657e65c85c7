"""Image boxes measured by their edges, with edges on the image border left unmeasured.

State per image axis (horizontal, vertical): centre c, velocity v, half-size s. A box's edges
are linear in it,

    low edge = c - s,  high edge = c + s,   H = [[1, 0, -1], [1, 0, 1]],  R_k = (e h_k)^2 I

with e the noise of each edge in units of the box's height h_k = 2 s_vertical of component k
(the paper's 12 px is e = 0.069 at MOT17-04's median height of 175 px): a detector's error
grows with the object's image size, so one e serves near and far people and every camera.
A detector that clips boxes to the image puts the cut edge on the border (within `border_margin`
pixels), which says only that the true edge is at or beyond it: the likelihood of a border edge is
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

A detector that does not clip (YOLOX, trained on MOT17's labels, which run on past the image)
places an edge beyond the border: its estimate of the part the image does not show, not a cut.
Such an edge (beyond the border by more than the margin) is measured like any other
(`extrapolated_edges`; off: censored like a border edge, for a detector that pads the image).
Measured against the labels on MOT17's YOLOX boxes, those edges' robust spread is .03 to .06
box heights against .015 to .026 for edges inside the image, both under the edge noise (.069):
one noise serves both. Censored, a person taller than the image, cut at the top and bottom and
on one side, was tracked by one edge; the rest drifted and the track lost the person.

Measurements travel as edge arrays z of shape (M, 2, 2): z[:, axis, 0] is the low edge and
z[:, axis, 1] the high edge, axis 0 horizontal and 1 vertical.
"""

from __future__ import annotations

import numpy as np

from occtrack.densities import gaussian
from occtrack.models._models import (  # noqa: F401 (_beyond_update, _censored, _cut_update: tests)
    _beyond_scores,
    _beyond_update,
    _box_clutter,
    _censored,
    _clip,
    _cut_update,
    _edges,
    _edges_of_boxes,
    _every_edge_measured,
    _innovation,
    _loglik_pairs,
    _measured_edges,
    _update_pairs,
    _update_rows,
)
from occtrack.models.aspect import AspectPrior
from occtrack.models.edge_tail import EdgeTail

H_EDGES = np.array([[1.0, 0.0, -1.0], [1.0, 0.0, 1.0]])
MIN_HEIGHT = 4.0  # px: the scale of a degenerate box


def _log_ndtr(x: np.ndarray) -> np.ndarray:
    """scipy.special.log_ndtr, imported on the first frame rather than with the tracker:
    scipy.special alone takes longer to import (0.15 s) than the rest of `occtrack.Tracker`."""
    from scipy.special import log_ndtr

    return log_ndtr(x)


def heights(means: np.ndarray) -> np.ndarray:
    """Box height 2 s_vertical of states (..., 2, 3), at least MIN_HEIGHT px: the unit of the
    tracker's lengths."""
    return np.maximum(2.0 * means[..., 1, 2], MIN_HEIGHT)


def edges_from_ltwh(boxes: np.ndarray) -> np.ndarray:
    """(M, 4) left, top, width, height -> (M, 2, 2) edges."""
    return _edges_of_boxes(np.ascontiguousarray(boxes, dtype=float).reshape(-1, 4))


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
                 clutter_score_power: float = 2.0, tail: EdgeTail | None = None,
                 extrapolated_edges: bool = True):
        self.image_size = np.asarray(image_size, dtype=float)
        self.region_size = self.image_size  # the filter's survival region: the image
        self.clutter_rate = float(clutter_rate)
        self.score_floor = float(score_floor)
        self.clutter_score_power = float(clutter_score_power)
        self.edge_noise = float(edge_noise)
        self.border_margin = float(border_margin)
        self.extrapolated_edges = bool(extrapolated_edges)
        # a learnt score term (`models.score_model.ScoreLearner`) in place of score^-power
        self.score_model = None
        self.aspect = aspect
        self.tail = tail  # a heavy tail of the edges' likelihood (`models.edge_tail`); None: none
        self._labelled: np.ndarray | None = None  # its components (`tracked_components`)
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
        """Which edges of measurements z (M, 2, 2) were measured: all but those on the border
        (and, without `extrapolated_edges`, those beyond it)."""
        W, H = self.image_size
        return _measured_edges(z, self.border_margin, W, H, self.extrapolated_edges)

    def clutter_density(self, z: np.ndarray, observed: np.ndarray,
                        scores: np.ndarray) -> np.ndarray:
        """kappa p_F(z_j) of each detection (M,): clutter_rate / (W H w h) / score^power
        (`config.TrackerConfig`): a false box falls anywhere in the image with a scale-free
        size; scores are clipped to [score_floor, 1] first."""
        W, H = self.image_size
        if self.score_model is not None:
            score_term = np.ascontiguousarray(self.score_model.score_term(scores), dtype=float)
        else:  # (numpy's power, not libm's: they differ in the last bit)
            score_term = _clip(np.ascontiguousarray(scores, dtype=float), self.score_floor,
                               1.0) ** (-self.clutter_score_power)
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
        """log p(z_j | component k) for all pairs, (K, M), censored edges and the tail
        included (every component's: this dense form is told no labels)."""
        zhat, S, _ = gaussian.innovation(means, covs, self.H, self.R(means))
        out = gaussian.loglik_from_innovation(zhat, S, z, observed)
        if self.tail is not None and out.size:
            k, j = np.divmod(np.arange(out.size), len(z))
            out = out + self.tail.correction(zhat, S, z, observed, k, j).reshape(out.shape)
        if observed.all() or len(means) == 0:
            return out
        sd = np.sqrt(np.diagonal(S, axis1=-2, axis2=-1))
        border = np.stack([np.full(2, self.border_margin),
                           self.image_size - self.border_margin], axis=-1)
        sign = np.array([1.0, -1.0])
        log_peak = -0.5 * np.log(2.0 * np.pi * self.noise_std(means) ** 2)
        # log P(edge beyond border) per component, axis and edge: (K, 2, 2)
        beyond = _log_ndtr(sign * (border - zhat) / sd) + log_peak[:, None, None]
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
        tail = self.tail
        extra = ()
        if tail is not None:  # the heavy tail, added by the kernel (`models.edge_tail`)
            # (d^2 and m come back only for a tail that learns from them)
            d2, m = (np.empty(len(k)), np.empty(len(k))) if tail.learning else (None, None)
            labelled = self._labelled
            if labelled is not None and len(labelled) != len(zhat):
                labelled = None  # (not this frame's components: the tail for every one)
            extra = (tail.weight, tail.scale, d2, m, labelled)
        if _every_edge_measured(observed):
            out = _loglik_pairs(zhat, S, z, observed, k, j, np.zeros((len(zhat), 0)),
                                np.zeros(len(zhat)), *extra)
        else:
            # log P(edge beyond the border) of every component, as in `loglik`, on the edges
            # (axis, low or high) that some detection has on the border only
            W, H = self.image_size
            log_peak = -0.5 * np.log(2.0 * np.pi * self.noise_std(means) ** 2)
            scores = _beyond_scores(zhat, S, self.border_margin, W - self.border_margin,
                                    H - self.border_margin, observed)
            out = _loglik_pairs(zhat, S, z, observed, k, j, _log_ndtr(scores), log_peak,
                                *extra)
        if tail is not None:
            if tail.learning:
                tail.remember(k, j, d2, m)
            self._labelled = None
        return out

    def tracked_components(self, labelled: np.ndarray) -> None:
        """The filter's components of tracked objects, `labelled` (K,) bool, for the next
        `loglik_pairs`: only theirs take the heavy tail (`models.edge_tail`)."""
        self._labelled = np.ascontiguousarray(labelled, dtype=bool)

    def learn_association(self, label: np.ndarray, taken: np.ndarray, confirmed: np.ndarray,
                          dt: float) -> None:
        """Learn from the detections the confirmed tracks took this frame (the tail's
        weight, `models.edge_tail`)."""
        if self.tail is not None:
            self.tail.learn(label, taken, confirmed, dt)

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
