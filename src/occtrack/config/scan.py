"""Settings of the lidar scan tracker (`occtrack.tracker.scan.ScanTracker`): the one
Gaussian-mixture PMB filter of the box tracker, fed whole 2-D scans (issue 24, item 2).

Lengths are in metres and times in seconds, in the world frame of the scans. The filter itself
keeps its own settings (`TrackerConfig`, lengths in units of an object's size, "h"); a scan
tracker's object is a disc of radius `radius`, so h is its diameter and `filter_config`
converts. The filter's frame is centimetres with the origin at the corner of the square
[-max_range, max_range]^2 about the sensor: the disc's half-size (25 cm) is then far above the
box tracker's smallest box (4 px, `occtrack.models.box.MIN_HEIGHT`), which would otherwise set
the unit of the motion noises.

Every number has a range (`SCAN_RANGES`), checked like the other tables of the schema, and a
TOML [scan] table (`from_dict`) goes through the same `build`. A scan tracker's settings file
holds that one table (`scan_table`), e.g.

    [scan]
    occlusion = "measurement-wise"
    max_range = 30.0
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from occtrack.config import TrackerConfig, build, check_ranges
from occtrack.errors import OcctrackError

SCAN_OCCLUSION_NAMES = ("none", "measurement-wise")
SCAN_LIKELIHOOD_NAMES = ("derived", "hand-made", "cluster")
SCAN_BODY_NAMES = ("disc", "legs")
CENTIMETRES = 100.0  # filter units a metre

SCAN_RANGES = {
    "p_d": "[0, 1]", "range_noise": "(0, 100]", "clutter_per_scan": "(0, 100000]",
    "max_range": "(0, 100000]", "radius": "(0, 100]", "leg_radius": "(0, 100]",
    "leg_separation": "[0, 100]", "leg_gate": "[0, 100]", "leg_hold": "[0, 100000]",
    "segment_jump": "(0, 1000]", "clutter_memory": "(0, 1000000]",
    "segment_gap": "[0, 1000]", "min_birth_beams": "[1, 100000]",
    "detectability": "[0, 1]", "occludability": "[0, 1]", "birth_occludability": "[0, 1]",
    "position_noise": "[0, 1000]", "velocity_noise": "[0, 1000]",
    "velocity_time": "(0, inf]", "coast_velocity_time": "(0, inf]", "death_rate": "[0, 1000]",
    "birth_mass": "(0, 1]", "edge_birth_mass": "(0, 1]", "initial_birth_mass": "(0, 1]",
    "edge_width": "[0, 100000]", "birth_position_std": "(0, 1000]",
    "birth_speed_std": "(0, 1000]", "report_existence": "[0, 1]",
    "report_min_confidence": "[0, 1]", "confirm_hits": "[1, 1000]",
    "confirm_window": "[1, 1000]", "gate_sigmas": "(0, 1000]", "max_gap": "(0, 1000000]",
}


@dataclass(frozen=True)
class ScanTrackerConfig:
    """Every setting of the scan tracker.

    Sensor (section V's beam model, `occtrack.models.beam.BeamModel`): a surface on a beam
    returns with probability `p_d` at its range plus N(0, range_noise^2); `clutter_per_scan`
    spurious returns a scan, uniform over the beams and over [0, max_range]; the nearest return
    is reported, none before `max_range`.

    Objects (`body`): "disc", a person is one disc of `radius` m (the simulated walkway's
    people); "legs", a laser at leg height, a person is two legs, each tracked as a disc of
    `leg_radius` m and paired into people (`occtrack.tracker.people.LegPairing`: legs at most
    `leg_separation` m apart, a person who lost both legs found again within `leg_gate` m for
    `leg_hold` s), reported at the legs' midpoint (with `leg_pairs_only`, once seen on two
    legs).

    `static_scene`: keep an occupancy grid of what stands still (`models.static_scene`) and
    give a segment's birth the probability that it is not part of it, so walls and posts do
    not become people (it needs the sensor's pose when the sensor moves).

    `clutter_map`: learn the clutter's density by range from the sensor as the scans come
    (`models.clutter_map`: the returns no likely object explains, over the beam that reached
    them, faded over `clutter_memory` s), so that a segment where spurious returns are common (the
    ground a tilted laser strikes, the flicker at the end of its range) is weak evidence of a
    person; off, clutter is `clutter_per_scan` spread evenly over the range.

    Segments: a scan's returns are cut into runs of neighbouring beams whose ranges differ by
    less than `segment_jump` m (plus 4 range_noise), skipping at most `segment_gap` beams
    without a return; each is one measurement of at most one object.

    Filter: the segment-level P_D (`detectability`, a Markov feature as in the box tracker),
    `occludability` (the stationary probability that an object can be hidden, learnt per
    object; `birth_occludability` at birth), constant velocity with `position_noise` m / sqrt(s)
    and `velocity_noise` m / s / sqrt(s), velocities relaxing with `velocity_time` (and with
    `coast_velocity_time` while unseen), deaths at `death_rate` a second. Births: a segment of
    at least `min_birth_beams` beams adds a Poisson component at the disc its returns fit,
    `birth_position_std` m and `birth_speed_std` m/s about it, of mass `birth_mass` a scan
    (`edge_birth_mass` within `edge_width` m of max_range, where people walk in;
    `initial_birth_mass` at the first scan). A Bernoulli is confirmed after `confirm_hits`
    segments in its first `confirm_window` scans, else deleted; reported while its existence
    exceeds `report_existence` and its confidence (`tracker.scan`: the probability that it
    exists and its centre is within one radius of the true one) is at least
    `report_min_confidence` (0: every such track; 0.5: only while more likely right than not,
    which drops hidden tracks whose position has grown uncertain). `gate_sigmas`: a segment
    is looked at for a component only if it lies within the disc widened by this many
    position standard deviations.

    Likelihood (issue 24's baselines): "derived", a segment scored by `models.scan_segments`
    (its beams jointly, and section V's closed-form term on the object's other beams);
    "hand-made", the same with the other beams' term replaced by the fixed shape of Thrun et
    al. (`models.scan_hand_made`: beyond: low, closer: uniform); "cluster", cluster-then-track:
    each segment reduced to the centre of the disc it fits and tracked as a point
    (`models.point`), N(z; centre, P + cluster_noise^2 I). A cluster carries no beams, so
    "cluster" goes with occlusion "none" only.
    """

    occlusion: str = "measurement-wise"
    likelihood: str = "derived"
    body: str = "disc"
    p_d: float = 0.98
    range_noise: float = 0.02
    clutter_per_scan: float = 5.0
    max_range: float = 20.0
    radius: float = 0.25
    leg_radius: float = 0.1
    leg_separation: float = 0.8
    leg_gate: float = 0.5
    leg_hold: float = 1.0
    leg_pairs_only: bool = True
    static_scene: bool = False
    clutter_map: bool = True
    clutter_memory: float = 10.0
    segment_jump: float = 0.3
    segment_gap: int = 1
    min_birth_beams: int = 2
    detectability: float = 0.95
    occludability: float = 0.98
    birth_occludability: float = 0.5
    position_noise: float = 0.05
    velocity_noise: float = 0.3
    velocity_time: float = math.inf
    coast_velocity_time: float = math.inf
    death_rate: float = 0.05
    birth_mass: float = 0.01
    edge_birth_mass: float = 0.1
    initial_birth_mass: float = 0.5
    edge_width: float = 3.0
    birth_position_std: float = 0.1
    birth_speed_std: float = 1.0
    report_existence: float = 0.5
    report_min_confidence: float = 0.0
    confirm_hits: int = 3
    confirm_window: int = 5
    gate_sigmas: float = 5.0
    cluster_noise: float = 0.1
    max_gap: float = 600.0  # s between scans after which every track ends (as the box tracker's)

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """ValueError naming the first setting out of range or at odds with another."""
        if self.occlusion not in SCAN_OCCLUSION_NAMES:
            raise ValueError(f"occlusion must be one of {', '.join(SCAN_OCCLUSION_NAMES)}, "
                             f"not {self.occlusion!r}")
        if self.likelihood not in SCAN_LIKELIHOOD_NAMES:
            raise ValueError(f"likelihood must be one of {', '.join(SCAN_LIKELIHOOD_NAMES)}, "
                             f"not {self.likelihood!r}")
        if self.body not in SCAN_BODY_NAMES:
            raise ValueError(f"body must be one of {', '.join(SCAN_BODY_NAMES)}, "
                             f"not {self.body!r}")
        if self.likelihood == "cluster" and self.occlusion != "none":
            raise ValueError("likelihood 'cluster' (points, no beams) goes with occlusion "
                             f"'none', not {self.occlusion!r}")
        check_ranges(self, SCAN_RANGES)
        if self.confirm_hits > self.confirm_window:
            raise ValueError(f"confirm_hits must be between 1 and confirm_window "
                             f"({self.confirm_window}), not {self.confirm_hits}")

    def replace(self, **changes) -> ScanTrackerConfig:
        return dataclasses.replace(self, **changes)

    @classmethod
    def from_dict(cls, values: dict, source: str = "configuration") -> ScanTrackerConfig:
        """From plain values (a TOML [scan] table), checking names, types and ranges."""
        return build(cls, values, source, "scan")

    @property
    def disc_radius(self) -> float:
        """The radius of the discs the filter tracks, m: a person's, or a leg's."""
        return self.leg_radius if self.body == "legs" else self.radius

    @property
    def unit(self) -> float:
        """The filter's unit of length h in metres: the disc's diameter."""
        return 2.0 * self.disc_radius

    def filter_config(self, rate: float = 10.0) -> TrackerConfig:
        """The filter's settings: this table's, in units of the disc's diameter (h) and
        the filter frame (`occtrack.models.scan_segments`: cm, the square about the sensor)."""
        h = self.unit
        side = 2.0 * self.max_range * CENTIMETRES
        return TrackerConfig(
            occlusion=self.occlusion, image_size=(side, side), fps=rate,
            camera_motion="none", edge_noise=self.range_noise / h,
            position_noise=self.position_noise / h, velocity_noise=self.velocity_noise / h,
            size_noise=0.0, velocity_time=self.velocity_time,
            coast_velocity_time=self.coast_velocity_time, death_rate=self.death_rate,
            exit_survival=0.1, detectability=self.detectability,
            occludability=self.occludability, birth_detectability=self.detectability,
            birth_occludability=self.birth_occludability, confirm_hits=self.confirm_hits,
            confirm_window=self.confirm_window, report_existence=self.report_existence,
            report_min_confidence=0.0, gate_sigmas=self.gate_sigmas,
            birth_speed_std=self.birth_speed_std / h, inward_speed=0.0,
            identity_spread=math.inf)  # (at 1.2 it bridges 153 of 191 full occlusions, not 182)


def scan_table(data: dict, source: str = "configuration") -> dict:
    """The [scan] table of a scan tracker's settings file (as TOML gives it), unchecked
    within (`ScanTrackerConfig.from_dict` checks it); any other table or top-level setting is
    an OcctrackError naming it and `source`."""
    other = sorted(set(data) - {"scan"})
    if other:
        name = other[0]
        if isinstance(data[name], dict):
            raise OcctrackError(f"unknown table [{name}]; a scan tracker settings file holds "
                                f"one [scan] table", source)
        raise OcctrackError(f"unknown setting {name!r} outside a table; the scan tracker's "
                            f"settings go in a [scan] table", source)
    table = data.get("scan", {})
    if not isinstance(table, dict):
        raise OcctrackError(f"[scan] must be a table of settings, not {table!r}", source)
    return dict(table)
