"""The settings schema (floor 1): every TOML table's fields, types and ranges, one loader.

Here: the box tracker (`TrackerConfig`, a file's top-level keys) and the machinery every table
uses (`load_toml`, `build`: names and types; `check_ranges`: ranges, in the messages a user
reads). `occtrack.config.highway`: the highway study's tables, [simulation], [simulation.road]
and [tracker] (`HighwayTrackerConfig`). The CLI, the API and the simulations all read these.

The box tracker's settings:

Every setting is in units that transfer between cameras, resolutions and frame rates:
lengths in box heights (a person's image size sets the scale of their noise and speed, which
is what perspective does), rates per second, and the clutter and birth terms relative to the
image. The paper's pixel settings for MOT17-04 (12 px edge noise, 11.6 px / sqrt(s) process
noise, ...) are converted at that sequence's median detection height, 175 px, so the paper's
tuning is kept where it was made and scales everywhere else. The image size and frame rate
come from the sequence (`seqinfo.ini`, flags), never from a default meant for one camera.

A TOML file holds any subset of the fields at top level, e.g.

    occlusion = "measurement-wise"
    image_size = [1280, 720]
    edge_noise = 0.05
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from pathlib import Path

from occtrack._compat import tomllib
from occtrack.errors import OcctrackError, opening

OCCLUSION_NAMES = ("none", "object-wise", "measurement-wise")
MIN_FPS, MAX_FPS = 0.01, 10_000.0
MAX_IMAGE_SIDE = 100_000.0
CAMERA_MOTION_NAMES = ("detections", "none")
CONFIDENCE_CENTRES = ("detection", "posterior")
# integer settings whose size sets memory or run time: far beyond any scene, short of a hang
INTEGER_RANGES = {"frame_step": (1, 10_000), "capacity": (0, 10_000_000),
                  "max_labels": (0, 1_000_000), "max_components_per_object": (0, 100_000),
                  "lbp_max_iterations": (1, 100_000), "confirm_hits": (1, 1_000),
                  "confirm_window": (1, 1_000)}


@dataclass(frozen=True)
class TrackerConfig:
    """Every setting of the Gaussian-mixture PMB box tracker.

    Rates are per second and noises per square-root second, so the settings hold at any
    frame rate; dt = frame_step / fps seconds pass between tracked frames.

    The default occlusion model is object-wise: an object's hit term carries its own
    visibility, so an object still hidden behind a tracked one cannot take a detection that
    shows up near where it was lost (measurement-wise weighs a hit by the detection's escape
    only, and its long-hidden objects take the next person to appear there: on MOT17-04, -11
    and -05, 3, 3 and 7 identity jumps after a gap of more than 10 frames against 0, 1 and 7;
    docs/occlusion-models.md).
    """

    occlusion: str = "object-wise"  # none, object-wise or measurement-wise
    image_size: tuple[float, float] = (1920.0, 1080.0)  # width, height in px
    fps: float = 30.0  # frames per second of the sequence
    frame_step: int = 1  # track every frame_step-th frame, report every frame
    # s: after a longer gap between two frames nothing can be carried across (a prediction
    # over an hour says nothing); every track ends with a warning and tracking starts afresh
    max_gap: float = 600.0
    camera_motion: str = "detections"  # estimate the camera's shift from the detections, or
    # "none" (a still camera); a per-frame motion given to Tracker.step always wins
    camera_expansion: bool = False  # with "detections", also the camera's forward motion
    # (each box moves away from the image centre by k h, h its height: tracker.camera)

    # 0: grow with the scene (arrays double when full; memory follows the people in view, not
    # the time); a positive number is a hard limit, reported once (a warning) when it bites:
    capacity: int = 0  # Gaussian components, all objects and the Poisson part (paper: 2048)
    max_labels: int = 0  # labelled Bernoullis; past the limit the weakest are recycled (paper: 72)
    report_existence: float = 0.5  # report an object when r exceeds this
    # a detected box's confidence (occtrack.tracker.confidence) takes the posterior box about
    # its mean, the exact form ("posterior"), or the posterior's spread about the detection
    # itself ("detection": leaves out how far the detection lies from the prediction; too sure)
    confidence_centre: str = "posterior"

    # lengths below are in units of the box's own height h (h of the component's mean box)
    edge_noise: float = 0.069  # std of each measured box edge, h (12 px at h = 175 px)
    # a detection's edges are Gaussian about the prediction with weight 1 - tail_weight, and
    # tail_scale times as spread with weight tail_weight: the few boxes that jump far (an
    # approaching car, a half-hidden person's visible part) stay the track's rather than
    # starting a twin (occtrack.models.edge_tail; 0: a Gaussian, as before); the weight is
    # fixed, or with learn_tail_weight learnt by online EM with this as its prior
    tail_weight: float = 0.05
    tail_scale: float = 3.0
    learn_tail_weight: bool = False
    border_margin: float = 1.0  # an edge this close to the border is unmeasured, px
    # an edge beyond the image border by more than border_margin is the detector's estimate of
    # the part the image does not show, measured like any other (models.box); false: censored
    # like an edge on the border (a detector that pads the image)
    extrapolated_edges: bool = True
    aspect_prior: bool = True  # an axis the border cuts takes its half-size from the other
    # through the aspect ratio of the whole detections so far (occtrack.models.aspect)

    position_noise: float = 0.066  # process noise of box centres, h / sqrt(s)
    velocity_noise: float = 0.5  # of velocities, h / s / sqrt(s)
    size_noise: float = 0.044  # of half-sizes, h / sqrt(s); with learn_size_noise the prior
    # of the value learnt from the sizes of the detections the tracks take (a car the camera
    # drives up to grows by tens of percent a second, a pedestrian beside a camera hardly
    # changes size: models.motion.SizeNoiseLearner)
    learn_size_noise: bool = True
    velocity_time: float = math.inf  # s: velocities relax to 0 with this time constant
    # (models.motion); inf: constant velocity, the paper's model
    coast_velocity_time: float = 0.1  # s: the same, for an object missed at its last update

    death_rate: float = 0.075  # per second, objects inside the image
    exit_survival: float = 0.4  # per tracked frame, objects whose centre left the image

    detectability: float | None = None  # stationary P_D; None: 0.9 without occlusion, else 0.93
    detectability_ratio: float = 0.99  # fraction of a departure forgotten in half a second
    occludability: float = 0.8  # stationary probability that a measurement can be hidden
    occludability_ratio: float = 0.8
    # learn the stationary occludability from how often the detector still finds the objects
    # the occlusion model calls hidden (a detector trained on amodal boxes finds most of
    # them), occludability the prior: models.occludability.OccludabilityLearner
    learn_occludability: bool = True
    birth_detectability: float = 0.9
    birth_occludability: float = 0.5

    # kappa p_F(z) = clutter_rate / (W H w h) / score^power: a false box falls anywhere in the
    # image with a scale-free size, so its density per px^4 is 1 / (W H w h) (dimensionless rate)
    clutter_rate: float = 5.0
    clutter_score_power: float = 2.0
    score_floor: float = 0.05  # scores are clipped to [score_floor, 1] first
    # learn the score term's shape from the detector at hand (score^-power the prior; the
    # level at the top scores kept: models.score_model.ScoreLearner)
    learn_score_model: bool = True

    edge_birth_rate: float = 6.94  # expected new objects per second per image edge
    spread_birth_rate: float = 1.0  # per second, anywhere in the image
    initial_objects: float = 100.0  # Poisson mass spread over the image at the first frame
    inward_speed: float = 0.26  # mean speed of objects entering at an edge, h / s
    birth_speed_std: float = 0.51  # h / s
    birth_half_size: tuple[float, float] | None = None  # px; None: learnt from the detections
    birth_half_size_std: tuple[float, float] | None = None

    # a labelled Bernoulli is confirmed after confirm_hits detections within its first
    # confirm_window tracked frames, else deleted (its detections were clutter); occlusion
    # explains the misses of confirmed objects only
    confirm_hits: int = 3
    confirm_window: int = 5
    # a box is reported when its confidence (the probability that it is a real object at that
    # place, occtrack.tracker.confidence) is at least this: by default, when it is more likely
    # right than wrong; 0: every object with existence above report_existence
    report_min_confidence: float = 0.5
    # optional limits on top, off by default (the confidence does their work): an undetected
    # object is reported only while unseen at most report_coast_time s and its centre known
    # to within report_centre_std box heights (the defaults before the confidence: .67, .1)
    report_coast_time: float | None = None
    report_centre_std: float | None = None

    occlusion_gain: float = 2.0  # box geometry: clip(gain * overlap / area, 0, 1)
    occlusion_ramp: tuple[float, float] = (-0.1, 0.25)  # bottom-gap ramp, 0 at first, 1 at second
    occluder_min_existence: float = 0.1  # object-wise: objects with r above this occlude

    max_components_per_object: int = 16  # each object keeps its heaviest ones; 0: no limit
    prune_mass: float = 1e-5  # drop components lighter than this
    label_min_existence: float = 1e-3  # Bernoullis weaker than this go to the Poisson part
    # an undetected object whose predicted centre's standard deviation exceeds this many of its
    # half-sizes (either axis) has lost its place and goes to the Poisson part too (inf: never)
    identity_spread: float = 1.2
    merge_position: float = 0.017  # merge components of one object in one cell this wide, h
    merge_velocity: float = 0.057  # h / s
    lbp_tolerance: float = 1e-7  # stop loopy BP when messages change less than this
    lbp_max_iterations: int = 200
    # association, likelihoods and occlusion only over the pairs that can interact: a
    # (component, detection) pair more than gate_sigmas standard deviations apart on a box edge
    # is skipped (its likelihood is below e^(-gate_sigmas^2 / 2) of the component's best), and
    # loopy BP runs cluster by cluster; false computes every pair (for checking)
    gating: bool = True
    gate_sigmas: float = 9.0

    def __post_init__(self) -> None:
        # the API checks what the TOML loader checks (`build`), naming the field: a type
        # that fits (numpy's numbers too) is taken as the field's, anything else refused
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if value is None and field.default is None:
                continue
            object.__setattr__(self, field.name, _coerce(field.name, value, field.default))
        self.validate()

    @property
    def dt(self) -> float:
        return self.frame_step / self.fps

    @property
    def stationary_detectability(self) -> float:
        if self.detectability is not None:
            return self.detectability
        return 0.9 if self.occlusion == "none" else 0.93

    def replace(self, **changes) -> TrackerConfig:
        return dataclasses.replace(self, **changes)

    def validate(self) -> None:
        """Raise ValueError naming the first setting out of range."""
        if self.occlusion not in OCCLUSION_NAMES:
            raise ValueError(f"occlusion must be one of {', '.join(OCCLUSION_NAMES)}, "
                             f"not {self.occlusion!r}")
        for name, (low, high) in INTEGER_RANGES.items():
            value = getattr(self, name)
            if not low <= value <= high:
                raise ValueError(f"{name} must be between {low} and {high}, not {value}")
        if self.camera_motion not in CAMERA_MOTION_NAMES:
            raise ValueError(f"camera_motion must be one of {', '.join(CAMERA_MOTION_NAMES)}, "
                             f"not {self.camera_motion!r}")
        if self.confidence_centre not in CONFIDENCE_CENTRES:
            raise ValueError(f"confidence_centre must be one of {', '.join(CONFIDENCE_CENTRES)}"
                             f", not {self.confidence_centre!r}")
        w, h = self.image_size
        positive = {"image width": w, "image height": h, "fps": self.fps,
                    "edge_noise": self.edge_noise,
                    "birth_speed_std": self.birth_speed_std, "prune_mass": self.prune_mass,
                    "merge_position": self.merge_position, "merge_velocity": self.merge_velocity,
                    "lbp_tolerance": self.lbp_tolerance, "occlusion_gain": self.occlusion_gain,
                    "clutter_rate": self.clutter_rate, "score_floor": self.score_floor,
                    "gate_sigmas": self.gate_sigmas}
        if self.report_centre_std is not None:
            positive["report_centre_std"] = self.report_centre_std
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, not {value}")
        # what a camera can be: from a frame every 100 s (time-lapse) to 10,000 a second
        # (high speed), images up to 100,000 px a side (a gigapixel panorama is 40,000)
        if not MIN_FPS <= self.fps <= MAX_FPS:
            raise ValueError(f"fps must be between {MIN_FPS:g} and {MAX_FPS:g} frames a "
                             f"second, not {self.fps:g}")
        for name, value in (("image width", w), ("image height", h)):
            if value > MAX_IMAGE_SIDE:
                raise ValueError(f"{name} must be at most {MAX_IMAGE_SIDE:g} px, not "
                                 f"{value:g}")
        if not self.max_gap > 0:
            raise ValueError(f"max_gap must be a positive number of seconds, not "
                             f"{self.max_gap}")
        non_negative = {"position_noise": self.position_noise,
                        "velocity_noise": self.velocity_noise, "size_noise": self.size_noise,
                        "death_rate": self.death_rate, "border_margin": self.border_margin,
                        "edge_birth_rate": self.edge_birth_rate,
                        "spread_birth_rate": self.spread_birth_rate,
                        "initial_objects": self.initial_objects,
                        "inward_speed": self.inward_speed,
                        "clutter_score_power": self.clutter_score_power}
        if self.report_coast_time is not None:
            non_negative["report_coast_time"] = self.report_coast_time
        for name, value in non_negative.items():
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a number >= 0, not {value}")
        probabilities = {"report_existence": self.report_existence,
                         "report_min_confidence": self.report_min_confidence,
                         "exit_survival": self.exit_survival,
                         "detectability": self.stationary_detectability,
                         "detectability_ratio": self.detectability_ratio,
                         "occludability": self.occludability,
                         "occludability_ratio": self.occludability_ratio,
                         "birth_detectability": self.birth_detectability,
                         "birth_occludability": self.birth_occludability,
                         "occluder_min_existence": self.occluder_min_existence,
                         "label_min_existence": self.label_min_existence}
        for name, value in probabilities.items():
            if not (0.0 <= value <= 1.0):
                raise ValueError(f"{name} must be a probability in [0, 1], not {value}")
        if not 0.0 <= self.tail_weight <= 0.5:
            raise ValueError(f"tail_weight must be in [0, 0.5] (the tail never the likelier "
                             f"explanation), not {self.tail_weight}")
        if not (math.isfinite(self.tail_scale) and self.tail_scale > 1):
            raise ValueError(f"tail_scale must be a number above 1, not {self.tail_scale}")
        if not self.identity_spread > 0:
            raise ValueError(f"identity_spread must be a positive number of half-sizes (inf: "
                             f"never), not {self.identity_spread}")
        for name in ("velocity_time", "coast_velocity_time"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be a positive number of seconds (inf: "
                                 f"constant velocity), not {getattr(self, name)}")
        if not 1 <= self.confirm_hits <= self.confirm_window:
            raise ValueError(f"confirm_hits must be between 1 and confirm_window "
                             f"({self.confirm_window}), not {self.confirm_hits}")
        if self.capacity != 0 and self.capacity < 16:
            raise ValueError(f"capacity must be at least 16 components, or 0 to grow with the "
                             f"scene, not {self.capacity}")
        if not self.occlusion_ramp[1] > self.occlusion_ramp[0]:
            raise ValueError("occlusion_ramp must rise: (zero point, one point)")
        for name in ("birth_half_size", "birth_half_size_std"):
            value = getattr(self, name)
            if value is not None and not (len(value) == 2 and all(v > 0 for v in value)):
                raise ValueError(f"{name} must be two positive numbers (horizontal, vertical)")

    @classmethod
    def from_dict(cls, values: dict, source: str = "configuration") -> TrackerConfig:
        """Build from plain values (as TOML gives them), checking names and types."""
        return build(cls, values, source)

    @classmethod
    def from_toml(cls, path: str | Path, **overrides) -> TrackerConfig:
        """Read a TOML file; `overrides` (not None) win over the file."""
        values = load_toml(path)
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls.from_dict(values, str(path))


def load_toml(path: str | Path) -> dict:
    """The settings in a TOML file, unchecked; OcctrackError if it cannot be read."""
    p = str(path)
    try:
        with opening(p, "a TOML file"), open(p, "rb") as fh:
            return tomllib.load(fh)
    except OSError as err:
        raise OcctrackError(f"cannot read: {err.strerror}", p) from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
        raise OcctrackError(f"not valid TOML: {err}", p) from None


def build(cls, values: dict, source: str = "configuration", table: str = ""):
    """An instance of the settings dataclass `cls` from plain values (as TOML gives them):
    unknown names, wrong types and out-of-range values are an OcctrackError naming the
    setting (and its `table`, when the file has several) and `source`."""
    where = f"[{table}] " if table else ""
    fields = {f.name: f for f in dataclasses.fields(cls)
              if f.default is not dataclasses.MISSING}
    unknown = sorted(set(values) - set(fields))
    if unknown:
        shown = f"{table}.{unknown[0]}" if table else unknown[0]
        raise OcctrackError(f"unknown setting {shown!r}; known settings"
                            f"{' of [' + table + ']' if table else ''}: "
                            f"{', '.join(fields)}", source)
    clean = {}
    for name, value in values.items():
        try:
            clean[name] = _coerce(name, value, fields[name].default)
        except (TypeError, ValueError) as err:
            raise OcctrackError(where + str(err), source) from None
    try:
        return cls(**clean)
    except ValueError as err:
        raise OcctrackError(where + str(err), source) from None


def check_ranges(settings, ranges: dict[str, str]) -> None:
    """ValueError naming the first setting outside its range. A range is written as an
    interval, "[0, 1]", "(0, 1000]", "[1, 100000]"; integer settings read "between"."""
    for name, interval in ranges.items():
        value = getattr(settings, name)
        low, high = (float(v) for v in interval[1:-1].split(","))
        above = value > low if interval[0] == "(" else value >= low
        below = value < high if interval[-1] == ")" else value <= high
        if not (above and below):  # NaN fails both
            if isinstance(value, int) and not isinstance(value, bool):
                raise ValueError(f"{name} must be between {low:g} and {high:g}, not {value}")
            raise ValueError(f"{name} must be a number in {interval}, not {value}")


def _is_bool(value) -> bool:
    """Python's or numpy's bool (numpy is not imported here: the settings load without it)."""
    kind = type(value)
    return isinstance(value, bool) or (kind.__module__ == "numpy"
                                       and kind.__name__ in ("bool", "bool_"))


def _coerce(name: str, value, default):
    """Check a value (from TOML or the API) against the type of the field's default, and
    give it that type: a whole number for an integer field, a float for a number, a pair of
    floats for a pair (numpy's numbers count as numbers)."""
    if isinstance(default, bool):
        if not _is_bool(value):
            raise TypeError(f"{name} must be true or false, not {value!r}")
        return bool(value)
    if isinstance(default, str):
        if not isinstance(value, str):
            raise TypeError(f"{name} must be a string, not {value!r}")
        return value
    if isinstance(default, int):
        if _is_bool(value) or not isinstance(value, numbers.Integral):
            raise TypeError(f"{name} must be an integer, not {value!r}")
        return int(value)
    if isinstance(default, tuple) or (default is None and isinstance(value, list | tuple)):
        if not isinstance(value, list | tuple) or len(value) != 2 or not all(
                isinstance(v, numbers.Real) and not _is_bool(v) for v in value):
            raise TypeError(f"{name} must be a pair of numbers like [1.0, 2.0], not {value!r}")
        return (float(value[0]), float(value[1]))
    if _is_bool(value) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, not {value!r}")
    return float(value)


# The highway study's tables ([simulation], [simulation.road], [tracker]); imported last, as
# they use the machinery above.
from occtrack.config.highway import (  # noqa: E402
    SENSOR_MODES,
    HighwayTrackerConfig,
    RoadConfig,
    SimulationConfig,
    highway_from_dict,
    load_highway,
)

__all__ = ["CAMERA_MOTION_NAMES", "CONFIDENCE_CENTRES", "INTEGER_RANGES", "OCCLUSION_NAMES",
           "SENSOR_MODES",
           "HighwayTrackerConfig", "RoadConfig", "SimulationConfig", "TrackerConfig", "build",
           "check_ranges", "highway_from_dict", "load_highway", "load_toml"]
