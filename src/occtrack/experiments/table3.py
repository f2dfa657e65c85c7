"""Paper Table III: GOSPA per step of three highway trackers under two simulated occlusions.

Every (simulation, tracker, seed) cell is one run of `occtrack.experiments.highway.evaluate`; the
three trackers of one simulation and seed see the very same cars and measurements. Seeds are
1..K. Each cell is deterministic, so the table does not depend on how the work is shared out:
by default the cells are tasks of `occtrack sweep`'s Dask engine (a LocalCluster of `--jobs`
workers, or the cluster at `--scheduler ADDRESS`); `--jobs 1` runs them in this process, and
without Dask (the `sweep` extra) they go to `--jobs` worker processes.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.progress import progress, summary

NAME = "table3"
HELP = "the highway study (paper appendix, Table III): 3 trackers x 2 simulated occlusions"
DESCRIPTION = """\
The highway study of the paper's appendix (Table III): GOSPA per time step (c = 5 m, p = 1,
alpha = 2) of the particle multi-Bernoulli tracker with three occlusion handlers
(object-wise-expval, object-wise-grid, measurement-wise) on the four-lane highway simulated
with object-wise and with measurement-wise occlusion. Each cell is the mean over seeds 1..K of
the per-step mean, +- its standard error, beside the paper's value [in brackets]; '*' marks
the best tracker of each row. GOSPA per true car and the localisation / missed / false split
follow, and each tracker's run time (seconds for one run of --steps steps, mean over seeds).
The traffic is as dense as in the authors' simulator (about 8.2 cars on the road; see
SimulationConfig.entry_delay); per-step GOSPA grows with the number of cars, per-car does not.

--json prints {simulation: {tracker: {"mean": m, "stderr": s, "seconds": t}}} only."""

SENSORS = ("object-wise", "measurement-wise")
TRACKERS = ("object-wise-expval", "object-wise-grid", "measurement-wise")
PAPER = {"object-wise": {"object-wise-expval": 4.94, "object-wise-grid": 4.79,
                         "measurement-wise": 4.90},
         "measurement-wise": {"object-wise-expval": 4.94, "object-wise-grid": 4.80,
                              "measurement-wise": 4.67}}
"""The paper's Table III, printed beside ours; never used to compute anything."""


def configure(parser: argparse.ArgumentParser) -> None:
    from occtrack.config.arguments import positive_int

    parser.add_argument("--steps", type=positive_int, default=10000,
                        help="time steps per run (default 10000, as in the paper)")
    parser.add_argument("--seeds", type=positive_int, default=3, metavar="K",
                        help="runs per cell, seeds 1..K (default 3)")
    parser.add_argument("--config", type=Path, metavar="TOML",
                        help="other settings ([simulation], [simulation.road], [tracker] tables, "
                             "as for occtrack simulate highway); the paper's by default")
    parser.add_argument("--jobs", type=positive_int, default=2,
                        help="worker processes (default 2; 1: in this process, no Dask)")
    engine = parser.add_mutually_exclusive_group()
    engine.add_argument("--dask", action="store_true",
                        help="run the cells as Dask tasks on a LocalCluster of --jobs workers "
                             "(occtrack sweep's machinery, the default when the sweep extra "
                             "is installed and --jobs > 1; an error without it)")
    engine.add_argument("--scheduler", metavar="ADDRESS",
                        help="run the cells as Dask tasks on a running cluster, e.g. "
                             "tcp://127.0.0.1:8786")
    parser.add_argument("--json", action="store_true", help="print the table as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _cell(sensor: str, tracker: str, steps: int, seed: int, simulation, tracking):
    from occtrack.experiments.highway import evaluate

    score, seconds = evaluate(simulation, tracking, sensor, tracker, steps, seed)
    return sensor, tracker, seed, score, seconds


def compute(steps: int, seeds: int, jobs: int = 2, quiet: bool = True, simulation=None,
            tracking=None) -> dict:
    """{sensor: {tracker: [(score, seconds) per seed, in seed order]}}."""
    from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig

    simulation = simulation or SimulationConfig()
    tracking = tracking or HighwayTrackerConfig.matching(simulation)
    work = [(s, t, steps, seed, simulation, tracking) for seed in range(1, seeds + 1)
            for s in SENSORS for t in TRACKERS]
    done: dict = {s: {t: {} for t in TRACKERS} for s in SENSORS}
    if jobs == 1:
        results = (_cell(*w) for w in work)
        for sensor, tracker, seed, score, seconds in progress(results, len(work), "table3",
                                                              quiet):
            done[sensor][tracker][seed] = (score, seconds)
    else:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            futures = [pool.submit(_cell, *w) for w in work]
            for future in progress(as_completed(futures), len(work), "table3", quiet):
                sensor, tracker, seed, score, seconds = future.result()
                done[sensor][tracker][seed] = (score, seconds)
    return {s: {t: [done[s][t][k] for k in sorted(done[s][t])] for t in TRACKERS}
            for s in SENSORS}


def compute_on_dask(steps: int, seeds: int, config: Path | None = None,
                    scheduler: str | None = None, workers: int = 2,
                    quiet: bool = True) -> dict:
    """`compute`'s result with every cell a task of `occtrack sweep`'s Dask engine (the
    same cells and seeds, so the same table)."""
    from occtrack.experiments import sweep
    from occtrack.metrics.highway import HighwayScore

    spec = sweep.Spec(path=config or Path("table3"), kind="highway", trackers=TRACKERS,
                      seeds=tuple(range(1, seeds + 1)), points=({},), sensors=SENSORS,
                      steps=steps, config=config.resolve() if config else None)
    cells = sweep.plan(spec)
    done: dict = {s: {t: {} for t in TRACKERS} for s in SENSORS}
    failures = []
    with sweep.DaskEngine(scheduler=scheduler, workers=workers) as engine:
        engine.warm("highway")
        for cell, row in progress(engine.run(cells), len(cells), "table3", quiet):
            if isinstance(row, sweep.Failure):
                failures.append(row)
                continue
            score = HighwayScore(row["gospa"], row["gospa_per_car"], row["localisation"],
                                 row["missed"], row["false"], row["steps"], row["car_steps"],
                                 row["n_missed"], row["n_false"], row["tracks"])
            done[cell.work][cell.tracker][cell.seed] = (score, row["seconds"])
    if failures:
        raise OcctrackError(sweep.format_failures(failures))
    return {s: {t: [done[s][t][k] for k in sorted(done[s][t])] for t in TRACKERS}
            for s in SENSORS}


def _stats(values: list[float]) -> tuple[float, float]:
    v = np.asarray(values, float)
    stderr = float(v.std(ddof=1) / np.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(v.mean()), stderr


def as_json(result: dict) -> str:
    out = {}
    for sensor, row in result.items():
        out[sensor] = {}
        for tracker, runs in row.items():
            mean, stderr = _stats([score.per_step for score, _ in runs])
            out[sensor][tracker] = {"mean": mean, "stderr": None if np.isnan(stderr) else stderr,
                                    "seconds": float(np.mean([s for _, s in runs]))}
    return json.dumps(out, indent=2)


def format_table(result: dict, steps: int, seeds: int) -> str:
    lines = [f"Highway (paper appendix, Table III): GOSPA per step, mean +- standard error over "
             f"seeds 1..{seeds}, {steps} steps each [paper]; * best of the row.",
             f"  {'simulated':<18}" + "".join(f"{t:<26}" for t in TRACKERS)]
    for sensor, row in result.items():
        means = {t: _stats([s.per_step for s, _ in runs]) for t, runs in row.items()}
        best = min(means, key=lambda t: means[t][0])
        cells = []
        for t in TRACKERS:
            m, se = means[t]
            err = "" if np.isnan(se) else f" +- {se:.3f}"
            cells.append(f"{m:.3f}{err} [{PAPER[sensor][t]:.2f}]{'*' if t == best else ''}"
                         .ljust(26))
        lines.append(f"  {sensor:<18}" + "".join(cells))
    lines += ["", "GOSPA per true car, and per step: localisation / missed / false",
              f"  {'simulated':<18}" + "".join(f"{t:<26}" for t in TRACKERS)]
    for sensor, row in result.items():
        cells = []
        for t in TRACKERS:
            runs = [s for s, _ in row[t]]
            cells.append((f"{np.mean([s.per_object for s in runs]):.3f}: "
                          f"{np.mean([s.localisation for s in runs]):.2f}/"
                          f"{np.mean([s.missed for s in runs]):.2f}/"
                          f"{np.mean([s.false for s in runs]):.2f}").ljust(26))
        lines.append(f"  {sensor:<18}" + "".join(cells))
    cars = np.mean([s.car_steps / s.steps for row in result.values() for runs in row.values()
                    for s, _ in runs])
    seconds = {t: np.mean([sec for row in result.values() for _, sec in row[t]])
               for t in TRACKERS}
    lines += ["", f"Cars on the road: {cars:.2f} per step. Tracker seconds per run: "
              + ", ".join(f"{t} {v:.1f}" for t, v in seconds.items()) + "."]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    if args.seeds < 1 or args.steps < 1:
        raise OcctrackError("--steps and --seeds must be at least 1")
    simulation = tracking = None
    if args.config is not None:
        from occtrack.config.highway import load_highway

        simulation, tracking = load_highway(args.config)
    start = time.perf_counter()
    from occtrack.experiments.sweep import dask_available

    if args.dask or args.scheduler or (args.jobs > 1 and dask_available()):
        result = compute_on_dask(args.steps, args.seeds, args.config, args.scheduler,
                                 args.jobs, args.quiet)
    else:
        result = compute(args.steps, args.seeds, args.jobs, args.quiet, simulation, tracking)
    seconds = time.perf_counter() - start
    tracks = sum(score.tracks for row in result.values() for runs in row.values()
                 for score, _ in runs)
    closing = summary(args.steps * args.seeds * len(SENSORS) * len(TRACKERS), tracks, seconds,
                      what="steps")
    if args.json:
        print(as_json(result))
        print(closing, file=sys.stderr)
    else:
        print(format_table(result, args.steps, args.seeds))
        print(closing)
    return 0
