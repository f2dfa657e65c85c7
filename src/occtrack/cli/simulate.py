"""`occtrack simulate SCENE`: run a tracker on a simulated scene and score it.

One sub-command per scene (only `highway` so far); a new scene is a new `configure_*` / `run_*`
pair registered in SCENES.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import deque
from pathlib import Path

from occtrack.cli.arguments import positive_int, seed_int
from occtrack.progress import progress, summary

NAME = "simulate"
HELP = "run a tracker on a simulated scene (the paper's highway) and score it"
DESCRIPTION = HELP + ". Scenes: highway. See occtrack simulate SCENE --help."

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


SCENES = {
    "highway": (configure_highway, run_highway,
                "four-lane highway seen from its side (paper appendix, Table III)",
                HIGHWAY_DESCRIPTION),
}
