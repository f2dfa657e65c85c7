"""The three highway occlusion handlers, behind the shared `OcclusionModel` interface.

Each returns, for every particle (of a track or of the undetected intensity), its visibility v
and hidden-measurement probability q (see `occtrack.occlusion.base`): hit = w P_D v p(z | x),
miss = w (1 - P_D v + P_D v q). Particles arrive flat, with their owner track (-1: undetected
intensity) and lane in a `HighwayContext`.

- measurement-wise (v = 1): q is the exact probability that the particle's own noisy shape would
  fall wholly inside a part hidden by the measured shapes of the nearer lanes (normal CDFs of
  each end against each hidden part; `MeasurementModel.hidden_probability`). No term couples
  the tracks.
- object-wise-expval (q = 0): the static, expected-value approximation. Each track i of a nearer
  lane is replaced by its expected extent [A_l, A_r] (angles) and hides a particle with angles
  [a_l, a_r] with probability r_i (1 - exp(-beta cover_l)) (1 - exp(-beta cover_r)), where
  cover_l = a_l - A_l and cover_r = A_r - a_r when both are positive (0 otherwise); occluders
  combine as a product, v = max(prod_i (1 - r_i P_i), v_min) (Granstrom's floor).
- object-wise-grid (q = 0): the sensor's angles cut into `grid_cells` cells; a cell is open with
  probability prod_i (1 - r_i P(track i covers the cell)) over the tracks of nearer lanes, from
  their particles; a particle is as visible as the best cell it covers (range maximum over its
  cells, from a sparse table).

The undetected intensity (owner -1) is hidden by tracks but hides nothing in the object-wise
handlers, as in the authors' prototype.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.occlusion.base import OcclusionContext, OcclusionTerms


@dataclass(frozen=True)
class HighwayContext(OcclusionContext):
    """OcclusionContext plus the lane (0 = nearest) of every particle. `means` are particles
    (left end, length, signed velocity); `measurement_model` is a highway MeasurementModel."""

    lane: np.ndarray | None = None


def _ends(ctx: HighwayContext) -> tuple[np.ndarray, np.ndarray]:
    left = ctx.means[:, 0]
    return left, left + ctx.means[:, 1]


class MeasurementWise:
    name = "measurement-wise"

    def __init__(self, config=None):
        pass

    def terms(self, ctx: HighwayContext) -> OcclusionTerms:
        model = ctx.measurement_model
        left, right = _ends(ctx)
        k = len(left)
        q = np.zeros(k)
        parts = model.occluded_parts(ctx.measurements)
        lo = np.concatenate([p[0] for p in parts])
        if k == 0 or len(lo) == 0:
            return OcclusionTerms(np.ones(k), q)
        hi = np.concatenate([p[1] for p in parts])
        count = np.array([len(p[0]) for p in parts])
        # Skip runs (a track; one lane's undetected part) whose hull no hidden part can hold:
        # q > 0 needs a part with low <= left + reach and high >= right - reach.
        reach = model.tail * model.sigma
        start, size = _runs(ctx.owner * len(parts) + ctx.lane)
        run_lane = ctx.lane[start]
        shift = 1e3 * (max(np.abs(lo).max(), np.abs(hi).max(), np.abs(left).max(),
                           np.abs(right).max()) + reach)
        offset = shift * np.repeat(np.arange(len(parts)), count)
        below = np.searchsorted(lo + offset, np.maximum.reduceat(left, start) + reach
                                + shift * run_lane, side="right")
        above = np.searchsorted(hi + offset, np.minimum.reduceat(right, start) - reach
                                + shift * run_lane)
        keep = above < below
        if keep.any():
            count_k = size[keep]
            at = (np.repeat(start[keep] - np.cumsum(count_k) + count_k, count_k)
                  + np.arange(count_k.sum()))
            q[at] = model.hidden_probability(ctx.lane[at], left[at], right[at],
                                             ctx.measurements, parts)
        return OcclusionTerms(np.ones(k), q)


def _track_extents(ctx: HighwayContext, distances: np.ndarray):
    """Existence, lane and expected extent (angles) of each track."""
    left, right = _ends(ctx)
    tracked = ctx.owner >= 0
    owner, w = ctx.owner[tracked], ctx.weights[tracked]
    n = len(ctx.existence)
    total = np.maximum(np.bincount(owner, w, n), np.finfo(float).tiny)
    lane = np.zeros(n, np.int64)
    lane[owner] = ctx.lane[tracked]
    d = distances[lane]
    a_left = np.bincount(owner, w * left[tracked], n) / total / d
    a_right = np.bincount(owner, w * right[tracked], n) / total / d
    return np.asarray(ctx.existence, float), lane, a_left, a_right


class ObjectWiseExpval:
    name = "object-wise-expval"

    def __init__(self, config):
        self.sharpness = float(config.expval_sharpness)
        self.min_visible = float(config.expval_min_visible)

    def terms(self, ctx: HighwayContext) -> OcclusionTerms:
        distances = ctx.measurement_model.distances
        left, right = _ends(ctx)
        k = len(left)
        r, occ_lane, occ_l, occ_r = _track_extents(ctx, distances)
        if len(r) == 0 or k == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        d = distances[ctx.lane]
        a_l, a_r = left / d, right / d
        # Runs of particles sharing owner and lane (a track; the Poisson part of one lane):
        # an occluder is scored only against the runs whose hull it could cover.
        start, size = _runs(ctx.owner * len(distances) + ctx.lane)
        run_lane = ctx.lane[start]
        max_l = np.maximum.reduceat(a_l, start)
        min_r = np.minimum.reduceat(a_r, start)
        cand = ((occ_lane[None, :] < run_lane[:, None]) & (occ_l[None, :] < max_l[:, None])
                & (occ_r[None, :] > min_r[:, None]))
        run, occ = np.nonzero(cand)
        if len(run) == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        count = size[run]
        first = np.repeat(start[run] - np.cumsum(count) + count, count)
        p = first + np.arange(count.sum())
        i = np.repeat(occ, count)
        cover_l = a_l[p] - occ_l[i]
        cover_r = occ_r[i] - a_r[p]
        hit = (cover_l > 0) & (cover_r > 0)
        p, i, cover_l, cover_r = p[hit], i[hit], cover_l[hit], cover_r[hit]
        beta = self.sharpness
        hidden = r[i] * (-np.expm1(-beta * cover_l)) * (-np.expm1(-beta * cover_r))
        log_open = np.bincount(p, np.log1p(-np.minimum(hidden, 1.0 - 1e-12)), k)
        return OcclusionTerms(np.maximum(np.exp(log_open), self.min_visible), np.zeros(k))


class ObjectWiseGrid:
    name = "object-wise-grid"

    def __init__(self, config):
        self.cells = int(config.grid_cells)
        road = config.road
        # Widest angle a car of the second lane can reach (the first is never hidden).
        reach = road.half_length + config.max_length + 3.0 * config.noise_std
        second = road.distances[min(1, road.n_lanes - 1)]
        self.centres = np.linspace(-reach / second, reach / second, self.cells)

    def _cover(self, a_l: np.ndarray, a_r: np.ndarray):
        """First and last cell whose centre lies inside each angular interval (first > last
        when it covers none), clipped to the grid."""
        c0, step = self.centres[0], self.centres[1] - self.centres[0]
        first = np.ceil((a_l - c0) / step).astype(np.int64)
        last = np.floor((a_r - c0) / step).astype(np.int64)
        return np.maximum(first, 0), np.minimum(last, self.cells - 1)

    def terms(self, ctx: HighwayContext) -> OcclusionTerms:
        distances = ctx.measurement_model.distances
        n_lanes = len(distances)
        left, right = _ends(ctx)
        k = len(left)
        d = distances[ctx.lane]
        a_l, a_r = left / d, right / d
        first, last = self._cover(a_l, a_r)
        n = len(ctx.existence)
        cells = self.cells
        log_open = np.zeros((n_lanes, cells))
        tracked = ctx.owner >= 0
        if n:
            owner = ctx.owner[tracked]
            f, g, w = first[tracked], last[tracked], ctx.weights[tracked]
            some = f <= g
            owner, f, g, w = owner[some], f[some], g[some], w[some]
            width = cells + 1
            diff = (np.bincount(owner * width + f, w, n * width)
                    - np.bincount(owner * width + g + 1, w, n * width))
            covered = np.cumsum(diff.reshape(n, width), axis=1)[:, :cells]
            total = np.maximum(np.bincount(ctx.owner[tracked], ctx.weights[tracked], n),
                               np.finfo(float).tiny)
            p_cover = np.clip(covered / total[:, None], 0.0, 1.0)
            r = np.asarray(ctx.existence, float)
            lane = np.zeros(n, np.int64)
            lane[ctx.owner[tracked]] = ctx.lane[tracked]
            per_track = np.log1p(-np.minimum(r[:, None] * p_cover, 1.0 - 1e-12))
            np.add.at(log_open, lane, per_track)
        # Open probability seen from lane k: occluders in lanes 0 .. k-1 only.
        behind = np.cumsum(log_open, axis=0) - log_open
        open_ = np.exp(behind)
        # A particle covering no cell centre reads the cell nearest its middle.
        none = first > last
        if none.any():
            c0, step = self.centres[0], self.centres[1] - self.centres[0]
            mid = np.rint((0.5 * (a_l[none] + a_r[none]) - c0) / step).astype(np.int64)
            first[none] = last[none] = np.clip(mid, 0, cells - 1)
        visible = np.ones(k)
        # Only runs (a track; one lane's undetected part) covering a cell that is not exactly
        # open need reading; the others read exactly 1.
        start, size = _runs(ctx.owner * n_lanes + ctx.lane)
        shut = np.zeros((n_lanes, cells + 1), np.int64)
        np.cumsum(open_ != 1.0, axis=1, out=shut[:, 1:])
        run_lane = ctx.lane[start]
        lo = np.minimum.reduceat(first, start)
        hi = np.maximum.reduceat(last, start)
        keep = shut[run_lane, hi + 1] > shut[run_lane, lo]
        if not keep.any():
            return OcclusionTerms(visible, np.zeros(k))
        count = size[keep]
        at = np.repeat(start[keep] - np.cumsum(count) + count, count) + np.arange(count.sum())
        first, last, lane = first[at], last[at], ctx.lane[at]
        table = _sparse_max(open_)
        level = np.floor(np.log2(last - first + 1)).astype(np.int64)
        seen = np.maximum(table[level, lane, first], table[level, lane, last - (1 << level) + 1])
        outside = (a_r[at] < self.centres[0]) | (a_l[at] > self.centres[-1])
        visible[at] = np.where(outside, 1.0, seen)
        return OcclusionTerms(visible, np.zeros(k))


def _runs(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and length of each run of equal keys."""
    start = np.flatnonzero(np.diff(key)) + 1
    start = np.concatenate(([0], start))
    return start, np.diff(np.concatenate((start, [len(key)])))


def _sparse_max(values: np.ndarray) -> np.ndarray:
    """table[j, :, i] = max(values[:, i : i + 2^j]) for range-maximum queries in O(1)."""
    n = values.shape[-1]
    levels = max(1, int(np.floor(np.log2(n))) + 1)
    table = np.empty((levels,) + values.shape)
    table[0] = values
    for j in range(1, levels):
        half = 1 << (j - 1)
        table[j] = table[j - 1]
        table[j, ..., : n - half] = np.maximum(table[j - 1, ..., : n - half],
                                               table[j - 1, ..., half:])
    return table


OCCLUSION_MODELS = {
    MeasurementWise.name: MeasurementWise,
    ObjectWiseExpval.name: ObjectWiseExpval,
    ObjectWiseGrid.name: ObjectWiseGrid,
}
TRACKER_NAMES = tuple(OCCLUSION_MODELS)


def make_occlusion(name: str, config):
    """The handler called `name`, set up from a TrackerConfig."""
    try:
        return OCCLUSION_MODELS[name](config)
    except KeyError:
        raise OcctrackError(f"unknown occlusion handler {name!r}; choose from "
                            f"{', '.join(TRACKER_NAMES)}") from None
