"""Settings of the simulated lidar scene (`occtrack.scenarios.lidar.scene`).

A horizontally scanning range sensor at the origin of the world (x, y in metres, angles in
radians counter-clockwise from +x) looks at a walkway: people walk the strip
|x| <= half_length along lines parallel to x, each on a lane of its own at distance |y| from
the sensor's line (both sides), so nobody walks into anybody; optional vehicles drive on road
lanes beyond the people. Defaults are a 2-D lidar of the kind found on a mobile robot (720
beams over 360 degrees, 10 scans a second, 2 cm range noise, 20 m range) watching 20 people.

Every number has a range (`LIDAR_RANGES`, printed as intervals in the error message), as the
other tables of the schema.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from occtrack.config import check_ranges

SENSOR_MODES = ("object-wise", "measurement-wise")

LIDAR_RANGES = {
    "beams": "[1, 100000]", "fov_deg": "(0, 360]", "rate": "(0, 100000]",
    "range_noise": "[0, 100]", "p_d": "[0, 1]", "clutter_per_scan": "[0, 100000]",
    "max_range": "(0, 100000]", "people": "[0, 10000]", "person_radius": "(0, 100]",
    "min_speed": "(0, 1000]", "max_speed": "(0, 1000]", "stop_probability": "[0, 1]",
    "min_stop": "[0, 100000]", "max_stop": "[0, 100000]", "half_length": "(0, 100000]",
    "nearest_lane": "(0, 100000]", "lanes_a_side": "[0, 10000]", "lane_spacing": "(0, 100000]",
    "vehicles": "[0, 1000]", "vehicle_length": "(0, 1000]", "vehicle_width": "(0, 1000]",
    "vehicle_speed": "(0, 1000]", "road_distance": "(0, 100000]", "road_spacing": "(0, 1000]",
    "sensor_vx": "[-1000, 1000]", "sensor_vy": "[-1000, 1000]", "sensor_yaw_rate": "[-100, 100]",
}


@dataclass(frozen=True)
class LidarSceneConfig:
    """The sensor, the people and the vehicles of the lidar scene.

    Sensor: `beams` beams spread evenly over `fov_deg` degrees centred on the sensor's heading
    (beam k at angle -fov/2 + (k + 1/2) fov / beams), all of a scan taken at one time, `rate`
    scans a second. The nearest surface on a beam returns with probability `p_d`, its range
    plus N(0, range_noise^2); `clutter_per_scan` spurious returns a scan (Poisson), each on a
    beam drawn uniformly at a range uniform in [0, max_range], the nearest return reported.
    A beam with no return before `max_range` reports none. `sensor` says what a miss means:
    object-wise (surfaces are opaque: a missed object still blocks the beam) or
    measurement-wise (the paper's model: each object on the beam returns or not, and the
    nearest return hides the rest). The sensor moves at (sensor_vx, sensor_vy) m/s and turns
    at sensor_yaw_rate rad/s from the origin, heading +x.

    People: `people` lanes drawn without replacement from the slots at distances
    nearest_lane + j lane_spacing (j = 0 .. lanes_a_side - 1) on either side (lanes_a_side = 0:
    just enough, people / 2). A lane holds one person at a time, walking from one end of the
    strip to the other at a speed uniform in [min_speed, max_speed] m/s, towards +x on the
    +y side and -x on the other (`one_way_sides`; else either way); with `stop_probability`
    the person stands still once on the way, for a time uniform in [min_stop, max_stop] s.
    When one leaves, the next enters. Vehicles likewise, on road lanes at road_distance +
    j road_spacing alternating sides, rectangles of vehicle_length x vehicle_width at
    vehicle_speed m/s (+- 20 %).

    Why these defaults: seen from the side, a walkway hides people far along it, where their
    angular speeds v |y| / (x^2 + y^2) are small and, for people walking the same way, alike;
    a narrow walkway (lanes 1 to 6.4 m out for 20 people) walked one way a side, 36 m long,
    gives about 30 full occlusions of over a second a minute.
    """

    beams: int = 720
    fov_deg: float = 360.0
    rate: float = 10.0
    range_noise: float = 0.02
    p_d: float = 0.98
    clutter_per_scan: float = 5.0
    max_range: float = 20.0
    sensor: str = "object-wise"
    people: int = 20
    person_radius: float = 0.25
    min_speed: float = 1.0
    max_speed: float = 1.5
    stop_probability: float = 0.3
    min_stop: float = 2.0
    max_stop: float = 8.0
    half_length: float = 18.0
    nearest_lane: float = 1.0
    lane_spacing: float = 0.6
    lanes_a_side: int = 0
    one_way_sides: bool = True
    vehicles: int = 0
    vehicle_length: float = 4.5
    vehicle_width: float = 1.8
    vehicle_speed: float = 8.0
    road_distance: float = 14.0
    road_spacing: float = 3.5
    sensor_vx: float = 0.0
    sensor_vy: float = 0.0
    sensor_yaw_rate: float = 0.0

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """ValueError naming the first setting out of range or at odds with another."""
        check_ranges(self, LIDAR_RANGES)
        if self.sensor not in SENSOR_MODES:
            raise ValueError(f"sensor must be one of {', '.join(SENSOR_MODES)}, "
                             f"not {self.sensor!r}")
        for low, high in (("min_speed", "max_speed"), ("min_stop", "max_stop")):
            if getattr(self, low) > getattr(self, high):
                raise ValueError(f"{high} must be at least {low} ({getattr(self, low)})")
        if self.people > 2 * self.lane_slots:
            raise ValueError(f"{self.people} people need at least {math.ceil(self.people / 2)}"
                             f" lanes_a_side (one person a lane), not {self.lanes_a_side}")
        if self.lane_spacing <= 2 * self.person_radius:
            raise ValueError("lane_spacing must exceed a person's diameter (2 person_radius),"
                             " or people on next lanes would overlap")
        if self.vehicles and self.road_distance - self.vehicle_width / 2 <= (
                self.people_band + self.person_radius):
            raise ValueError("road_distance puts vehicles on the people's lanes; "
                             "raise road_distance")

    @property
    def lane_slots(self) -> int:
        """People's lanes a side: `lanes_a_side`, or 0 for just enough (people / 2)."""
        return self.lanes_a_side or math.ceil(self.people / 2)

    @property
    def people_band(self) -> float:
        """Distance of the farthest lane people may walk on: `people` lanes a side, of which
        `people` of the 2 `people` are drawn."""
        return self.nearest_lane + max(self.lane_slots - 1, 0) * self.lane_spacing

    @property
    def period(self) -> float:
        return 1.0 / self.rate
