"""Settings of the highway study (paper appendix): the road, the simulation and the trackers.

Defaults are the paper's values (DESIGN.md section 2.3). Names from the literature: P_D is the
detection probability, kappa the clutter rate (expected false measurements per step), lambda_b
the birth rate (expected new cars per lane per step), r a track's probability of existence.

Coordinates: x runs along the road, the point sensor sits at x = 0 beside it, and lane k
(k = 1 nearest) is at distance `lane_spacing * k`. A car is the interval [left, left + length]
of its lane; its velocity is signed (+ in the first `lanes_right` lanes, - in the others). The
sensor sees by angle, so a car's shape as seen is [left, right] / distance.

A TOML file holds a [simulation] table (its road in [simulation.road]) and a [tracker] table.
Every number has a range (`*_RANGES`, intervals as the error message prints them): wide
enough for any study, short of a setting that exhausts memory or runs for ever.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path

from occtrack.config import build, check_ranges, load_toml
from occtrack.errors import OcctrackError

SENSOR_MODES = ("object-wise", "measurement-wise")

ROAD_RANGES = {"lanes_right": "[0, 100]", "lanes_left": "[0, 100]",
               "lane_spacing": "(0, 1000]", "half_length": "(0, 100000]"}
# The car model, shared by the simulation and the tracker that knows it (metres, steps).
MODEL_RANGES = {"min_length": "(0, 1000]", "max_length": "(0, 1000]",
                "min_speed": "(0, 1000]", "max_speed": "(0, 1000]",
                "noise_std": "(0, 1000]", "clutter_rate": "[0, 1000]",
                "clutter_min_length": "(0, 1000]", "clutter_max_length": "(0, 1000]"}
SIMULATION_RANGES = {**MODEL_RANGES, "detection_probability": "[0, 1]",
                     "speed_step": "[0, 1000]", "max_gap": "(0, 1000000]",
                     "entry_delay": "[0, 1000000]", "min_headway": "[0, 1000]"}
TRACKER_RANGES = {**MODEL_RANGES, "detection_probability": "(0, 1]",
                  "birth_rate": "(0, 1000]", "survival": "[0, 1]",
                  "particles": "[1, 100000]", "max_tracks": "[1, 100000]",
                  "undetected_particles": "[1, 100000]", "birth_particles": "[1, 100000]",
                  "report_threshold": "(0, 1)", "prune_threshold": "[0, 1)",
                  "resample_threshold": "[0, 1]", "kernel_bandwidth": "[0, 1)",
                  "lbp_tol": "(0, 1]", "lbp_max_iter": "[1, 100000]",
                  "expval_sharpness": "(0, 1000000]", "expval_min_visible": "[0, 1]",
                  "grid_cells": "[2, 100000]"}
MAX_TRACK_PARTICLES = 10_000_000  # max_tracks x particles: 240 MB of particle states


@dataclass(frozen=True)
class RoadConfig:
    """A straight road section [-half_length, half_length] of parallel lanes."""

    lanes_right: int = 2
    lanes_left: int = 2
    lane_spacing: float = 3.0
    half_length: float = 30.0

    def __post_init__(self) -> None:
        self.validate()

    @property
    def n_lanes(self) -> int:
        return self.lanes_right + self.lanes_left

    @property
    def distances(self):
        """Distance of each lane from the sensor, nearest first."""
        import numpy as np

        return self.lane_spacing * np.arange(1, self.n_lanes + 1, dtype=float)

    @property
    def directions(self):
        """+1 for lanes whose traffic moves towards +x, -1 for the others."""
        import numpy as np

        return np.r_[np.ones(self.lanes_right), -np.ones(self.lanes_left)]

    def validate(self) -> None:
        """ValueError naming the first setting out of range."""
        check_ranges(self, ROAD_RANGES)
        if self.n_lanes < 1:
            raise ValueError("the road needs at least one lane: lanes_right + lanes_left "
                             "must be at least 1")


def _check_order(settings, low: str, high: str) -> None:
    if not getattr(settings, low) <= getattr(settings, high):
        raise ValueError(f"{high} must be at least {low} ({getattr(settings, low)}), "
                         f"not {getattr(settings, high)}")


def _check_model(settings) -> None:
    for low, high in (("min_length", "max_length"), ("min_speed", "max_speed"),
                      ("clutter_min_length", "clutter_max_length")):
        _check_order(settings, low, high)


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

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """ValueError naming the first setting out of range."""
        self.road.validate()
        check_ranges(self, SIMULATION_RANGES)
        _check_model(self)


@dataclass(frozen=True)
class HighwayTrackerConfig:
    """The highway's particle multi-Bernoulli tracker. The model part (noise, P_D, kappa,
    lambda_b, the ranges of lengths and speeds, the road) is what the paper lets the tracker
    know about the simulation; `HighwayTrackerConfig.matching(sim)` copies it. The rest are the
    filter's own settings.

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

    def __post_init__(self) -> None:
        self.validate()

    @classmethod
    def matching(cls, sim: SimulationConfig, **overrides) -> HighwayTrackerConfig:
        """The tracker that knows the simulation's parameters (as the paper's does)."""
        known = {f.name: getattr(sim, f.name) for f in fields(sim)
                 if f.name in {g.name for g in fields(cls)}}
        return cls(**{**known, **overrides})

    def validate(self) -> None:
        """ValueError naming the first setting out of range."""
        self.road.validate()
        check_ranges(self, TRACKER_RANGES)
        _check_model(self)
        if not self.prune_threshold < self.report_threshold:
            raise ValueError(f"prune_threshold must be below report_threshold "
                             f"({self.report_threshold}), not {self.prune_threshold}")
        if self.max_tracks * self.particles > MAX_TRACK_PARTICLES:
            raise ValueError(f"max_tracks x particles must be at most {MAX_TRACK_PARTICLES} "
                             f"(memory), not {self.max_tracks} x {self.particles}")


def highway_from_dict(data: dict, source: str = "configuration"
                      ) -> tuple[SimulationConfig, HighwayTrackerConfig]:
    """The simulation and the tracker from plain tables (as TOML gives them): "simulation"
    (its road in "road") and "tracker", keys as the dataclass fields. The tracker knows the
    simulation's model parameters (`HighwayTrackerConfig.matching`) unless [tracker] sets
    them. OcctrackError naming table, setting and range for anything wrong."""
    unknown = sorted(set(data) - {"simulation", "tracker"})
    if unknown:
        raise OcctrackError(f"unknown table [{unknown[0]}]; a highway settings file holds "
                            f"[simulation], [simulation.road] and [tracker]", source)
    sim = _table(data, "simulation", source)
    road = _table(sim, "road", source, "simulation.road")
    tracker = _table(data, "tracker", source)
    if "road" in tracker:
        raise OcctrackError("the tracker uses the simulation's road; set it in "
                            "[simulation.road]", source)
    road_config = build(RoadConfig, road, source, "simulation.road")
    sim.pop("road", None)
    simulation = build(SimulationConfig, sim, source, "simulation")
    simulation = _replace_road(simulation, road_config, source, "simulation")
    known = {f.name: getattr(simulation, f.name) for f in fields(simulation)
             if f.name in _names(HighwayTrackerConfig) and f.name != "road"}
    tracking = build(HighwayTrackerConfig, {**known, **tracker}, source, "tracker")
    tracking = _replace_road(tracking, road_config, source, "tracker")
    return simulation, tracking


def load_highway(path: str | Path) -> tuple[SimulationConfig, HighwayTrackerConfig]:
    """The simulation and the tracker from a TOML file (`highway_from_dict`)."""
    return highway_from_dict(load_toml(path), str(path))


def _replace_road(settings, road: RoadConfig, source: str, table: str):
    from dataclasses import replace

    try:
        return replace(settings, road=road)
    except ValueError as err:  # a road that makes another setting out of range
        raise OcctrackError(f"[{table}] {err}", source) from None


def _table(data: dict, name: str, source: str, shown: str | None = None) -> dict:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise OcctrackError(f"[{shown or name}] must be a table of settings, not {value!r}",
                            source)
    return dict(value)


def _names(kind: type) -> set[str]:
    return {f.name for f in fields(kind)}
