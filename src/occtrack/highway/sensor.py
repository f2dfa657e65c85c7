"""The highway sensor: contiguous shapes seen by angle from a point beside the road.

A shape [left, right] in lane k (distance d_k) covers the angles [left, right] / d_k (tangents,
which order the same way). Nearer lanes hide farther ones; shapes of one lane never hide each
other. The sensor reports each shape that is not wholly hidden by its two ends. An end that is
seen is a point; an end that is hidden is the interval in which it could lie: the connected
part of the hidden angles (scaled back to metres in its lane) that contains it.

Two ways to decide what hides what (paper appendix):

- object-wise: the cars hide the cars. Visibility comes from the true cars (a missed car still
  hides others); then misses (P_D), then Gaussian noise on the seen ends, drawn again while the
  reported ends would be out of order (a seen end beyond its neighbouring hidden interval, or
  left beyond right). Clutter is added last, never hidden and hiding nothing.
- measurement-wise: every car first makes its measurement (misses, then independent Gaussian
  noise on both ends, the two noisy ends reported in order), clutter shapes are added, and then
  the measurements hide the measurements. Under this model the probability that a shape with
  ends (l, r) is wholly hidden is exactly
      q = sum over hidden parts [a, b] of P(a <= l + e1 <= b) P(a <= r + e2 <= b),
  e1, e2 ~ N(0, sigma^2), which the measurement-wise tracker uses.

Clutter: Poisson(kappa) shapes per step, lane uniform, left end uniform over the road section,
length uniform in [clutter_min_length, clutter_max_length].

Hidden parts are tracked as sorted disjoint intervals and located with `searchsorted`; no
float end is ever compared for equality (the prototype's equality test dropped hidden spans).
The sensor is particular to this study, so it is written here; scipy supplies the normal CDF.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtr

from occtrack.errors import OcctrackError
from occtrack.highway.config import SENSOR_MODES, SimulationConfig

if TYPE_CHECKING:
    from occtrack.highway.simulate import Cars


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


def union(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted disjoint intervals whose union is that of [lo_i, hi_i] (touching ones merged)."""
    if len(lo) == 0:
        return np.empty(0), np.empty(0)
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    reach = np.maximum.accumulate(hi)
    first = np.concatenate(([0], np.flatnonzero(lo[1:] > reach[:-1]) + 1))
    return lo[first], np.maximum.reduceat(hi, first)


def locate(x: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Index of the interval containing each x (closed), or -1."""
    if len(starts) == 0:
        return np.full(len(x), -1)
    i = np.searchsorted(starts, x, side="right") - 1
    inside = (i >= 0) & (x <= ends[np.maximum(i, 0)])
    return np.where(inside, i, -1)


@dataclass(frozen=True)
class Occluded:
    """What the occlusion pass found for each input shape."""

    reported: np.ndarray
    left_hidden: np.ndarray
    right_hidden: np.ndarray
    left_span: np.ndarray
    right_span: np.ndarray


def occlude(lane: np.ndarray, left: np.ndarray, right: np.ndarray,
            distances: np.ndarray) -> Occluded:
    """Nearer lanes hide farther ones. Returns, per shape, whether it is reported (not wholly
    hidden), which ends are hidden and the hidden interval (metres in its own lane) of each
    hidden end (NaN for a seen end)."""
    n = len(lane)
    reported = np.ones(n, bool)
    left_hidden = np.zeros(n, bool)
    right_hidden = np.zeros(n, bool)
    left_span = np.full((n, 2), np.nan)
    right_span = np.full((n, 2), np.nan)
    starts, ends = np.empty(0), np.empty(0)
    for k, d in enumerate(distances):
        sel = np.flatnonzero(lane == k)
        if len(sel) == 0:
            continue
        a, b = left[sel] / d, right[sel] / d
        ia, ib = locate(a, starts, ends), locate(b, starts, ends)
        left_hidden[sel], right_hidden[sel] = ia >= 0, ib >= 0
        reported[sel] = ~((ia >= 0) & (ia == ib))
        for i, span in ((ia, left_span), (ib, right_span)):
            h = i >= 0
            span[sel[h], 0] = starts[i[h]] * d
            span[sel[h], 1] = ends[i[h]] * d
        starts, ends = union(np.concatenate((starts, a)), np.concatenate((ends, b)))
    return Occluded(reported, left_hidden, right_hidden, left_span, right_span)


def _clutter(config: SimulationConfig, rng: np.random.Generator):
    n = rng.poisson(config.clutter_rate)
    lane = rng.integers(0, config.road.n_lanes, n)
    half = config.road.half_length
    left = rng.uniform(-half, half, n)
    length = rng.uniform(config.clutter_min_length, config.clutter_max_length, n)
    return lane, left, left + length


def _assemble(lane, left, right, occ: Occluded, source) -> Scan:
    keep = occ.reported
    lane, left, right, source = lane[keep], left[keep], right[keep], source[keep]
    lh, rh = occ.left_hidden[keep], occ.right_hidden[keep]
    lo_l = np.where(lh, occ.left_span[keep, 0], left)
    hi_l = np.where(lh, occ.left_span[keep, 1], left)
    lo_r = np.where(rh, occ.right_span[keep, 0], right)
    hi_r = np.where(rh, occ.right_span[keep, 1], right)
    order = np.lexsort((lo_l, lane))
    return Scan(lane[order].astype(np.int64), np.c_[lo_l, hi_l][order], np.c_[lo_r, hi_r][order],
                lh[order], rh[order], source[order].astype(np.int64))


def sense_object_wise(cars: Cars, config: SimulationConfig, rng: np.random.Generator) -> Scan:
    distances = config.road.distances
    occ = occlude(cars.lane, cars.left, cars.right, distances)
    detected = occ.reported & (rng.random(len(cars)) < config.detection_probability)
    occ = Occluded(detected, occ.left_hidden, occ.right_hidden, occ.left_span, occ.right_span)
    left, right = cars.left.copy(), cars.right.copy()
    # Noise on seen ends, redrawn where the reported ends would be out of order.
    todo = np.flatnonzero(detected)
    sigma = config.noise_std
    for _ in range(10_000):
        if len(todo) == 0:
            break
        zl = cars.left[todo] + sigma * rng.standard_normal(len(todo))
        zr = cars.right[todo] + sigma * rng.standard_normal(len(todo))
        lh, rh = occ.left_hidden[todo], occ.right_hidden[todo]
        zl = np.where(lh, cars.left[todo], zl)
        zr = np.where(rh, cars.right[todo], zr)
        upper_left = np.where(lh, occ.left_span[todo, 1], zl)
        lower_right = np.where(rh, occ.right_span[todo, 0], zr)
        good = upper_left < lower_right
        left[todo[good]], right[todo[good]] = zl[good], zr[good]
        todo = todo[~good]
    else:  # pragma: no cover - needs a seen end sitting on a boundary 10^4 times in a row
        raise OcctrackError("could not draw ordered measurement noise")
    scan = _assemble(cars.lane, left, right, occ, cars.id)
    c_lane, c_left, c_right = _clutter(config, rng)
    nc = len(c_lane)
    clutter = Scan(c_lane.astype(np.int64), np.c_[c_left, c_left], np.c_[c_right, c_right],
                   np.zeros(nc, bool), np.zeros(nc, bool), np.full(nc, -1, np.int64))
    return concatenate(scan, clutter)


def sense_measurement_wise(cars: Cars, config: SimulationConfig,
                           rng: np.random.Generator) -> Scan:
    detected = rng.random(len(cars)) < config.detection_probability
    n = int(detected.sum())
    zl = cars.left[detected] + config.noise_std * rng.standard_normal(n)
    zr = cars.right[detected] + config.noise_std * rng.standard_normal(n)
    zl, zr = np.minimum(zl, zr), np.maximum(zl, zr)
    c_lane, c_left, c_right = _clutter(config, rng)
    lane = np.r_[cars.lane[detected], c_lane]
    left, right = np.r_[zl, c_left], np.r_[zr, c_right]
    source = np.r_[cars.id[detected], np.full(len(c_lane), -1)]
    occ = occlude(lane, left, right, config.road.distances)
    return _assemble(lane, left, right, occ, source)


def sense(cars: Cars, config: SimulationConfig, mode: str, rng: np.random.Generator) -> Scan:
    if mode == "object-wise":
        return sense_object_wise(cars, config, rng)
    if mode == "measurement-wise":
        return sense_measurement_wise(cars, config, rng)
    raise OcctrackError(f"unknown sensor occlusion {mode!r}; choose from {', '.join(SENSOR_MODES)}")


def concatenate(a: Scan, b: Scan) -> Scan:
    s = Scan(np.r_[a.lane, b.lane], np.r_[a.left, b.left], np.r_[a.right, b.right],
             np.r_[a.left_hidden, b.left_hidden], np.r_[a.right_hidden, b.right_hidden],
             np.r_[a.source, b.source])
    order = np.lexsort((s.left[:, 0], s.lane))
    return Scan(s.lane[order], s.left[order], s.right[order], s.left_hidden[order],
                s.right_hidden[order], s.source[order])


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
    """Standard deviations beyond which a Gaussian end is taken to be 0 (tails below 1e-9)."""

    def __init__(self, config):
        self.distances = config.road.distances
        self.n_lanes = config.road.n_lanes
        self.half_length = config.road.half_length
        self.sigma = float(config.noise_std)
        self.clutter_lengths = (config.clutter_min_length, config.clutter_max_length)

    def _end(self, e: np.ndarray, z: np.ndarray, hidden: np.ndarray) -> np.ndarray:
        s = self.sigma
        out = np.empty_like(e)
        seen = ~hidden
        if seen.any():
            d = (z[seen, 0, None] - e[seen]) / s
            out[seen] = np.exp(-0.5 * d * d) / (s * np.sqrt(2.0 * np.pi))
        if hidden.any():
            out[hidden] = (ndtr((z[hidden, 1, None] - e[hidden]) / s)
                           - ndtr((z[hidden, 0, None] - e[hidden]) / s))
        return out

    def _seen(self, lo, hi, zl, zr):
        """Both ends seen: the two orders of two independent Gaussian ends."""
        s2 = -0.5 / self.sigma**2
        return (np.exp(s2 * ((zl - lo) ** 2 + (zr - hi) ** 2))
                + np.exp(s2 * ((zl - hi) ** 2 + (zr - lo) ** 2))) / (2.0 * np.pi * self.sigma**2)

    def likelihood(self, left: np.ndarray, right: np.ndarray, z_left: np.ndarray,
                   z_right: np.ndarray, left_hidden: np.ndarray,
                   right_hidden: np.ndarray) -> np.ndarray:
        """p(z_p | particle) for rows p of (P, N) particle ends and P measurements."""
        both = ~left_hidden & ~right_hidden
        if both.all():
            return self._seen(left, right, z_left[:, 0, None], z_right[:, 0, None])
        out = np.empty(left.shape)
        if both.any():
            out[both] = self._seen(left[both], right[both], z_left[both, 0, None],
                                   z_right[both, 0, None])
        rest = ~both
        if rest.any():
            lo, hi = left[rest], right[rest]
            zl, zr, lh, rh = z_left[rest], z_right[rest], left_hidden[rest], right_hidden[rest]
            out[rest] = (self._end(lo, zl, lh) * self._end(hi, zr, rh)
                         + self._end(hi, zl, lh) * self._end(lo, zr, rh))
        return out

    def occluded_parts(self, scan: Scan) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each lane, the hidden parts (sorted disjoint intervals, metres in that lane)
        made by the measured shapes of the nearer lanes."""
        parts = []
        starts, ends = np.empty(0), np.empty(0)
        lo, hi = scan.extent
        for k, d in enumerate(self.distances):
            parts.append((starts * d, ends * d))
            sel = scan.lane == k
            starts, ends = union(np.concatenate((starts, lo[sel] / d)),
                                 np.concatenate((ends, hi[sel] / d)))
        return parts

    def hidden_probability(self, lane: np.ndarray, left: np.ndarray, right: np.ndarray,
                           scan: Scan, parts=None) -> np.ndarray:
        """q: the probability that a car's noisy shape would lie wholly inside one hidden part
        of its lane, sum_C P(l' in C) P(r' in C). Only parts within `tail` sigma of both ends
        are visited, found with searchsorted, so the cost is in the particles near them.
        `parts`: `occluded_parts(scan)`, if already at hand."""
        q = np.zeros(len(lane))
        if parts is None:
            parts = self.occluded_parts(scan)
        count = np.array([len(lo) for lo, _ in parts])
        if count.sum() == 0 or len(lane) == 0:
            return q
        s, reach = self.sigma, self.tail * self.sigma
        lo = np.concatenate([p[0] for p in parts])
        hi = np.concatenate([p[1] for p in parts])
        part_lane = np.repeat(np.arange(self.n_lanes), count)
        # Parts are sorted within a lane; a lane offset beyond any position sorts them all.
        shift = 1e3 * (max(np.abs(lo).max(), np.abs(hi).max()) + self.half_length + reach)
        last = np.searchsorted(lo + shift * part_lane, left + reach + shift * lane,
                               side="right") - 1
        at = np.arange(len(lane))
        while len(at):
            ok = last >= 0
            ok[ok] = (part_lane[last[ok]] == lane[at[ok]]) & (hi[last[ok]] >= right[at[ok]] - reach)
            at, c = at[ok], last[ok]
            if len(at) == 0:
                break
            li, ri, a, b = left[at], right[at], lo[c], hi[c]
            q[at] += ((ndtr((b - li) / s) - ndtr((a - li) / s))
                      * (ndtr((b - ri) / s) - ndtr((a - ri) / s)))
            last = c - 1
        return np.clip(q, 0.0, 1.0)

    def clutter_density(self, scan: Scan) -> np.ndarray:
        """p_F(z_j): lane uniform, left end uniform on the section, length uniform; seen ends
        as a density, hidden ends integrated over their intervals."""
        half = self.half_length
        lmin, lmax = self.clutter_lengths
        c = 1.0 / (self.n_lanes * 2.0 * half * (lmax - lmin))
        lh, rh = scan.left_hidden, scan.right_hidden
        s_lo = np.maximum(scan.left[:, 0], -half)
        s_hi = np.minimum(scan.left[:, 1], half)
        e_lo, e_hi = scan.right[:, 0], scan.right[:, 1]
        out = np.zeros(len(scan))
        seen_s = (scan.left[:, 0] >= -half) & (scan.left[:, 0] <= half)
        vv = ~lh & ~rh
        gap = e_lo - scan.left[:, 0]
        out[vv] = (seen_s & (gap >= lmin) & (gap <= lmax))[vv]
        hv = lh & ~rh
        out[hv] = _overlap(s_lo, s_hi, e_lo - lmax, e_lo - lmin)[hv]
        vh = ~lh & rh
        out[vh] = (seen_s * _overlap(e_lo, e_hi, scan.left[:, 0] + lmin,
                                     scan.left[:, 0] + lmax))[vh]
        hh = lh & rh
        if hh.any():
            out[hh] = _band_area(s_lo[hh], s_hi[hh], e_lo[hh], e_hi[hh], lmin, lmax)
        return c * out


def _overlap(a0, a1, b0, b1):
    return np.clip(np.minimum(a1, b1) - np.maximum(a0, b0), 0.0, None)


def _band_area(s0, s1, e0, e1, lmin, lmax):
    """Area of {(s, e): s in [s0, s1], e in [e0, e1], lmin <= e - s <= lmax}: the integral over
    s of a piecewise-linear overlap, exact by the trapezoid rule on its breakpoints."""
    knots = np.stack([s0, s1, e0 - lmax, e0 - lmin, e1 - lmax, e1 - lmin], axis=1)
    knots = np.sort(np.clip(knots, s0[:, None], np.maximum(s0, s1)[:, None]), axis=1)
    width = _overlap(e0[:, None], e1[:, None], knots + lmin, knots + lmax)
    return np.sum(0.5 * (width[:, 1:] + width[:, :-1]) * np.diff(knots, axis=1), axis=1)
