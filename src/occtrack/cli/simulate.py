"""`occtrack simulate SCENE`: a simulated scene: the highway tracked and scored, or a lidar
scene written as scan files.

One sub-command per scene; a new scene is a new `configure_*` / `run_*` pair registered in
SCENES.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import deque
from pathlib import Path

from occtrack.cli.arguments import positive_float, positive_int, seed_int, whole_number
from occtrack.errors import OcctrackError
from occtrack.progress import progress, summary

NAME = "simulate"
HELP = "a simulated scene: the paper's highway tracked and scored, or lidar scans to files"
DESCRIPTION = HELP + ". Scenes: highway, lidar. See occtrack simulate SCENE --help."

HIGHWAY_DESCRIPTION = """\
The four-lane highway of the paper's appendix (Table III): cars enter, cross the 60 m road
section at constant speed and leave; a point sensor beside the road sees contiguous shapes by
angle and reports each shape's two ends, a seen end as a point (Gaussian noise), a hidden end
as the span it could lie in; misses and Poisson clutter. A particle multi-Bernoulli tracker
follows the cars and is scored by GOSPA (c = 5 m, p = 1, alpha = 2; distance
sqrt(dfront^2 + dlength^2) within a lane, infinite across lanes).

--sensor picks how the simulation hides things: object-wise (cars hide cars) or
measurement-wise (measurements hide measurements). --tracker picks the tracker's occlusion
handler: measurement-wise (exact probability that a car's measurement is hidden),
object-wise-expval (expected extents of nearer tracks) or object-wise-grid (a visibility grid
over the sensor's angles). The tracker knows the simulation's parameters (noise, P_D, clutter,
births), as in the paper.

Prints GOSPA per step (the paper's figure), its localisation / missed / false split and GOSPA
per true car, then a one-line summary. --figure draws the last step; --animation the last
--animation-steps steps as a GIF (5 steps per second, real time)."""


def configure(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="scene", metavar="SCENE", required=True)
    for name, (configure_scene, run_scene, help_, description) in SCENES.items():
        p = sub.add_parser(name, help=help_, description=description,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        configure_scene(p)
        p.set_defaults(_scene_run=run_scene)


def run(args: argparse.Namespace) -> int:
    return args._scene_run(args)


def configure_highway(p: argparse.ArgumentParser) -> None:
    from occtrack.config.highway import SENSOR_MODES
    from occtrack.occlusion.highway import TRACKER_NAMES

    p.add_argument("--sensor", choices=SENSOR_MODES, default="measurement-wise",
                   help="how the simulation hides things (default measurement-wise)")
    p.add_argument("--tracker", choices=TRACKER_NAMES, default="measurement-wise",
                   help="the tracker's occlusion handler (default measurement-wise)")
    p.add_argument("--steps", type=positive_int, default=1000,
                   help="time steps at 5 per second (default 1000)")
    p.add_argument("--seed", type=seed_int, default=1, help="random seed (default 1)")
    p.add_argument("--config", type=Path, metavar="TOML",
                   help="settings: [simulation], [simulation.road] and [tracker] tables with "
                        "the fields of occtrack.config.highway")
    p.add_argument("--figure", type=Path, metavar="PNG", help="draw the last step")
    p.add_argument("--animation", type=Path, metavar="GIF",
                   help="animate the last --animation-steps steps")
    p.add_argument("--animation-steps", type=positive_int, default=100, metavar="N",
                   help="steps in the animation (default 100)")
    p.add_argument("--force", action="store_true", help="overwrite existing pictures")
    p.add_argument("--json", action="store_true", help="print the score as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def run_highway(args: argparse.Namespace) -> int:
    from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig, load_highway
    from occtrack.experiments.highway import evaluate
    from occtrack.models.highway_sensor import MeasurementModel

    if args.config is not None:
        simulation, tracking = load_highway(args.config)
    else:
        simulation = SimulationConfig()
        tracking = HighwayTrackerConfig.matching(simulation)
    from occtrack.viz.highway import check_path

    if args.figure is not None:
        check_path(args.figure, (".png",), args.force)
    if args.animation is not None:
        check_path(args.animation, (".gif",), args.force)
    keep = max(args.animation_steps if args.animation else 0, 1 if args.figure else 0)
    recent: deque = deque(maxlen=keep)
    def on_step(t, cars, scan, estimates):
        if keep:
            recent.append((cars, scan, estimates))

    start = time.perf_counter()
    score, tracker_seconds = evaluate(
        simulation, tracking, args.sensor, args.tracker, args.steps, args.seed, on_step,
        lambda frames: progress(frames, total=args.steps, desc="highway", quiet=args.quiet))
    seconds = time.perf_counter() - start
    model = MeasurementModel(tracking)
    label = f"{args.sensor} simulation, {args.tracker} tracker, seed {args.seed}"
    if args.figure is not None:
        from occtrack.viz.highway import save_figure

        save_figure(args.figure, simulation.road, [recent[-1]], model,
                    [f"{label}: step {args.steps - 1}"], overwrite=args.force)
    if args.animation is not None:
        from occtrack.viz.highway import save_animation

        frames = list(recent)
        save_animation(args.animation, simulation.road, frames, model, label,
                       first_step=args.steps - len(frames), overwrite=args.force)
    if args.json:
        out = {"sensor": args.sensor, "tracker": args.tracker, "steps": args.steps,
               "seed": args.seed, **score.as_dict(), "tracker_seconds": tracker_seconds}
        print(json.dumps(out, indent=2))
    else:
        cars = score.car_steps / max(score.steps, 1)
        print(f"highway: {label}")
        print(f"GOSPA per step {score.per_step:.3f} (localisation {score.localisation:.3f}, "
              f"missed {score.missed:.3f}, false {score.false:.3f}); "
              f"per true car {score.per_object:.3f}; {cars:.2f} cars on the road per step")
        print(f"tracker {tracker_seconds:.2f} s ({args.steps / max(tracker_seconds, 1e-9):.0f}"
              f" steps per second)")
    # With --json, stdout holds the JSON alone; the rest goes to stderr.
    out = sys.stderr if args.json else sys.stdout
    if args.figure is not None:
        print(f"figure: {args.figure}", file=out)
    if args.animation is not None:
        print(f"animation: {args.animation}", file=out)
    print(summary(args.steps, score.tracks, seconds, what="steps"), file=out)
    return 0


LIDAR_DESCRIPTION = """\
A 2-D scanning range sensor (a lidar) in the middle of a walkway, and people walking past it:
discs of radius 0.25 m, each on a lane of its own parallel to x (lanes 0.6 m apart from 1 m
out, on either side of the sensor; 1 to 6.4 m for 20 people), each side walking one way at
1-1.5 m/s, some stopping for a few seconds; when one leaves the 36 m strip the next enters.
--vehicles adds cars (4.5 x 1.8 m rectangles) on road lanes beyond. Every beam is cast
exactly against every object; the first surface returns with probability 0.98, its range with
2 cm noise; 5 clutter returns a scan; nothing within --max-range is no return. Seeded: one
seed gives the same files byte for byte, and a longer scene begins as a shorter one.

Writes to DIR:
  scans.csv   one row a beam: time (s), angle (rad, counter-clockwise from the sensor's
              heading), range (m; inf: no return), as a user's own scanner could log it
  truth.csv   one row an object a scan: time, id, shape (disc / rect), x, y, vx, vy, length,
              width, heading, clear_beams (beams that would reach it were it alone),
              visible_beams (beams whose first surface it is), occluded (1: fully occluded)
  sensor.csv  the sensor's pose a scan (it stands still unless --sensor-velocity is given)
Formats: occtrack.io.scans, which reads them back. Prints one line: scans, beams, people and
the full occlusions lasting over 1 s (from the first to the last scan of the spell).
Existing files are refused unless --force."""


def configure_lidar(p: argparse.ArgumentParser) -> None:
    from occtrack.config.lidar import SENSOR_MODES

    p.add_argument("-o", "--out", type=Path, required=True, metavar="DIR",
                   help="folder for scans.csv, truth.csv and sensor.csv (made if missing)")
    p.add_argument("--seed", type=seed_int, default=0, help="random seed (default 0)")
    p.add_argument("--people", type=whole_number(0), default=20,
                   help="people walking at any time (default 20)")
    p.add_argument("--vehicles", type=whole_number(0), default=0,
                   help="vehicles driving at any time (default 0)")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--scans", type=positive_int, help="scans to write (default 1800)")
    length.add_argument("--duration", type=positive_float, metavar="SECONDS",
                        help="seconds to simulate (default 180)")
    p.add_argument("--beams", type=positive_int, default=720, help="beams a scan (default 720)")
    p.add_argument("--fov", type=positive_float, default=360.0, metavar="DEG",
                   help="field of view in degrees, centred on the heading (default 360)")
    p.add_argument("--rate", type=positive_float, default=10.0,
                   help="scans a second (default 10)")
    p.add_argument("--max-range", type=positive_float, default=20.0, metavar="M",
                   help="range beyond which nothing returns, m (default 20)")
    p.add_argument("--sensor", choices=SENSOR_MODES, default="object-wise",
                   help="what a missed return means: object-wise (the object still blocks "
                        "the beam) or measurement-wise (the paper's model: the beam goes on)")
    p.add_argument("--sensor-velocity", type=float, nargs=2, default=(0.0, 0.0),
                   metavar=("VX", "VY"), help="the sensor's velocity, m/s (default 0 0)")
    p.add_argument("--force", action="store_true", help="overwrite existing files in DIR")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


MAX_SCAN_ROWS = 2_000_000_000
"""Bound on beams x scans of `simulate lidar`: one row of scans.csv a beam, about 25 bytes, so
50 GB of disk and a day of writing; a larger count is a typo (`--scans 1e14`), not a scene."""


def run_lidar(args: argparse.Namespace) -> int:
    from occtrack.config.lidar import LidarSceneConfig
    from occtrack.scenarios.lidar.files import write_scene

    try:
        config = LidarSceneConfig(
            beams=args.beams, fov_deg=args.fov, rate=args.rate, max_range=args.max_range,
            sensor=args.sensor, people=args.people, vehicles=args.vehicles,
            sensor_vx=args.sensor_velocity[0], sensor_vy=args.sensor_velocity[1])
    except ValueError as err:
        raise OcctrackError(str(err)) from None
    scans = args.scans or (max(round(args.duration * args.rate), 1) if args.duration else 1800)
    if scans * args.beams > MAX_SCAN_ROWS:
        given = f"--scans {args.scans}" if args.scans else f"--duration {args.duration:g}"
        raise OcctrackError(f"{given} at {args.beams} beams a scan is {scans * args.beams:.3g} "
                            f"rows of scans.csv, more than {MAX_SCAN_ROWS:.0e} (about 50 GB); "
                            f"write a shorter scene or fewer beams")
    start = time.perf_counter()
    done = write_scene(args.out, config, scans, args.seed, args.force,
                       lambda s: progress(s, total=scans, desc="lidar", quiet=args.quiet))
    print(f"lidar: {done.scans} scans of {done.beams} beams, {args.people} people at a time "
          f"({done.objects} objects in all), {done.occlusions.longer_than(1.0)} full "
          f"occlusions over 1 s, {time.perf_counter() - start:.2f} s; written to {args.out}")
    return 0


SCENES = {
    "highway": (configure_highway, run_highway,
                "four-lane highway seen from its side (paper appendix, Table III)",
                HIGHWAY_DESCRIPTION),
    "lidar": (configure_lidar, run_lidar,
              "people walking past a scanning range sensor, written as scan files",
              LIDAR_DESCRIPTION),
}
