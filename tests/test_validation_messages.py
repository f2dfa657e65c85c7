"""Every refusal of `TrackerConfig.validate` and of the public API's input checks names the
setting or argument at fault, in the words a caller reads (issue 15, item 2)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from occtrack.config import TrackerConfig
from occtrack.errors import OcctrackError
from occtrack.tracker import Tracker

POSITIVE = {"image width": dict(image_size=(0.0, 720.0)),
            "image height": dict(image_size=(1280.0, -1.0)),
            "fps": dict(fps=0.0), "edge_noise": dict(edge_noise=-0.1),
            "report_centre_std": dict(report_centre_std=0.0),
            "birth_speed_std": dict(birth_speed_std=math.inf),
            "prune_mass": dict(prune_mass=0.0), "merge_position": dict(merge_position=0.0),
            "merge_velocity": dict(merge_velocity=-1.0),
            "lbp_tolerance": dict(lbp_tolerance=0.0),
            "occlusion_gain": dict(occlusion_gain=math.nan),
            "clutter_rate": dict(clutter_rate=0.0), "score_floor": dict(score_floor=0.0),
            "gate_sigmas": dict(gate_sigmas=0.0)}
NON_NEGATIVE = ["position_noise", "velocity_noise", "size_noise", "death_rate",
                "border_margin", "edge_birth_rate", "spread_birth_rate", "initial_objects",
                "inward_speed", "clutter_score_power", "report_coast_time"]
PROBABILITIES = ["report_existence", "exit_survival", "detectability", "detectability_ratio",
                 "occludability", "occludability_ratio", "birth_detectability",
                 "birth_occludability", "occluder_min_existence", "label_min_existence",
                 "report_min_confidence"]

CONFIG_CASES = [
    (dict(occlusion="grid"),
     "occlusion must be one of none, object-wise, measurement-wise, not 'grid'"),
    (dict(camera_motion="orb"), "camera_motion must be one of detections, none, not 'orb'"),
    (dict(confidence_centre="mean"),
     "confidence_centre must be one of detection, posterior, not 'mean'"),
    (dict(frame_step=0), "frame_step must be between 1 and 10000, not 0"),
    (dict(capacity=-1), "capacity must be between 0 and 10000000, not -1"),
    (dict(max_labels=-1), "max_labels must be between 0 and 1000000, not -1"),
    (dict(max_components_per_object=-1),
     "max_components_per_object must be between 0 and 100000, not -1"),
    (dict(lbp_max_iterations=0), "lbp_max_iterations must be between 1 and 100000, not 0"),
    (dict(confirm_hits=0), "confirm_hits must be between 1 and 1000, not 0"),
    (dict(confirm_window=1001), "confirm_window must be between 1 and 1000, not 1001"),
    (dict(velocity_time=0.0), "velocity_time must be a positive number of seconds (inf: "
                              "constant velocity), not 0.0"),
    (dict(coast_velocity_time=-1.0), "coast_velocity_time must be a positive number of "
                                     "seconds (inf: constant velocity), not -1.0"),
    (dict(confirm_hits=6, confirm_window=5),
     "confirm_hits must be between 1 and confirm_window (5), not 6"),
    (dict(capacity=15), "capacity must be at least 16 components, or 0 to grow with the "
                        "scene, not 15"),
    (dict(occlusion_ramp=(0.25, 0.25)), "occlusion_ramp must rise: (zero point, one point)"),
    (dict(birth_half_size=(10.0, 0.0)),
     "birth_half_size must be two positive numbers (horizontal, vertical)"),
    *[(change, f"{name} must be a positive number, not {next(iter(change.values()))}"
       if name not in ("image width", "image height") else
       f"{name} must be a positive number, not ")
      for name, change in POSITIVE.items()],
    *[({name: -0.5}, f"{name} must be a number >= 0, not -0.5") for name in NON_NEGATIVE],
    *[({name: math.inf}, f"{name} must be a number >= 0, not inf") for name in NON_NEGATIVE[:2]],
    *[({name: 1.5}, f"{name} must be a probability in [0, 1], not 1.5")
      for name in PROBABILITIES],
    *[({name: -0.1}, f"{name} must be a probability in [0, 1], not -0.1")
      for name in PROBABILITIES[:2]],
]


@pytest.mark.parametrize("change,message", CONFIG_CASES,
                         ids=[m.split(" must")[0] + f"-{i}" for i, (_, m) in
                              enumerate(CONFIG_CASES)])
def test_config_validate_names_the_setting(change, message):
    with pytest.raises(ValueError) as err:
        TrackerConfig(**change)
    assert str(err.value).startswith(message)
    ok = TrackerConfig()
    with pytest.raises(ValueError) as again:  # replace() validates as the constructor does
        ok.replace(**change)
    assert str(again.value) == str(err.value)


def test_config_image_size_values_in_the_message():
    with pytest.raises(ValueError, match=r"^image width must be a positive number, not 0\.0$"):
        TrackerConfig(image_size=(0.0, 720.0))
    with pytest.raises(ValueError, match=r"^image height must be a positive number, not -1"):
        TrackerConfig(image_size=(1280.0, -1.0))


def test_config_limits_are_inclusive():
    """The ends of every range are valid settings."""
    TrackerConfig(frame_step=10_000, capacity=16, max_labels=0, max_components_per_object=0,
                  lbp_max_iterations=1, confirm_hits=1, confirm_window=1,
                  report_existence=1.0, exit_survival=0.0, position_noise=0.0,
                  occlusion_ramp=(0.0, 1e-9), birth_half_size=(1e-9, 1e-9))
    TrackerConfig(capacity=0, confirm_hits=1000, confirm_window=1000)


BOXES = [[10.0, 10.0, 20.0, 20.0]]
UPDATE_CASES = [
    (dict(boxes=BOXES, box_format="xywh"),
     "box_format must be one of 'xyxy', 'ltwh', 'cxcywh', not 'xywh'"),
    (dict(boxes=BOXES, box_format=None),
     "box_format must be one of 'xyxy', 'ltwh', 'cxcywh', not None"),
    (dict(boxes="det.txt"),
     "boxes must be an array of numbers of shape (M, 4) in xyxy, not the string 'det.txt'"),
    (dict(boxes=b"det.txt"),
     "boxes must be an array of numbers of shape (M, 4) in xyxy, not the string b'det.txt'"),
    (dict(boxes=[["a", "b", "c", "d"]]),
     "boxes must be an array of numbers of shape (M, 4) in xyxy, not list ("),
    (dict(boxes=np.zeros((3, 5))), "boxes must have shape (M, 4) (x1, y1, x2, y2 (corners)), "
                                   "not (3, 5)"),
    (dict(boxes=np.zeros((3, 5)), box_format="ltwh"),
     "boxes must have shape (M, 4) (left, top, width, height), not (3, 5)"),
    (dict(boxes=np.zeros(4), box_format="cxcywh"),
     "boxes must have shape (M, 4) (centre x, centre y, width, height), not (4,)"),
    (dict(boxes=[[1, 2, np.nan, 4]]), "boxes contain NaN or infinity"),
    (dict(boxes=[[1, 2, np.inf, 4]], box_format="ltwh"), "boxes contain NaN or infinity"),
    (dict(boxes=[[0, 0, 5, 5], [10, 10, 5, 20]]),
     "box 1 [10.0, 10.0, 5.0, 20.0] has x2 < x1 or y2 < y1; xyxy boxes are corners (pass "
     "box_format='ltwh' for left, top, width, height)"),
    (dict(boxes=[[10, 10, 20, 5]]), "box 0 [10.0, 10.0, 20.0, 5.0] has x2 < x1 or y2 < y1"),
    (dict(boxes=[[10, 10, -2, 5]], box_format="ltwh"), "boxes have a negative width or height"),
    (dict(boxes=[[10, 10, 2, -5]], box_format="cxcywh"),
     "boxes have a negative width or height"),
    (dict(boxes=BOXES, scores=[0.5, 0.6]),
     "scores must be 1 finite numbers, one per box, not an array of shape (2,)"),
    (dict(boxes=BOXES, scores=[np.nan]),
     "scores must be 1 finite numbers, one per box, not an array of shape (1,)"),
    (dict(boxes=BOXES, scores="high"),
     "scores must be an array of numbers of shape (M,), not the string 'high'"),
    (dict(boxes=BOXES, classes=[[1]]),
     "classes must be 1 whole numbers, one per box, not an array of shape (1, 1)"),
    (dict(boxes=BOXES, classes=[0.5]), "classes must be whole numbers (class ids)"),
    (dict(boxes=BOXES, classes=[np.inf]), "classes must be whole numbers (class ids)"),
    (dict(boxes=BOXES, classes=[2.0**63]), "classes must be whole numbers (class ids)"),
    (dict(boxes=BOXES, classes=np.array([2**62])), "classes must be whole numbers (class ids)"),
    (dict(boxes=BOXES, classes=np.array([2**64 - 1], dtype=np.uint64)),
     "classes must be whole numbers (class ids)"),
    (dict(boxes=BOXES, classes=[{}]), "classes must be an array of numbers of shape (M,), not "
                                      "list ("),
    (dict(boxes=BOXES, timestamp="now"), "timestamp must be a number of seconds, not 'now'"),
    (dict(boxes=BOXES, timestamp=True), "timestamp must be a number of seconds, not True"),
    (dict(boxes=BOXES, timestamp=np.bool_(False)),
     "timestamp must be a number of seconds, not "),
    (dict(boxes=BOXES, timestamp=float("nan")),
     "timestamp must be a finite number of seconds, not nan"),
    (dict(boxes=BOXES, timestamp=np.float32(np.inf)),
     "timestamp must be a finite number of seconds, not inf"),
    (dict(boxes=BOXES, camera_motion=np.eye(3)),
     "camera_motion must be a finite 2 x 3 affine matrix"),
    (dict(boxes=BOXES, camera_motion=[[1, 0, np.nan], [0, 1, 0]]),
     "camera_motion must be a finite 2 x 3 affine matrix"),
]


@pytest.mark.parametrize("kwargs,message", UPDATE_CASES,
                         ids=[f"{i}" for i in range(len(UPDATE_CASES))])
def test_update_names_what_is_wrong(kwargs, message):
    tracker = Tracker()
    with pytest.raises(ValueError) as err:
        tracker.update(**kwargs)
    assert str(err.value).startswith(message), str(err.value)
    assert tracker.filter.steps == 0


def test_update_refuses_a_timestamp_that_does_not_increase():
    tracker = Tracker()
    tracker.update(BOXES, timestamp=1.0)
    for stamp in (1.0, 0.5):
        with pytest.raises(ValueError, match=re.escape(
                f"timestamp {stamp} does not follow the previous frame's 1.0; timestamps "
                f"must increase")):
            tracker.update(BOXES, timestamp=stamp)
    assert tracker.filter.steps == 1


STEP_CASES = [
    (dict(dt=0.0), "dt must be at least 1e-06 s (frames a microsecond apart are one frame), "
                   "not 0"),
    (dict(dt=-0.5), "dt must be at least 1e-06 s (frames a microsecond apart are one frame), "
                    "not -0.5"),
    (dict(dt="soon"), "dt must be a number of seconds, not 'soon'"),
    (dict(dt=math.inf), "dt must be a finite number of seconds, not inf"),
    (dict(boxes=[[10, 10, 20, 20]], scores=[1.0, 1.0]), "scores must be 1 finite numbers"),
    (dict(classes=[1, 2]), "classes must be 1 whole numbers, one per box, not an array of "
                           "shape (2,)"),
    (dict(boxes=[[10, 10, -1, 20]]), "boxes have a negative width or height"),
    (dict(boxes=np.zeros((2, 3))), "boxes must have shape (M, 4) (left, top, width, height), "
                                   "not (2, 3)"),
    (dict(camera_motion=np.zeros((2, 2))), "camera_motion must be a finite 2 x 3 affine matrix"),
]


@pytest.mark.parametrize("kwargs,message", STEP_CASES,
                         ids=[f"{i}" for i in range(len(STEP_CASES))])
def test_step_names_what_is_wrong(kwargs, message):
    tracker = Tracker()
    kwargs = {"boxes": [[10.0, 10.0, 20.0, 40.0]], **kwargs}
    with pytest.raises(ValueError) as err:
        tracker.step(**kwargs)
    assert str(err.value).startswith(message), str(err.value)
    assert tracker.filter.steps == 0


def test_a_config_that_is_not_a_tracker_config_is_named():
    with pytest.raises(ValueError, match=r"^config must be a TrackerConfig, not dict$"):
        Tracker({"fps": 30})


# -- the highway study's tables (occtrack.config.highway): every number against its range ----

def _highway_cases():
    from occtrack.config.highway import (
        ROAD_RANGES,
        SIMULATION_RANGES,
        TRACKER_RANGES,
        HighwayTrackerConfig,
        RoadConfig,
        SimulationConfig,
    )

    cases = []
    for table, kind, ranges in (("simulation.road", RoadConfig, ROAD_RANGES),
                                ("simulation", SimulationConfig, SIMULATION_RANGES),
                                ("tracker", HighwayTrackerConfig, TRACKER_RANGES)):
        for name, interval in ranges.items():
            low, high = (float(v) for v in interval[1:-1].split(","))
            integer = isinstance(getattr(kind(), name), int)
            bad = int(high) + 1 if integer else (low if interval[0] == "(" else low - 0.5)
            message = (f"{name} must be between {low:g} and {high:g}, not {bad}" if integer
                       else f"{name} must be a number in {interval}, not {bad}")
            cases.append((table, kind, name, bad, message))
    return cases


HIGHWAY_CASES = _highway_cases()


@pytest.mark.parametrize("table,kind,name,bad,message", HIGHWAY_CASES,
                         ids=[f"{c[0]}.{c[2]}" for c in HIGHWAY_CASES])
def test_highway_settings_name_the_key_and_its_range(table, kind, name, bad, message,
                                                     tmp_path):
    """Each numeric highway setting out of range is refused, by the dataclass (ValueError) and
    by the TOML loader (OcctrackError naming the file and the table)."""
    from occtrack.config.highway import load_highway
    from occtrack.errors import OcctrackError

    with pytest.raises(ValueError) as err:
        kind(**{name: bad})
    assert str(err.value) == message
    path = tmp_path / "highway.toml"
    path.write_text(f"[{table}]\n{name} = {bad!r}\n")
    with pytest.raises(OcctrackError) as err:
        load_highway(path)
    assert str(err.value) == f"{path}: [{table}] {message}"


HIGHWAY_TOML_CASES = [
    ("[tracker]\nparticles = 1e8\n", "[tracker] particles must be an integer, not 100000000.0"),
    ("[tracker]\nlbp_max_iter = 100000000\n",
     "[tracker] lbp_max_iter must be between 1 and 100000, not 100000000"),
    ("[tracker]\nparticles = 100000\nmax_tracks = 1000\n",
     "[tracker] max_tracks x particles must be at most 10000000 (memory), not 1000 x 100000"),
    ("[tracker]\nprune_threshold = 0.6\n",
     "[tracker] prune_threshold must be below report_threshold (0.5), not 0.6"),
    ("[simulation]\nmin_speed = 6.0\n",
     "[simulation] max_speed must be at least min_speed (6.0), not 5.0"),
    ("[simulation]\nnoise_std = nan\n", "[simulation] noise_std must be a number in (0, 1000], "
                                        "not nan"),
    ("[simulation.road]\nlanes_right = 0\nlanes_left = 0\n",
     "[simulation.road] the road needs at least one lane: lanes_right + lanes_left must be at "
     "least 1"),
    ("[simulation.road]\nlanes = 3\n", "unknown setting 'simulation.road.lanes'"),
    ("[tracker]\nroad = {}\n", "the tracker uses the simulation's road"),
    ("[tracker]\nsurvival = 'high'\n", "[tracker] survival must be a number, not 'high'"),
    ("[lidar]\nx = 1\n", "unknown table [lidar]"),
    ("tracker = 3\n", "[tracker] must be a table of settings, not 3"),
]


@pytest.mark.parametrize("text,message", HIGHWAY_TOML_CASES,
                         ids=[f"{i}" for i in range(len(HIGHWAY_TOML_CASES))])
def test_highway_toml_names_the_table_and_setting(text, message, tmp_path):
    from occtrack.config.highway import load_highway
    from occtrack.errors import OcctrackError

    path = tmp_path / "highway.toml"
    path.write_text(text)
    with pytest.raises(OcctrackError) as err:
        load_highway(path)
    assert str(err.value).startswith(f"{path}: {message}"), str(err.value)


def test_highway_defaults_and_the_paper_settings_pass():
    from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig

    sim = SimulationConfig()
    tracker = HighwayTrackerConfig.matching(sim)
    assert tracker.noise_std == sim.noise_std and tracker.road == sim.road
    HighwayTrackerConfig(particles=4096, max_tracks=64, noise_std=0.85, birth_rate=0.15)


TOML_CASES = [
    ("gating = 1\n", "gating must be true or false, not 1"),
    ('occlusion = 3\n', "occlusion must be a string, not 3"),
    ("capacity = true\n", "capacity must be an integer, not True"),
    ('edge_noise = "0.1"\n', "edge_noise must be a number, not '0.1'"),
    ("edge_noise = false\n", "edge_noise must be a number, not False"),
    ("birth_half_size = [1.0, true]\n",
     "birth_half_size must be a pair of numbers like [1.0, 2.0], not [1.0, True]"),
    ("prune_masss = 0.1\n", "unknown setting 'prune_masss'; known settings: "),
]


@pytest.mark.parametrize("text,message", TOML_CASES, ids=[m.split(" ")[0] + f"-{i}" for i, (_, m)
                                                         in enumerate(TOML_CASES)])
def test_toml_values_of_the_wrong_type_name_the_setting_and_file(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(OcctrackError) as err:
        TrackerConfig.from_toml(path)
    assert str(err.value).startswith(f"{path}: {message}"), str(err.value)


def test_a_toml_path_that_is_no_file_is_named(tmp_path):
    with pytest.raises(OcctrackError) as err:
        TrackerConfig.from_toml(tmp_path / "none.toml")
    assert str(err.value) == f"{tmp_path / 'none.toml'}: no such file"
    with pytest.raises(OcctrackError) as err:
        TrackerConfig.from_toml(tmp_path)
    assert str(err.value) == f"{tmp_path}: is a directory, expected a TOML file"


def test_run_names_what_it_takes():
    with pytest.raises(ValueError) as err:
        Tracker().run(42)
    assert str(err.value) == ("Tracker.run takes a MotTable or one (M, 4) or (M, 5) array per "
                              "frame, not int")
    with pytest.raises(ValueError) as err:
        Tracker().run([np.zeros((1, 4)), np.zeros((2, 3))], quiet=True)
    assert str(err.value) == "frame 2: detections must be (M, 4) or (M, 5), not (2, 3)"
    empty = Tracker().run([[], np.zeros((0, 5))], quiet=True)  # an empty frame is no error
    assert empty.frames == 2 and len(empty.id) == 0
