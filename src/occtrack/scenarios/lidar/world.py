"""The moving objects of the lidar scene: people (discs) and vehicles (rectangles) walking and
driving past the sensor, each lane holding one object at a time.

Lanes run parallel to x at fixed y, so nobody meets anybody: the only interaction is that a
nearer object hides a farther one along the sensor's beams, which is what the scene is for.
Long full occlusions come from the geometry of a walkway seen from its side: far along the
strip the angular speeds v |y| / (x^2 + y^2) are small and alike, so a near person covers a far
one for seconds, and a person standing still (`stop_probability`) is covered by each passer-by.

An object's pass is kept as its entry time t0, entry point x0, direction s = +-1, speed v and
one stop (after moving for `stop_at` seconds, for `stop_for` seconds; stop_at = inf for none).
Its position at t is computed afresh, x0 + s v m(t) with the moving time
m(t) = min(t - t0, stop_at) + max(t - t0 - stop_at - stop_for, 0), so no rounding accumulates.
Each lane draws from its own random stream, so a longer scene begins as the shorter one did.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.config.lidar import LidarSceneConfig
from occtrack.scenarios.lidar.raycast import Shapes


@dataclass(frozen=True)
class Objects:
    """The objects in the scene at one time: id (K,), their shapes, velocity (K, 2) m/s."""

    id: np.ndarray
    shapes: Shapes
    velocity: np.ndarray

    def __len__(self) -> int:
        return len(self.id)


def lane_distances(config: LidarSceneConfig, rng: np.random.Generator) -> np.ndarray:
    """Signed y of each person's lane: `people` of the 2 `people` slots at nearest_lane +
    j lane_spacing either side, then the vehicles' road lanes, alternating sides."""
    n = config.people
    slots = config.nearest_lane + config.lane_spacing * np.arange(config.lane_slots)
    people = rng.permutation(np.r_[slots, -slots])[:n]
    j = np.arange(config.vehicles)
    roads = (config.road_distance + config.road_spacing * (j // 2)) * np.where(j % 2, -1, 1)
    return np.r_[people, roads]


class Crowd:
    """Every lane's current object, renewed when it leaves the strip."""

    def __init__(self, config: LidarSceneConfig, seed: np.random.SeedSequence):
        self.config = config
        n, m = config.people, config.vehicles
        lane_seed, *streams = seed.spawn(1 + n + m)
        self.y = lane_distances(config, np.random.default_rng(lane_seed))
        self.rngs = [np.random.default_rng(s) for s in streams]
        self.disc = np.r_[np.ones(n, bool), np.zeros(m, bool)]
        self.length = np.r_[np.full(n, 2 * config.person_radius), np.full(m, config.vehicle_length)]
        self.width = np.r_[np.full(n, 2 * config.person_radius), np.full(m, config.vehicle_width)]
        lanes = n + m
        self.id = np.zeros(lanes, np.int64)
        self.t0, self.x0, self.sign, self.speed = (np.zeros(lanes) for _ in range(4))
        self.stop_at, self.stop_for = np.full(lanes, np.inf), np.zeros(lanes)
        self.next_id = 1
        for lane in range(lanes):
            self._new_pass(lane, 0.0)
            self.t0[lane] = -self.rngs[lane].uniform(0, self.end(lane))  # already on its way

    def path(self, lane: int) -> float:
        """Metres from entering (wholly outside the strip) to leaving (wholly outside again)."""
        return 2 * self.config.half_length + self.length[lane]

    def end(self, lane: int) -> float:
        """Time from the lane's current entry until its object has left."""
        return self.path(lane) / self.speed[lane] + self.stop_for[lane]

    def _new_pass(self, lane: int, t0: float) -> None:
        c, rng = self.config, self.rngs[lane]
        person = self.disc[lane]
        sign = 1.0 if rng.random() < 0.5 else -1.0
        if c.one_way_sides:
            sign = 1.0 if self.y[lane] > 0 else -1.0
        speed = (rng.uniform(c.min_speed, c.max_speed) if person
                 else c.vehicle_speed * rng.uniform(0.8, 1.2))
        stops = person and rng.random() < c.stop_probability
        at = rng.uniform(0, self.path(lane) / speed)
        duration = rng.uniform(c.min_stop, c.max_stop)
        self.id[lane], self.next_id = self.next_id, self.next_id + 1
        self.t0[lane], self.sign[lane], self.speed[lane] = t0, sign, speed
        self.x0[lane] = -sign * (c.half_length + self.length[lane] / 2)
        self.stop_at[lane], self.stop_for[lane] = (at, duration) if stops else (np.inf, 0.0)

    def at(self, t: float) -> Objects:
        """The objects at time t (non-decreasing from call to call)."""
        for lane in range(len(self.y)):
            while t >= self.t0[lane] + self.end(lane):
                self._new_pass(lane, self.t0[lane] + self.end(lane))
        elapsed = t - self.t0
        after = elapsed - self.stop_at - self.stop_for
        moving = np.minimum(elapsed, self.stop_at) + np.maximum(after, 0.0)
        x = self.x0 + self.sign * self.speed * moving
        stopped = (elapsed >= self.stop_at) & (after < 0)
        vx = np.where(stopped, 0.0, self.sign * self.speed)
        heading = np.where(self.sign > 0, 0.0, np.pi)
        shapes = Shapes(np.c_[x, self.y], heading, self.length.copy(), self.width.copy(),
                        self.disc.copy())
        return Objects(self.id.copy(), shapes, np.c_[vx, np.zeros_like(vx)])
