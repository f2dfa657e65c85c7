"""Traffic on the simulated highway: cars entering each lane, moving at constant speed, leaving.

Each car is kept as its entry time t_e, speed v and length L; its front at step t is
`-half_length + v (t - t_e)` along its direction of travel, computed afresh each step so that no
rounding accumulates. A car is on the road (and is a true object) from its entry until its rear
has passed the far end of the section. Entry gaps are drawn so that a follower never comes within
`min_headway` of its leader while both are on the road (the authors' prototype let a slower car
be caught up); `Traffic.step` checks nothing, `cars_overlap` lets tests do so.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from occtrack.highway.config import SENSOR_MODES, SimulationConfig

if TYPE_CHECKING:
    from occtrack.highway.sensor import Scan


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
    from occtrack.highway.sensor import sense

    if sensor not in SENSOR_MODES:
        from occtrack.errors import OcctrackError
        raise OcctrackError(f"unknown sensor occlusion {sensor!r}; "
                            f"choose from {', '.join(SENSOR_MODES)}")
    traffic_seed, sensor_seed = np.random.SeedSequence(seed).spawn(2)
    traffic = Traffic(config, np.random.default_rng(traffic_seed))
    rng = np.random.default_rng(sensor_seed)
    for _ in range(steps):
        cars = traffic.step()
        yield cars, sense(cars, config, sensor, rng)
