"""Traffic on the simulated highway: cars entering each lane, moving at constant speed, leaving.

Each car is kept as its entry time t_e, speed v and length L; its front at step t is
`-half_length + v (t - t_e)` along its direction of travel, computed afresh each step so that no
rounding accumulates. A car is on the road (and is a true object) from its entry until its rear
has passed the far end of the section. Entry gaps are drawn so that a follower never comes within
`min_headway` of its leader while both are on the road (the authors' prototype let a slower car
be caught up); `Traffic.step` checks nothing, `cars_overlap` lets tests do so.

The sensor (paper appendix) sees the cars by angle from a point beside the road; the shapes it
reports are `Scan`s (`occtrack.models.highway_sensor`). Two ways to decide what hides what:

- object-wise: the cars hide the cars. Visibility comes from the true cars (a missed car still
  hides others); then misses (P_D), then Gaussian noise on the seen ends, drawn again while the
  reported ends would be out of order (a seen end beyond its neighbouring hidden interval, or
  left beyond right). Clutter is added last, never hidden and hiding nothing.
- measurement-wise: every car first makes its measurement (misses, then independent Gaussian
  noise on both ends, the two noisy ends reported in order), clutter shapes are added, and then
  the measurements hide the measurements.

Clutter: Poisson(kappa) shapes per step, lane uniform, left end uniform over the road section,
length uniform in [clutter_min_length, clutter_max_length].
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from occtrack.config.highway import SENSOR_MODES, SimulationConfig
from occtrack.errors import OcctrackError
from occtrack.models.highway_sensor import Scan
from occtrack.occlusion.extents import Occluded, occlude


@dataclass(frozen=True)
class Cars:
    """The cars on the road at one step: id, lane (0 = nearest), left end, length and signed
    velocity (metres per step)."""

    id: np.ndarray
    lane: np.ndarray
    left: np.ndarray
    length: np.ndarray
    velocity: np.ndarray

    def __len__(self) -> int:
        return len(self.id)

    @property
    def right(self) -> np.ndarray:
        return self.left + self.length

    @property
    def front(self) -> np.ndarray:
        """The leading end: right end when moving towards +x, left end otherwise."""
        return np.where(self.velocity > 0, self.right, self.left)


class Traffic:
    """Cars on every lane of the road, advanced one step at a time."""

    def __init__(self, config: SimulationConfig, rng: np.random.Generator):
        config.validate()
        self.config = config
        self.rng = rng
        self.t = -1
        n = config.road.n_lanes
        self._direction = config.road.directions
        self._entry = np.empty(0)
        self._speed = np.empty(0)
        self._length = np.empty(0)
        self._lane = np.empty(0, dtype=np.int64)
        self._id = np.empty(0, dtype=np.int64)
        self._next_id = 0
        c = config
        self._next_speed = rng.uniform(c.min_speed, c.max_speed, n)
        self._next_length = rng.uniform(c.min_length, c.max_length, n)
        self._next_entry = rng.uniform(0.0, c.max_gap, n)

    def _schedule_follower(self, lane: int) -> None:
        """Draw the next car of a lane, given the one that has just been admitted."""
        c, rng = self.config, self.rng
        v, length, t_e = self._next_speed[lane], self._next_length[lane], self._next_entry[lane]
        v_new = rng.uniform(max(c.min_speed, v - c.speed_step), min(c.max_speed, v + c.speed_step))
        span = 2.0 * c.road.half_length
        # Follower front <= leader rear - headway, both at the follower's entry and when the
        # leader leaves the road; positions are linear in time, so then also in between.
        gap_min = max((length + c.min_headway) / v,
                      (span + length) / v - (span - c.min_headway) / v_new)
        gap = c.entry_delay + rng.uniform(max(gap_min - c.entry_delay, 0.0),
                                          max(gap_min - c.entry_delay, c.max_gap))
        self._next_speed[lane] = v_new
        self._next_length[lane] = rng.uniform(c.min_length, c.max_length)
        self._next_entry[lane] = t_e + gap

    def step(self) -> Cars:
        self.t += 1
        t = self.t
        half = self.config.road.half_length
        for lane in range(self.config.road.n_lanes):
            while self._next_entry[lane] <= t:
                self._entry = np.append(self._entry, self._next_entry[lane])
                self._speed = np.append(self._speed, self._next_speed[lane])
                self._length = np.append(self._length, self._next_length[lane])
                self._lane = np.append(self._lane, lane)
                self._id = np.append(self._id, self._next_id)
                self._next_id += 1
                self._schedule_follower(lane)
        front = -half + self._speed * (t - self._entry)
        on_road = front - self._length < half
        self._entry, self._speed, self._length = (self._entry[on_road], self._speed[on_road],
                                                  self._length[on_road])
        self._lane, self._id, front = self._lane[on_road], self._id[on_road], front[on_road]
        direction = self._direction[self._lane]
        left = np.where(direction > 0, front - self._length, -front)
        order = np.lexsort((left, self._lane))
        return Cars(self._id[order], self._lane[order], left[order], self._length[order],
                    (direction * self._speed)[order])


def cars_overlap(cars: Cars, headway: float = 0.0) -> bool:
    """True if two cars of one lane are closer than `headway` (or overlap)."""
    order = np.lexsort((cars.left, cars.lane))
    lane, left, right = cars.lane[order], cars.left[order], cars.right[order]
    same = lane[1:] == lane[:-1]
    return bool(np.any(same & (left[1:] < right[:-1] + headway)))


def simulate(config: SimulationConfig, sensor: str, steps: int,
             seed: int) -> Iterator[tuple[Cars, Scan]]:
    """The cars and the scan of each step. Traffic and sensor draw from separate streams of
    `seed`, so one seed gives the same traffic under either sensor."""
    if sensor not in SENSOR_MODES:
        raise OcctrackError(f"unknown sensor occlusion {sensor!r}; "
                            f"choose from {', '.join(SENSOR_MODES)}")
    traffic_seed, sensor_seed = np.random.SeedSequence(seed).spawn(2)
    traffic = Traffic(config, np.random.default_rng(traffic_seed))
    rng = np.random.default_rng(sensor_seed)
    for _ in range(steps):
        cars = traffic.step()
        yield cars, sense(cars, config, sensor, rng)


# -- the sensor -----------------------------------------------------------------------------------

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
