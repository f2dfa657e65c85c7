"""`occtrack reproduce lidar`: the lidar scan tracker against its baselines on the same scans
(issue 24): the default simulated walkway (`occtrack.scenarios.lidar`), seeds 0..4, four
trackers in the one PMB filter.

- derived: the scan's segments scored by the derived likelihood (`models.scan_segments`),
  measurement-wise occlusion (`occlusion.scan`);
- hand-made: the same segments, the other beams' term the fixed hand-made shape (`models.
  scan_hand_made`: beyond: low, closer: uniform), no occlusion term in the miss;
- none: the derived likelihood, no occlusion term;
- cluster: cluster-then-track, each segment's fitted centre tracked as a point (`models.point`),
  no occlusion term;
- hand-made-occluded (not run by default): the hand-made likelihood with the measurement-wise
  occlusion term, which separates the likelihood's share from the occlusion term's.

Per run (`experiments.scan_tracking.run_scene`): GOSPA per scan (c = 1 m, p = 1, alpha = 2)
and its localisation / missed / false parts, HOTA on positions (similarity 1 - d / 1 m), DetA,
AssA, identity switches, the full occlusions shorter
than 2 s bridged (the person seen, i.e. two beams on it, and matched to the same track just
before and just after the spell; a one-beam glimpse does not end a spell), the same over the
scene's bare flag (every fully occluded run, a glimpse splitting it), scans a second.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from occtrack.progress import progress

NAME = "lidar"
HELP = "the lidar scan tracker against its baselines (hand-made, no occlusion, clusters)"
DESCRIPTION = """\
The lidar scan tracker on the default simulated walkway (20 people, a 720-beam 360-degree
scanner at 10 scans a second, 2 cm range noise, 5 clutter returns a scan) against three
baselines in the same PMB filter, on the same scans:

  derived    the derived scan likelihood, measurement-wise occlusion (the tracker)
  hand-made  the hand-made beam shape (beyond: low, closer: uniform), no occlusion term
  none       the derived likelihood, no occlusion term
  cluster    cluster-then-track: each segment's fitted centre as a point, no occlusion term

The table: per tracker, the mean over the seeds of GOSPA per scan (c = 1 m) with its
localisation / missed / false parts, HOTA on positions (TrackEval's, similarity
max(0, 1 - d / 1 m)) with DetA and AssA, the ECE of the tracks' confidence (right: a person
within one radius), identity switches a run, the full occlusions shorter than
2 s bridged with the same identity (of all of them, summed over the seeds; a spell lasts while
fewer than two beams return from the person, so a one-beam glimpse, which looks like clutter,
does not end it; the person seen on both sides), the same over every run of fully occluded
scans (a glimpse splits a spell; people entering or leaving while hidden left out) and scans a
second.

--json prints exactly one object: {"full_occlusions": N, "trackers": {tracker: {"gospa":
[the mean per scan of each seed], "bridged": share of the N bridged}}}."""

TRACKERS = {"derived": ("derived", "measurement-wise"), "hand-made": ("hand-made", "none"),
            "none": ("derived", "none"), "cluster": ("cluster", "none"),
            "hand-made-occluded": ("hand-made", "measurement-wise")}
DEFAULT_TRACKERS = ("derived", "hand-made", "none", "cluster")


def configure(parser: argparse.ArgumentParser) -> None:
    from occtrack.config.arguments import positive_int, whole_number

    parser.add_argument("--seeds", type=whole_number(0), nargs="+", default=[0, 1, 2, 3, 4],
                        metavar="SEED", help="scene seeds (default 0 1 2 3 4)")
    parser.add_argument("--scans", type=positive_int, default=1800,
                        help="scans a run (default 1800: the scene's three minutes, with 81 "
                             "to 101 full occlusions of over a second on seeds 0-4)")
    parser.add_argument("--trackers", nargs="+", choices=list(TRACKERS),
                        default=list(DEFAULT_TRACKERS), metavar="TRACKER",
                        help=f"which of {', '.join(TRACKERS)} (default: the first four; "
                             "hand-made-occluded: the hand-made likelihood with the "
                             "measurement-wise occlusion term)")
    parser.add_argument("--jobs", type=positive_int, default=1,
                        help="worker processes (default 1: in this process)")
    parser.add_argument("--figure", metavar="PNG",
                        help="also draw one scan of the first seed (within --scans) where the "
                             "derived tracker holds fully occluded people that the tracker "
                             "without occlusion has lost (viz extra)")
    parser.add_argument("--animation", metavar="GIF",
                        help="also animate the scans of the first seed around the one "
                             "--figure draws, a frame per scan at the scan rate, in the same "
                             "two panels: beams, people (the fully occluded filled), tracks "
                             "(dashed while held hidden) (viz extra)")
    parser.add_argument("--animation-scans", type=positive_int, default=60, metavar="N",
                        help="frames of --animation: the N scans centred on the picked one "
                             "(default 60: 6 s)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite an existing figure or animation")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _cell(name: str, seed: int, scans: int):
    from occtrack.experiments.scan_tracking import run_scene

    likelihood, occlusion = TRACKERS[name]
    return name, run_scene(seed, occlusion, scans, likelihood=likelihood)


def compute(seeds: list[int], scans: int, trackers: list[str], jobs: int = 1,
            quiet: bool = True) -> dict:
    """{tracker: [ScanRun per seed, in seed order]}."""
    work = [(name, seed, scans) for name in trackers for seed in seeds]
    out: dict = {name: {} for name in trackers}
    if jobs == 1:
        results = (_cell(*w) for w in work)
        for name, run in progress(results, len(work), "lidar", quiet):
            out[name][run.seed] = run
    else:
        with ProcessPoolExecutor(jobs) as pool:
            futures = [pool.submit(_cell, *w) for w in work]
            for future in progress(futures, len(work), "lidar", quiet):
                name, run = future.result()
                out[name][run.seed] = run
    return {name: [runs[s] for s in seeds] for name, runs in out.items()}


def as_dict(result: dict) -> dict:
    first = next(iter(result.values()))
    n = sum(r.spells for r in first)
    return {"full_occlusions": int(n),
            "trackers": {name: {"gospa": [float(r.gospa) for r in runs],
                                "bridged": sum(r.kept for r in runs) / n if n else None}
                         for name, runs in result.items()}}


def format_table(result: dict, seeds: list[int], scans: int) -> str:
    first = next(iter(result.values()))
    n = sum(r.spells for r in first)
    lines = [f"Lidar walkway, seeds {' '.join(map(str, seeds))}, {scans} scans each: "
             f"{n} full occlusions under 2 s.",
             "",
             "| tracker | GOSPA / scan (m) | loc. | missed | false | HOTA | DetA | AssA | ECE | "
             "id switches / run | bridged < 2 s | every fully occluded run < 2 s | scans/s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, runs in result.items():
        m = {f: float(np.mean([getattr(r, f) for r in runs]))
             for f in ("gospa", "localisation", "missed", "false", "hota", "deta", "assa",
                       "ece", "switches", "scans_per_second")}
        kept = sum(r.kept for r in runs)
        strict = f"{sum(r.strict_kept for r in runs)}/{sum(r.strict_spells for r in runs)}"
        lines.append(f"| {name} | {m['gospa']:.3f} | {m['localisation']:.3f} | "
                     f"{m['missed']:.3f} | {m['false']:.3f} | {m['hota']:.3f} | "
                     f"{m['deta']:.3f} | {m['assa']:.3f} | {m['ece']:.3f} | "
                     f"{m['switches']:.1f} | "
                     f"{kept}/{n} ({kept / max(n, 1):.0%}) | {strict} | "
                     f"{m['scans_per_second']:.0f} |")
    lines += ["", "GOSPA / scan per seed:", "",
              "| tracker | " + " | ".join(f"seed {s}" for s in seeds) + " |",
              "|---|" + "---|" * len(seeds)]
    for name, runs in result.items():
        lines.append(f"| {name} | " + " | ".join(f"{r.gospa:.3f}" for r in runs) + " |")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from occtrack.extras import require

    require("trackeval", "occtrack reproduce lidar (HOTA)")  # before the run, not after
    seeds = list(dict.fromkeys(args.seeds))
    if args.figure or args.animation:  # refuse before the long run, not after
        from occtrack.experiments.scan_tracking import check_pickable
        from occtrack.viz.frame import check_new
        from occtrack.viz.highway import check_path

        require("matplotlib", "a picture (--figure, --animation)")
        if args.figure:
            check_new(args.figure, args.force)
        if args.animation:
            require("PIL", "--animation")  # matplotlib's PillowWriter
            check_path(args.animation, (".gif",), args.force)
        check_pickable(args.scans)
    start = time.perf_counter()
    result = compute(seeds, args.scans, list(dict.fromkeys(args.trackers)), args.jobs,
                     args.quiet)
    seconds = time.perf_counter() - start
    scans = args.scans * len(seeds) * len(result)
    closing = (f"{len(result) * len(seeds)} runs, {scans} scans, {seconds:.2f} s, "
               f"{scans / max(seconds, 1e-9):.1f} scans per second")
    if args.json:
        print(json.dumps(as_dict(result)))
        print(closing, file=sys.stderr)
    else:
        print(format_table(result, seeds, args.scans))
    if args.figure or args.animation:
        from occtrack.experiments.scan_tracking import occlusion_scans

        length = args.animation_scans if args.animation else 1
        pictures, picked = occlusion_scans(seeds[0], args.scans, quiet=args.quiet, length=length)
        said = []
        if args.figure:
            from occtrack.viz.lidar import draw_scan_tracks

            draw_scan_tracks(args.figure, pictures[picked], args.force)
            said.append(f"scan at {pictures[picked].time:.1f} s of seed {seeds[0]} drawn in "
                        f"{args.figure}")
        if args.animation:
            from occtrack.viz.lidar import animate_scan_tracks

            animate_scan_tracks(args.animation, pictures, args.force, quiet=args.quiet)
            said.append(f"scans {pictures[0].time:.1f} to {pictures[-1].time:.1f} s of seed "
                        f"{seeds[0]} ({len(pictures)} frames) animated in {args.animation}")
        if not args.json:
            print("\n".join(said))
    if not args.json:
        print(closing)
    return 0
