"""Occlusion of ground-plane boxes seen from a sensor: nearer boxes hide the angles behind them.

The highway's model (`occtrack.occlusion.extents`, the paper's appendix) in the open plane: a
box on the ground covers, from the sensor at position o, the angular interval [a_lo, a_hi]
spanned by its four corners, at the range d of its centre. Box B hides box A with probability

    p(A hidden by B) = clip(gain * |[a_lo, a_hi]_A & [a_lo, a_hi]_B| / (a_hi - a_lo)_A, 0, 1)
                       * ramp((d_A - d_B) / depth_B)

the angular share of A behind B, as the image boxes' geometry takes the share of area
(`occtrack.occlusion.box_geometry`, the same gain and ramp), times the ramp that makes only a
nearer box an occluder (depth_B: B's longer side, the measure of "nearer" as the box height is
in the image). Several occluders combine as 1 - prod(1 - p). The same three models as the image
boxes: `none`, object-wise (each object's mean box, weighted by its existence, hides the
others' components: paper eq. "misstermOWO" with the expected-value approximation) and
measurement-wise (the seen boxes hide each component's would-be box, and each other: paper eq.
"new_individual_MM").

Only pairs whose angular intervals overlap can interact: they are found by sorting the
intervals (`occtrack.spatial.overlapping_pairs` on the intervals), so the cost follows the
overlaps rather than K N. Boxes are edge arrays (K, 2, 2) in the filter's frame: [axis,
low/high], axis 0 the ground's x and 1 its z (`occtrack.tracker.ground`). The sensor's
position `sensor` (2,) is in that frame; the ground tracker keeps it there.

Hand-written: no library computes occlusion between boxes from a sensor's point of view in a
form a filter's miss term takes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from occtrack.occlusion._occlusion import _occluder_boxes
from occtrack.occlusion.base import OcclusionContext, OcclusionTerms
from occtrack.spatial import DENSE_PAIRS, overlapping_pairs

TWO_PI = 2.0 * np.pi


def _corners(boxes: np.ndarray) -> np.ndarray:
    """(K, 4, 2) corners of edge boxes (K, 2, 2)."""
    x, z = boxes[:, 0], boxes[:, 1]
    return np.stack([np.stack([x[:, i], z[:, j]], axis=-1)
                     for i, j in ((0, 0), (0, 1), (1, 0), (1, 1))], axis=1)


@dataclass
class SensorViewGeometry:
    """When one ground box hides another, seen from `sensor` (see the module)."""

    gain: float = 2.0
    ramp_zero: float = -0.1
    ramp_one: float = 0.25
    sensor: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def __post_init__(self) -> None:
        if self.gain <= 0:
            raise ValueError("occlusion gain must be positive")
        if not self.ramp_one > self.ramp_zero:
            raise ValueError("occlusion ramp must rise: ramp_one > ramp_zero")
        self.sensor = np.asarray(self.sensor, dtype=float).reshape(2)

    def view(self, boxes: np.ndarray) -> tuple[np.ndarray, ...]:
        """Each box's angular interval (lo, hi), radians, around its centre's bearing (so an
        interval may run past +-pi; at most pi wide), its centre's range and its depth."""
        boxes = np.asarray(boxes, dtype=float).reshape(-1, 2, 2)
        centre = boxes.mean(axis=2) - self.sensor
        bearing = np.arctan2(centre[:, 1], centre[:, 0])
        rel = _corners(boxes) - self.sensor
        delta = np.arctan2(rel[..., 1], rel[..., 0]) - bearing[:, None]
        delta = (delta + np.pi) % TWO_PI - np.pi
        half = np.minimum(np.maximum(-delta.min(axis=1), delta.max(axis=1)), np.pi / 2)
        lo = bearing + np.maximum(delta.min(axis=1), -half)
        hi = bearing + np.minimum(delta.max(axis=1), half)
        depth = np.maximum((boxes[:, :, 1] - boxes[:, :, 0]).max(axis=1), 1e-9)
        return lo, hi, np.hypot(centre[:, 0], centre[:, 1]), depth

    def hides(self, a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...], i: np.ndarray,
              j: np.ndarray) -> np.ndarray:
        """p(box i of view a hidden by box j of view b) for the pairs (i[e], j[e])."""
        a_lo, a_hi, a_d, _ = (x[i] for x in a)
        b_lo, b_hi, b_d, b_depth = (x[j] for x in b)
        overlap = np.zeros(len(i))
        for turn in (-TWO_PI, 0.0, TWO_PI):  # the same angles a turn apart
            overlap = np.maximum(overlap, np.minimum(a_hi, b_hi + turn)
                                 - np.maximum(a_lo, b_lo + turn))
        width = np.maximum(a_hi - a_lo, 1e-12)
        share = np.clip(self.gain * np.maximum(overlap, 0.0) / width, 0.0, 1.0)
        ramp = np.clip(((a_d - b_d) / b_depth - self.ramp_zero)
                       / (self.ramp_one - self.ramp_zero), 0.0, 1.0)
        return share * ramp

    def _pairs(self, a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...],
               dense: bool) -> tuple[np.ndarray, np.ndarray]:
        K, N = len(a[0]), len(b[0])
        if dense or K * N <= DENSE_PAIRS:
            i, j = np.divmod(np.arange(K * N), max(N, 1))
            return i, j
        # intervals as boxes of one unit's height; an interval near +-pi is also tried a
        # turn away, so wrapped overlaps are found
        def boxes(lo, hi):
            unit = np.broadcast_to([0.0, 1.0], (len(lo), 2))
            return np.stack([np.stack([lo, hi], axis=-1), unit], axis=1)
        found = [overlapping_pairs(boxes(a[0], a[1]), boxes(b[0] + turn, b[1] + turn))
                 for turn in (-TWO_PI, 0.0, TWO_PI)]
        i = np.concatenate([f[0] for f in found])
        j = np.concatenate([f[1] for f in found])
        key = np.unique(i * N + j)
        return np.divmod(key, N)

    def visible(self, hidden: np.ndarray, occluders: np.ndarray,
                weights: np.ndarray | None = None, skip: np.ndarray | None = None,
                dense: bool = False) -> np.ndarray:
        """prod_n (1 - w_n p[k, n]) for each box k: the probability that no occluder hides
        it, occluder n counting with weight w_n (1 when None), never the occluder skip[k]
        (-1: none)."""
        a, b = self.view(hidden), self.view(occluders)
        K = len(a[0])
        if K == 0 or len(b[0]) == 0:
            return np.ones(K)
        i, j = self._pairs(a, b, dense)
        p = self.hides(a, b, i, j)
        if weights is not None:
            p = p * np.asarray(weights, dtype=float)[j]
        if skip is not None:
            p = np.where(np.asarray(skip)[i] == j, 0.0, p)
        log_visible = np.bincount(i, weights=np.log1p(-np.minimum(p, 1.0 - 1e-15)),
                                  minlength=K)
        return np.exp(log_visible)


class SensorViewObjectWise:
    """Object-wise occlusion seen from the sensor (expected-value approximation): each
    object's mean box, weighted by its existence r_i (objects with r_i above `min_existence`),
    hides the other objects' components; an object never hides itself and the Poisson part
    hides nothing."""

    name = "object-wise"

    def __init__(self, geometry: SensorViewGeometry | None = None,
                 min_existence: float = 0.1):
        self.geometry = geometry or SensorViewGeometry()
        self.min_existence = float(min_existence)

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        K = len(ctx.means)
        r = np.asarray(ctx.existence, dtype=float)
        occluders = np.flatnonzero(r > self.min_existence)
        if K == 0 or len(occluders) == 0:
            return OcclusionTerms(np.ones(K), np.zeros(K))
        # each occluder's mean box and each component's own object among them: the image
        # boxes' kernel (`occtrack.occlusion.box_objectwise`), as the edges have the same layout
        boxes = np.ascontiguousarray(ctx.measurement_model.predicted_edges(ctx.means),
                                     dtype=float)
        mean_boxes, own = _occluder_boxes(
            boxes, np.ascontiguousarray(ctx.weights, dtype=float),
            np.ascontiguousarray(ctx.owner, dtype=np.int64), occluders)
        visible = self.geometry.visible(boxes, mean_boxes, weights=r[occluders], skip=own,
                                        dense=not ctx.gating)
        return OcclusionTerms(visible, np.zeros(K))


class SensorViewMeasurementWise:
    """Measurement-wise occlusion seen from the sensor: the boxes that were seen hide each
    component's would-be box (q_k, at its predicted box) and each other (h_j)."""

    name = "measurement-wise"

    def __init__(self, geometry: SensorViewGeometry | None = None):
        self.geometry = geometry or SensorViewGeometry()

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        K, z = len(ctx.means), ctx.measurements
        if len(z) == 0:
            return OcclusionTerms(np.ones(K), np.zeros(K), np.zeros(0))
        boxes = ctx.measurement_model.predicted_edges(ctx.means) if K else np.zeros((0, 2, 2))
        g, dense = self.geometry, not ctx.gating
        hidden = 1.0 - g.visible(boxes, z, dense=dense)
        seen_hidden = 1.0 - g.visible(z, z, skip=np.arange(len(z)), dense=dense)
        return OcclusionTerms(np.ones(K), hidden, seen_hidden)


def sensor_view_occlusion(name: str, geometry: SensorViewGeometry,
                          min_existence: float = 0.1):
    """The sensor-view occlusion model called `name`: none, object-wise or measurement-wise."""
    from occtrack.occlusion.base import NoOcclusion

    models = {"none": lambda: NoOcclusion(),
              "object-wise": lambda: SensorViewObjectWise(geometry, min_existence),
              "measurement-wise": lambda: SensorViewMeasurementWise(geometry)}
    if name not in models:
        raise ValueError(f"unknown occlusion model {name!r}; choose from "
                         f"{', '.join(models)}")
    return models[name]()
