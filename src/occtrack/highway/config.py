"""Settings of the highway study (paper appendix): the road, the simulation and the trackers.

Defaults are the paper's values (DESIGN.md section 2.3). Names from the literature: P_D is the
detection probability, kappa the clutter rate (expected false measurements per step), lambda_b
the birth rate (expected new cars per lane per step), r a track's probability of existence.

Coordinates: x runs along the road, the point sensor sits at x = 0 beside it, and lane k
(k = 1 nearest) is at distance `lane_spacing * k`. A car is the interval [left, left + length]
of its lane; its velocity is signed (+ in the first `lanes_right` lanes, - in the others). The
sensor sees by angle, so a car's shape as seen is [left, right] / distance.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from occtrack._compat import tomllib
from occtrack.errors import OcctrackError

SENSOR_MODES = ("object-wise", "measurement-wise")


@dataclass(frozen=True)
class RoadConfig:
    """A straight road section [-half_length, half_length] of parallel lanes."""

    lanes_right: int = 2
    lanes_left: int = 2
    lane_spacing: float = 3.0
    half_length: float = 30.0

    @property
    def n_lanes(self) -> int:
        return self.lanes_right + self.lanes_left

    @property
    def distances(self) -> np.ndarray:
        """Distance of each lane from the sensor, nearest first."""
        return self.lane_spacing * np.arange(1, self.n_lanes + 1, dtype=float)

    @property
    def directions(self) -> np.ndarray:
        """+1 for lanes whose traffic moves towards +x, -1 for the others."""
        return np.r_[np.ones(self.lanes_right), -np.ones(self.lanes_left)]

    def validate(self) -> None:
        _check(self.lanes_right >= 0 and self.lanes_left >= 0 and self.n_lanes >= 1,
               "the road needs at least one lane")
        _check(self.lane_spacing > 0, "lane_spacing must be positive")
        _check(self.half_length > 0, "half_length must be positive")


@dataclass(frozen=True)
class SimulationConfig:
    """Traffic and sensor of the simulated highway.

    Cars enter each lane one after another. A new car's speed is drawn within `speed_step` of
    the previous car's (clipped to [min_speed, max_speed]) and its entry follows the previous
    one's by `entry_delay` plus a gap drawn uniformly up to `max_gap` steps, never so short that
    it could come within `min_headway` metres of the car ahead before that car has left the road.

    entry_delay = 1 reproduces the authors' simulator, whose countdown to the next entry starts
    one step after an entry: its traffic (about 8.3 cars on the road, 0.105 entries per lane
    per step, measured) is what the paper's Table III was scored on. With entry_delay = 0 the
    road holds about 8.7 cars (0.112 entries per lane per step), and per-step GOSPA grows with
    the number of cars.
    """

    road: RoadConfig = field(default_factory=RoadConfig)
    min_length: float = 2.0
    max_length: float = 7.0
    min_speed: float = 2.0
    max_speed: float = 5.0
    speed_step: float = 1.0
    max_gap: float = 15.0
    entry_delay: float = 1.0
    min_headway: float = 1.0
    noise_std: float = 0.75
    detection_probability: float = 0.99
    clutter_rate: float = 0.15
    clutter_min_length: float = 2.0
    clutter_max_length: float = 7.0

    def validate(self) -> None:
        self.road.validate()
        _check(0 < self.min_length <= self.max_length, "need 0 < min_length <= max_length")
        _check(0 < self.min_speed <= self.max_speed, "need 0 < min_speed <= max_speed")
        _check(self.speed_step >= 0, "speed_step must be >= 0")
        _check(self.max_gap > 0, "max_gap must be positive")
        _check(self.entry_delay >= 0, "entry_delay must be >= 0")
        _check(self.min_headway >= 0, "min_headway must be >= 0")
        _check(self.noise_std > 0, "noise_std must be positive")
        _check(0 <= self.detection_probability <= 1, "detection_probability must be in [0, 1]")
        _check(self.clutter_rate >= 0, "clutter_rate must be >= 0")
        _check(0 < self.clutter_min_length <= self.clutter_max_length,
               "need 0 < clutter_min_length <= clutter_max_length")


@dataclass(frozen=True)
class TrackerConfig:
    """The particle multi-Bernoulli tracker. The model part (noise, P_D, kappa, lambda_b, the
    ranges of lengths and speeds, the road) is what the paper lets the tracker know about the
    simulation; `TrackerConfig.matching(sim)` copies it. The rest are the filter's own settings.

    birth_rate: lambda_b, expected new cars per lane per step: the simulator's mean entry rate
    (0.105 measured over 10^5 steps with the default settings; the prototype used 0.15).
    survival: P_S of a car whose rear is still on the road section (0 once it has left).
    particles: per track; undetected_particles / birth_particles: per lane, for the Poisson
    intensity of cars not yet detected.
    """

    road: RoadConfig = field(default_factory=RoadConfig)
    min_length: float = 2.0
    max_length: float = 7.0
    min_speed: float = 2.0
    max_speed: float = 5.0
    noise_std: float = 0.75
    detection_probability: float = 0.99
    clutter_rate: float = 0.15
    clutter_min_length: float = 2.0
    clutter_max_length: float = 7.0
    birth_rate: float = 0.105
    survival: float = 0.999
    particles: int = 768
    max_tracks: int = 64
    undetected_particles: int = 256
    birth_particles: int = 256
    report_threshold: float = 0.5
    prune_threshold: float = 1e-3
    resample_threshold: float = 0.5
    kernel_bandwidth: float = 0.55
    lbp_tol: float = 1e-7
    lbp_max_iter: int = 1000
    expval_sharpness: float = 10.0
    expval_min_visible: float = 0.01
    grid_cells: int = 101

    @classmethod
    def matching(cls, sim: SimulationConfig, **overrides) -> TrackerConfig:
        """The tracker that knows the simulation's parameters (as the paper's does)."""
        known = {f.name: getattr(sim, f.name) for f in fields(sim)
                 if f.name in {g.name for g in fields(cls)}}
        return cls(**{**known, **overrides})

    def validate(self) -> None:
        self.road.validate()
        _check(0 < self.min_length <= self.max_length, "need 0 < min_length <= max_length")
        _check(0 < self.min_speed <= self.max_speed, "need 0 < min_speed <= max_speed")
        _check(self.noise_std > 0, "noise_std must be positive")
        _check(0 < self.detection_probability <= 1, "detection_probability must be in (0, 1]")
        _check(self.clutter_rate >= 0, "clutter_rate must be >= 0")
        _check(self.birth_rate > 0, "birth_rate must be positive")
        _check(0 <= self.survival <= 1, "survival must be in [0, 1]")
        for name in ("particles", "max_tracks", "undetected_particles", "birth_particles",
                     "lbp_max_iter", "grid_cells"):
            _check(getattr(self, name) >= 1, f"{name} must be at least 1")
        _check(0 < self.report_threshold < 1, "report_threshold must be in (0, 1)")
        _check(0 <= self.prune_threshold < self.report_threshold,
               "prune_threshold must be in [0, report_threshold)")
        _check(0 <= self.resample_threshold <= 1, "resample_threshold must be in [0, 1]")
        _check(0 <= self.kernel_bandwidth < 1, "kernel_bandwidth must be in [0, 1)")
        _check(self.expval_sharpness > 0, "expval_sharpness must be positive")
        _check(0 <= self.expval_min_visible <= 1, "expval_min_visible must be in [0, 1]")


def load_config(path: str | Path) -> tuple[SimulationConfig, TrackerConfig]:
    """The simulation and the tracker from a TOML file: a [simulation] table (its road in
    [simulation.road]) and a [tracker] table, keys as the dataclass fields. The tracker knows
    the simulation's model parameters (`TrackerConfig.matching`) unless [tracker] sets them."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as err:
        raise OcctrackError(f"cannot read: {err.strerror}", str(path)) from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
        raise OcctrackError(f"not valid TOML: {err}", str(path)) from None
    unknown = sorted(set(data) - {"simulation", "tracker"})
    sim = dict(data.get("simulation", {}))
    road = dict(sim.pop("road", {}))
    tracker = dict(data.get("tracker", {}))
    unknown += [f"simulation.{k}" for k in sorted(set(sim) - _names(SimulationConfig))]
    unknown += [f"simulation.road.{k}" for k in sorted(set(road) - _names(RoadConfig))]
    unknown += [f"tracker.{k}" for k in sorted(set(tracker) - _names(TrackerConfig) - {"road"})]
    if unknown:
        raise OcctrackError(f"unknown setting(s): {', '.join(unknown)}", str(path))
    if "road" in tracker:
        raise OcctrackError("the tracker uses the simulation's road; set it in "
                            "[simulation.road]", str(path))
    try:
        simulation = replace(SimulationConfig(**sim), road=RoadConfig(**road))
        simulation.validate()
        tracking = TrackerConfig.matching(simulation, **tracker)
        tracking.validate()
    except (TypeError, OcctrackError) as err:
        raise OcctrackError(str(err), str(path)) from None
    return simulation, tracking


def _names(kind: type) -> set[str]:
    return {f.name for f in fields(kind)}


def _check(condition: bool, message: str) -> None:
    if not condition:
        raise OcctrackError(message)
