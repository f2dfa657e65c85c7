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
compiled with numba (a Python loop per particle would be 100 times slower, and numpy's
whole-array steps make a temporary array per operation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from occtrack.jit import njit


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
                           np.asarray(left_hidden, bool), np.asarray(right_hidden, bool),
                           self.sigma, self.tail)

    def hit_weights(self, particles: np.ndarray, weights: np.ndarray, row: np.ndarray,
                    first: np.ndarray, count: np.ndarray, width: int,
                    scan: Scan, measurement: np.ndarray) -> np.ndarray:
        """weights * p(z_j | particle) over windows of particles, without copying them out:
        pair p scores measurement `measurement[p]` against particles[row[p], first[p] + k]
        (left end, length, ...) for k < count[p], 0 for count[p] <= k < width. Returns
        (pairs, width)."""
        j = np.asarray(measurement, np.int64)
        return _hit_weights(particles, weights, np.asarray(row, np.int64),
                            np.asarray(first, np.int64), np.asarray(count, np.int64), width,
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
        return _occluded_parts(scan.lane, np.ascontiguousarray(ext_lo),
                               np.ascontiguousarray(ext_hi), self.distances)

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
        return _hidden_probability(np.asarray(lane, np.int64), np.asarray(left, float),
                                   np.asarray(right, float), lo, hi, start, self.sigma,
                                   self.tail * self.sigma)

    def clutter_density(self, scan: Scan) -> np.ndarray:
        """p_F(z_j): lane uniform, left end uniform on the section, length uniform; seen ends
        as a density, hidden ends integrated over their intervals."""
        half = self.half_length
        lmin, lmax = self.clutter_lengths
        c = 1.0 / (self.n_lanes * 2.0 * half * (lmax - lmin))
        return _clutter_density(scan.left, scan.right, scan.left_hidden, scan.right_hidden,
                                half, lmin, lmax, c)


# -- compiled loops (numba): one pass over the particles, no temporaries ----------------------

_SQRT_HALF = 0.7071067811865476
_INV_SQRT_2PI = 0.3989422804014327


@njit
def _ndtr(x):
    """Phi(x). Beyond 9 (below -39) erfc rounds Phi to exactly 1 (0) in double precision, so
    those are returned without calling it: the same numbers, for less work where a hidden
    part is wide against sigma."""
    if x > 9.0:
        return 1.0
    if x < -39.0:
        return 0.0
    return 0.5 * math.erfc(-x * _SQRT_HALF)


@njit
def _end_term(e, z_lo, z_hi, hidden, inv_sigma, tail):
    """f(e): N(z; e, sigma^2) for a seen end, P(e + noise in [z_lo, z_hi]) for a hidden one;
    0 beyond `tail` standard deviations."""
    lo = (z_lo - e) * inv_sigma
    if hidden:
        hi = (z_hi - e) * inv_sigma
        if hi < -tail or lo > tail:
            return 0.0
        return _ndtr(hi) - _ndtr(lo)
    if lo * lo > tail * tail:
        return 0.0
    return math.exp(-0.5 * lo * lo) * _INV_SQRT_2PI * inv_sigma


@njit
def _near(e, z_lo, z_hi, hidden, inv_sigma, tail):
    """Whether `_end_term` is computed rather than taken as 0 (within `tail` sigma)."""
    lo = (z_lo - e) * inv_sigma
    if hidden:
        return not ((z_hi - e) * inv_sigma < -tail or lo > tail)
    return not lo * lo > tail * tail


@njit
def _both_orders(lo, hi, zl0, zl1, lh, zr0, zr1, rh, inv, tail):
    """p(z | ends lo, hi) summed over the two orders of the two ends; a product is computed
    only where both its ends are near (most particles are far from most measurements, and
    the reversed order is far for all but the shortest shapes)."""
    total = 0.0
    if _near(lo, zl0, zl1, lh, inv, tail) and _near(hi, zr0, zr1, rh, inv, tail):
        total += _end_term(lo, zl0, zl1, lh, inv, tail) * _end_term(hi, zr0, zr1, rh, inv, tail)
    if _near(hi, zl0, zl1, lh, inv, tail) and _near(lo, zr0, zr1, rh, inv, tail):
        total += _end_term(hi, zl0, zl1, lh, inv, tail) * _end_term(lo, zr0, zr1, rh, inv, tail)
    return total


@njit
def _likelihood(left, right, z_left, z_right, left_hidden, right_hidden, sigma, tail):
    """`_both_orders` of every (particle row, particle)."""
    rows, n = left.shape
    out = np.empty((rows, n))
    inv = 1.0 / sigma
    for p in range(rows):
        zl0, zl1, lh = z_left[p, 0], z_left[p, 1], left_hidden[p]
        zr0, zr1, rh = z_right[p, 0], z_right[p, 1], right_hidden[p]
        for k in range(n):
            out[p, k] = _both_orders(left[p, k], right[p, k], zl0, zl1, lh, zr0, zr1, rh, inv,
                                     tail)
    return out


@njit
def _hit_weights(particles, weights, row, first, count, width, z_left, z_right, left_hidden,
                 right_hidden, sigma, tail):
    out = np.zeros((len(row), width))
    inv = 1.0 / sigma
    for p in range(len(row)):
        zl0, zl1, lh = z_left[p, 0], z_left[p, 1], left_hidden[p]
        zr0, zr1, rh = z_right[p, 0], z_right[p, 1], right_hidden[p]
        r, f0 = row[p], first[p]
        for k in range(count[p]):
            lo = particles[r, f0 + k, 0]
            hi = lo + particles[r, f0 + k, 1]
            out[p, k] = weights[r, f0 + k] * _both_orders(lo, hi, zl0, zl1, lh, zr0, zr1, rh,
                                                          inv, tail)
    return out


@njit
def _occluded_parts(scan_lane, ext_lo, ext_hi, distances):
    """Lane k's hidden parts: the union of the angles [lo, hi] / d covered by the shapes of
    lanes 0 .. k-1 (touching intervals merged), scaled back by d_k, concatenated over the lanes
    (lo/hi[start[k]:start[k + 1]]). One sort of all shapes by angle, then one merging walk per
    lane over the shapes of its nearer lanes."""
    lanes = len(distances)
    m = len(scan_lane)
    a_lo = np.empty(m)
    a_hi = np.empty(m)
    for j in range(m):
        d = distances[scan_lane[j]]
        a_lo[j] = ext_lo[j] / d
        a_hi[j] = ext_hi[j] / d
    order = np.argsort(a_lo, kind="mergesort")
    lo = np.empty(max(lanes * m, 1))
    hi = np.empty(max(lanes * m, 1))
    start = np.zeros(lanes + 1, np.int64)
    c = 0
    for k in range(lanes):
        start[k] = c
        d = distances[k]
        have = False
        run_lo = run_hi = 0.0
        for t in range(m):
            j = order[t]
            if scan_lane[j] >= k:
                continue
            if have and a_lo[j] <= run_hi:
                run_hi = max(run_hi, a_hi[j])
                continue
            if have:
                lo[c] = run_lo * d
                hi[c] = run_hi * d
                c += 1
            have = True
            run_lo = a_lo[j]
            run_hi = a_hi[j]
        if have:
            lo[c] = run_lo * d
            hi[c] = run_hi * d
            c += 1
    start[lanes] = c
    return lo[:c], hi[:c], start


@njit
def _hidden_probability(lane, left, right, lo, hi, start, sigma, reach):
    """Parts of lane k are lo/hi[start[k]:start[k + 1]], sorted and disjoint (a few). A
    particle equal to the one before it (resampling makes copies, and sorting puts them side
    by side) takes its q without the normal CDFs."""
    q = np.zeros(len(lane))
    inv = 1.0 / sigma
    for i in range(len(lane)):
        k = lane[i]
        first = start[k]
        li, ri = left[i], right[i]
        if i > 0 and li == left[i - 1] and ri == right[i - 1] and k == lane[i - 1]:
            q[i] = q[i - 1]
            continue
        total = 0.0
        # from the last part, skip those starting beyond reach of the left end, then add
        # while a part can hold the right end (ends grow with the index: parts are disjoint)
        for j in range(start[k + 1] - 1, first - 1, -1):
            if lo[j] > li + reach:
                continue
            if hi[j] < ri - reach:
                break
            a, b = lo[j], hi[j]
            total += ((_ndtr((b - li) * inv) - _ndtr((a - li) * inv))
                      * (_ndtr((b - ri) * inv) - _ndtr((a - ri) * inv)))
        q[i] = min(max(total, 0.0), 1.0)
    return q


@njit
def _overlap(a0, a1, b0, b1):
    """Length of [a0, a1] intersected with [b0, b1] (0 if they do not meet)."""
    return max(min(a1, b1) - max(a0, b0), 0.0)


@njit
def _clutter_density(left, right, left_hidden, right_hidden, half, lmin, lmax, c):
    """c times: for two seen ends, 1 if the left end is on the section and the length within
    [lmin, lmax]; for one hidden end, the length of its interval that such a shape allows;
    for two, the area of {(s, e) in the two intervals: lmin <= e - s <= lmax}, exact by the
    trapezoid rule on the breakpoints of the piecewise-linear overlap."""
    m = len(left)
    out = np.empty(m)
    knots = np.empty(6)
    for j in range(m):
        l0, l1, r0, r1 = left[j, 0], left[j, 1], right[j, 0], right[j, 1]
        seen = 1.0 if -half <= l0 <= half else 0.0
        if not left_hidden[j] and not right_hidden[j]:
            gap = r0 - l0
            v = seen if lmin <= gap <= lmax else 0.0
        elif not right_hidden[j]:
            v = _overlap(max(l0, -half), min(l1, half), r0 - lmax, r0 - lmin)
        elif not left_hidden[j]:
            v = seen * _overlap(r0, r1, l0 + lmin, l0 + lmax)
        else:
            s0, s1 = max(l0, -half), min(l1, half)
            top = max(s0, s1)
            knots[0], knots[1], knots[2] = s0, s1, r0 - lmax
            knots[3], knots[4], knots[5] = r0 - lmin, r1 - lmax, r1 - lmin
            for t in range(6):
                knots[t] = min(max(knots[t], s0), top)
            knots.sort()
            v = 0.0
            for t in range(5):
                w0 = _overlap(r0, r1, knots[t] + lmin, knots[t] + lmax)
                w1 = _overlap(r0, r1, knots[t + 1] + lmin, knots[t + 1] + lmax)
                v += 0.5 * (w1 + w0) * (knots[t + 1] - knots[t])
        out[j] = c * v
    return out
