"""The lidar scene: a 2-D scanning range sensor watching people walk past (paper section V's
sensor, with a world behind it), seeded and reproducible.

Each scan casts every beam against every object exactly (`raycast`); the first surface on a
beam gives its range. What the sensor then reports follows section V's beam model: the surface
returns with probability P_D at its range plus N(0, sigma^2), clutter returns (Poisson a scan,
uniform over beams and over [0, max_range]) are added, and the nearest return is reported; no
return before max_range is reported as none (inf). Under `sensor = "measurement-wise"` every
object on a beam returns or not on its own and the nearest return hides the others, the
paper's model exactly; under "object-wise" (the default: surfaces are opaque) a missed object
still blocks its beam.

The ground truth of each scan gives every object's shape and motion and two beam counts:
`clear`, the beams that would reach it were it alone, and `visible`, the beams whose first
surface it is. An object with clear > 0 and visible == 0 is fully occluded: in the field of
view and in range, some beam passes through its angular span, and none reaches it.
`full_occlusions` finds those spells per object, so a tracker's study can count them and how
long they last. Both counts are geometric: a missed detection or a clutter return in front of
an object does not change them.

World and sensor draw from separate streams of the seed, so one seed gives the same walkers
under either sensor mode, and the scans after the first N do not change the first N.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from occtrack.config.lidar import LidarSceneConfig
from occtrack.scenarios.lidar.raycast import beam_counts, cast, nearest
from occtrack.scenarios.lidar.world import Crowd, Objects


@dataclass(frozen=True)
class LidarScan:
    """One scan and its truth. time s; pose (x, y, heading) of the sensor in the world;
    angle (B,) rad in the sensor's frame; range (B,) m, inf where nothing returned; objects in
    the world frame; clear and visible (K,) beams an object (see the module docstring)."""

    time: float
    pose: np.ndarray
    angle: np.ndarray
    range: np.ndarray
    objects: Objects
    clear: np.ndarray
    visible: np.ndarray

    @property
    def occluded(self) -> np.ndarray:
        """Fully occluded objects: some beam would reach each, none does."""
        return (self.clear > 0) & (self.visible == 0)


def beam_angles(config: LidarSceneConfig) -> np.ndarray:
    """Beam k at -fov/2 + (k + 1/2) fov / beams, radians in the sensor's frame."""
    fov = np.deg2rad(config.fov_deg)
    return -fov / 2 + (np.arange(config.beams) + 0.5) * fov / config.beams


def sensor_pose(config: LidarSceneConfig, t: float) -> np.ndarray:
    """(x, y, heading) at time t: from the origin, heading +x, at constant velocity and turn
    rate."""
    return np.array([config.sensor_vx * t, config.sensor_vy * t, config.sensor_yaw_rate * t])


def measure(dist: np.ndarray, config: LidarSceneConfig, rng: np.random.Generator) -> np.ndarray:
    """The reported range of each beam from the (B, K) ranges to the objects: detections,
    noise, clutter, the nearest return; inf where none before max_range."""
    b, k = dist.shape
    detected = rng.random((b, k)) < config.p_d
    noisy = np.maximum(dist + config.range_noise * rng.standard_normal((b, k)), 0.0)
    if config.sensor == "measurement-wise" or k == 0:
        z = np.min(np.where(detected, noisy, np.inf), axis=1, initial=np.inf)
    else:
        first, _ = nearest(dist, np.inf)
        rows = np.arange(b)
        z = np.where((first >= 0) & detected[rows, first], noisy[rows, first], np.inf)
    n = rng.poisson(config.clutter_per_scan)
    np.minimum.at(z, rng.integers(0, b, n), rng.uniform(0, config.max_range, n))
    return np.where(z < config.max_range, z, np.inf)


def simulate_scene(config: LidarSceneConfig, scans: int, seed: int) -> Iterator[LidarScan]:
    """The scans at times 0, 1/rate, ..., (scans - 1)/rate, each with its truth."""
    world_seed, sensor_seed = np.random.SeedSequence(seed).spawn(2)
    crowd = Crowd(config, world_seed)
    rng = np.random.default_rng(sensor_seed)
    angle = beam_angles(config)
    for i in range(scans):
        t = i / config.rate
        pose = sensor_pose(config, t)
        objects = crowd.at(t)
        dist = cast(pose[:2], pose[2] + angle, objects.shapes)
        clear, visible = beam_counts(dist, config.max_range)
        yield LidarScan(t, pose, angle, measure(dist, config, rng), objects, clear, visible)


@dataclass(frozen=True)
class Occlusions:
    """Spells of full occlusion: object id, times of the first and last fully occluded scan
    (each (N,)). duration = last - first, the time it was certainly hidden."""

    id: np.ndarray
    first: np.ndarray
    last: np.ndarray

    @property
    def duration(self) -> np.ndarray:
        return self.last - self.first

    def longer_than(self, seconds: float) -> int:
        return int(np.count_nonzero(self.duration > seconds))


def full_occlusions(time: np.ndarray, ids: np.ndarray, occluded: np.ndarray,
                    period: float, seen: np.ndarray | None = None) -> Occlusions:
    """The spells of full occlusion in truth rows (time, id, occluded; any order): runs of
    fully occluded rows of one id at successive scans (`period` apart).

    With `seen` (rows where the object shows enough of itself to be told from a clutter return,
    say two beams), a spell is a run of rows not seen that holds at least one fully occluded
    row, from its first to its last row: a glimpse too small to be seen does not end it."""
    order = np.lexsort((time, ids))
    t, i, occ = time[order], ids[order], occluded[order].astype(bool)
    run = occ if seen is None else ~seen[order].astype(bool)
    follows = np.r_[False, (i[1:] == i[:-1]) & (np.diff(t) < 1.5 * period)]
    starts = run & ~(follows & np.r_[False, run[:-1]])
    ends = run & ~np.r_[follows[1:] & run[1:], False]
    if seen is not None:  # keep the runs with a fully occluded row
        which = np.cumsum(starts) - 1
        hidden = np.bincount(which[run], weights=occ[run], minlength=int(starts.sum())) > 0
        return Occlusions(i[starts][hidden], t[starts][hidden], t[ends][hidden])
    return Occlusions(i[starts], t[starts], t[ends])
