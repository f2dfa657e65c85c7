"""The highway sensor as the trackers model it: shapes seen by angle from a point beside the
road, each reported by its two ends (paper appendix).

A shape that is not wholly hidden is reported by its two ends: an end that is seen is a point;
an end that is hidden is the interval in which it could lie (`occtrack.occlusion.extents`).
Under measurement-wise occlusion (every car first makes its measurement, then the measurements
hide the measurements) the probability that a shape with ends (l, r) is wholly hidden is exactly
    q = sum over hidden parts [a, b] of P(a <= l + e1 <= b) P(a <= r + e2 <= b),
e1, e2 ~ N(0, sigma^2), which the measurement-wise tracker uses (`MeasurementModel`). The
simulated sensor itself is a scenario (`occtrack.scenarios.highway`).

The sensor is particular to this study, so it is written here; its per-particle loops are
compiled (Cython: `occtrack.models._models`, its `_highway_sensor.pxi`; a Python loop per
particle would be 100 times slower, and numpy's whole-array steps make a temporary array per
operation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.models._models import (  # noqa: F401 (_both_orders: occtrack.filters.particle_tomb)
    _both_orders,
    _clutter_density,
    _hidden_probability,
    _hit_weights,
    _likelihood,
    _occluded_parts,
)


@dataclass(frozen=True)
class Scan:
    """One step's measurements. left[j] and right[j] are (low, high) intervals; an end that was
    seen has low == high, written once, and `left_hidden[j]` / `right_hidden[j]` say which ends
    are intervals. `source[j]` is the true car's id (-1 for clutter): for tests and pictures
    only, never read by a tracker."""

    lane: np.ndarray
    left: np.ndarray
    right: np.ndarray
    left_hidden: np.ndarray
    right_hidden: np.ndarray
    source: np.ndarray

    def __len__(self) -> int:
        return len(self.lane)

    @property
    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """The outer bounds (left low, right high): everything this shape can hide."""
        return self.left[:, 0], self.right[:, 1]

    @staticmethod
    def empty() -> Scan:
        return Scan(np.empty(0, np.int64), np.empty((0, 2)), np.empty((0, 2)),
                    np.empty(0, bool), np.empty(0, bool), np.empty(0, np.int64))


class MeasurementModel:
    """The sensor as the trackers model it: the measurement-wise law above, with known noise,
    road and clutter. Distances, likelihoods and probabilities in metres of a car's own lane.

    A shape's likelihood given a car with ends (l, r) sums the two ways its two noisy ends can
    have been put in order:
        p(z | l, r) = f_left(l) f_right(r) + f_left(r) f_right(l),
    with f(e) = N(z; e, sigma^2) for a seen end and P(e + noise in [low, high]) for a hidden one
    (a density in the seen ends, a probability in the hidden ones). Clutter is scored the same
    way: its density over the seen ends, integrated over the hidden intervals.
    """

    tail = 6.0
    """Standard deviations beyond which a Gaussian end is taken to be 0 (tails below 1e-8)."""

    def __init__(self, config):
        self.distances = config.road.distances
        self.n_lanes = config.road.n_lanes
        self.half_length = config.road.half_length
        self.sigma = float(config.noise_std)
        self.clutter_lengths = (config.clutter_min_length, config.clutter_max_length)

    def likelihood(self, left: np.ndarray, right: np.ndarray, z_left: np.ndarray,
                   z_right: np.ndarray, left_hidden: np.ndarray,
                   right_hidden: np.ndarray) -> np.ndarray:
        """p(z_p | particle) for rows p of (P, N) particle ends and P measurements."""
        return _likelihood(np.ascontiguousarray(left, dtype=float),
                           np.ascontiguousarray(right, dtype=float),
                           np.ascontiguousarray(z_left, dtype=float),
                           np.ascontiguousarray(z_right, dtype=float),
                           np.ascontiguousarray(left_hidden, bool),
                           np.ascontiguousarray(right_hidden, bool),
                           self.sigma, self.tail)

    def hit_weights(self, particles: np.ndarray, weights: np.ndarray, row: np.ndarray,
                    first: np.ndarray, count: np.ndarray, width: int,
                    scan: Scan, measurement: np.ndarray) -> np.ndarray:
        """weights * p(z_j | particle) over windows of particles, without copying them out:
        pair p scores measurement `measurement[p]` against particles[row[p], first[p] + k]
        (left end, length, ...) for k < count[p], 0 for count[p] <= k < width. Returns
        (pairs, width)."""
        j = np.asarray(measurement, np.int64)
        return _hit_weights(np.ascontiguousarray(particles, float),
                            np.ascontiguousarray(weights, float),
                            np.ascontiguousarray(row, np.int64),
                            np.ascontiguousarray(first, np.int64),
                            np.ascontiguousarray(count, np.int64), width,
                            scan.left[j], scan.right[j], scan.left_hidden[j],
                            scan.right_hidden[j], self.sigma, self.tail)

    def occluded_parts(self, scan: Scan) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each lane, the hidden parts (sorted disjoint intervals, metres in that lane)
        made by the measured shapes of the nearer lanes."""
        lo, hi, start = self._parts(scan)
        return [(lo[start[k]:start[k + 1]], hi[start[k]:start[k + 1]])
                for k in range(self.n_lanes)]

    def _parts(self, scan: Scan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`occluded_parts` concatenated: lane k's are lo/hi[start[k]:start[k + 1]]."""
        ext_lo, ext_hi = scan.extent
        return _occluded_parts(np.ascontiguousarray(scan.lane, np.int64),
                               np.ascontiguousarray(ext_lo, float),
                               np.ascontiguousarray(ext_hi, float),
                               np.ascontiguousarray(self.distances, float))

    def hidden_probability(self, lane: np.ndarray, left: np.ndarray, right: np.ndarray,
                           scan: Scan, parts=None) -> np.ndarray:
        """q: the probability that a car's noisy shape would lie wholly inside one hidden part
        of its lane, sum_C P(l' in C) P(r' in C). Only parts within `tail` sigma of both ends
        are visited (a binary search, then a walk back), so the cost is in the particles near
        them. `parts`: `occluded_parts(scan)`, if already at hand."""
        if parts is None:
            lo, hi, start = self._parts(scan)
        else:
            start = np.concatenate(([0], np.cumsum([len(p[0]) for p in parts]))).astype(np.int64)
            lo = np.concatenate([np.asarray(p[0], float) for p in parts])
            hi = np.concatenate([np.asarray(p[1], float) for p in parts])
        return _hidden_probability(np.ascontiguousarray(lane, np.int64),
                                   np.ascontiguousarray(left, float),
                                   np.ascontiguousarray(right, float), lo, hi, start, self.sigma,
                                   self.tail * self.sigma)

    def clutter_density(self, scan: Scan) -> np.ndarray:
        """p_F(z_j): lane uniform, left end uniform on the section, length uniform; seen ends
        as a density, hidden ends integrated over their intervals."""
        half = self.half_length
        lmin, lmax = self.clutter_lengths
        c = 1.0 / (self.n_lanes * 2.0 * half * (lmax - lmin))
        return _clutter_density(np.ascontiguousarray(scan.left, float),
                                np.ascontiguousarray(scan.right, float),
                                np.ascontiguousarray(scan.left_hidden, bool),
                                np.ascontiguousarray(scan.right_hidden, bool), half, lmin, lmax,
                                c)

