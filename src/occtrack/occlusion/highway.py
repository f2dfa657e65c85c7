"""The highway trackers' three occlusion handlers, behind the shared `OcclusionModel` interface.

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
  their particles; a particle is as visible as the best cell it covers.

The undetected intensity (owner -1) is hidden by tracks but hides nothing in the object-wise
handlers, as in the authors' prototype. The object-wise handlers' loops are compiled
(`occtrack.occlusion.extent_kernels`, from `_occlusion.pyx`), loaded when a handler first runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.occlusion.base import OcclusionContext, OcclusionTerms


@dataclass(frozen=True)
class HighwayContext(OcclusionContext):
    """OcclusionContext plus the lane (0 = nearest) of every particle. `means` are particles
    (left end, length, signed velocity); `measurement_model` is a highway MeasurementModel.
    The tracker passes views of its own arrays (no copy a step): they hold during `terms`
    only, and a handler must not write to them."""

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
        q = model.hidden_probability(ctx.lane, left, right, ctx.measurements)
        return OcclusionTerms(np.ones(len(left)), q)


def _angles(ctx: HighwayContext, distances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    left, right = _ends(ctx)
    d = distances[ctx.lane]
    return left / d, right / d


def _track_extents(ctx: HighwayContext, distances: np.ndarray):
    """Existence, lane and expected extent (angles) of each track."""
    from occtrack.occlusion.extent_kernels import track_extents

    a_l, a_r = _angles(ctx, distances)
    lane, a_left, a_right = track_extents(np.asarray(ctx.owner, np.int64),
                                          np.asarray(ctx.lane, np.int64),
                                          np.asarray(ctx.weights, float), a_l, a_r,
                                          len(ctx.existence))
    return np.asarray(ctx.existence, float), lane, a_left, a_right


class ObjectWiseExpval:
    name = "object-wise-expval"

    def __init__(self, config):
        self.sharpness = float(config.expval_sharpness)
        self.min_visible = float(config.expval_min_visible)

    def terms(self, ctx: HighwayContext) -> OcclusionTerms:
        from occtrack.occlusion.extent_kernels import expval_visibility

        distances = ctx.measurement_model.distances
        k = len(ctx.owner)
        r, occ_lane, occ_l, occ_r = _track_extents(ctx, distances)
        if len(r) == 0 or k == 0:
            return OcclusionTerms(np.ones(k), np.zeros(k))
        a_l, a_r = _angles(ctx, distances)
        visible = expval_visibility(np.asarray(ctx.owner, np.int64),
                                    np.asarray(ctx.lane, np.int64), a_l, a_r, r, occ_lane,
                                    occ_l, occ_r, self.sharpness, self.min_visible)
        return OcclusionTerms(visible, np.zeros(k))


class ObjectWiseGrid:
    name = "object-wise-grid"

    def __init__(self, config):
        self.cells = int(config.grid_cells)
        road = config.road
        # Widest angle a car of the second lane can reach (the first is never hidden).
        reach = road.half_length + config.max_length + 3.0 * config.noise_std
        second = road.distances[min(1, road.n_lanes - 1)]
        self.centres = np.linspace(-reach / second, reach / second, self.cells)

    def terms(self, ctx: HighwayContext) -> OcclusionTerms:
        from occtrack.occlusion.extent_kernels import grid_visibility

        distances = ctx.measurement_model.distances
        a_l, a_r = _angles(ctx, distances)
        centres = self.centres
        visible = grid_visibility(np.asarray(ctx.owner, np.int64),
                                  np.asarray(ctx.lane, np.int64),
                                  np.asarray(ctx.weights, float), a_l, a_r,
                                  np.asarray(ctx.existence, float), len(ctx.existence),
                                  len(distances), centres[0], centres[1] - centres[0],
                                  centres[-1], self.cells)
        return OcclusionTerms(visible, np.zeros(len(a_l)))


OCCLUSION_MODELS = {
    MeasurementWise.name: MeasurementWise,
    ObjectWiseExpval.name: ObjectWiseExpval,
    ObjectWiseGrid.name: ObjectWiseGrid,
}
TRACKER_NAMES = tuple(OCCLUSION_MODELS)


def make_occlusion(name: str, config):
    """The handler called `name`, set up from a HighwayTrackerConfig."""
    try:
        return OCCLUSION_MODELS[name](config)
    except KeyError:
        raise OcctrackError(f"unknown occlusion handler {name!r}; choose from "
                            f"{', '.join(TRACKER_NAMES)}") from None
