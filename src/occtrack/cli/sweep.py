"""`occtrack sweep SPEC.toml`: sequences x trackers x settings x seeds, each cell one Dask task."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "sweep"
HELP = "run a grid / random search of settings over sequences or the highway, on Dask"
DESCRIPTION = """\
Run every cell of a sweep spec (TOML): each work item (a MOTChallenge sequence folder, a sensor
of the highway simulation, or an object's range on a lidar beam) x tracker (occlusion model) x
settings point (the [grid]'s combinations, times the [random] draws) x seed is one task.
Results go into one Parquet table (-o, default SPEC with the suffix .parquet): per cell its
settings (setting.NAME columns and canonical JSON in `settings`), seed, metrics (mot: HOTA,
IDF1, MOTA, ... under the mot17 protocol; highway: GOSPA per step and per car, and its split;
lidar: the derived beam likelihood at five returns and the largest standard score of simulated
beams against it) and run time (`seconds`: the tracker; `task_seconds`: the whole task;
`cpu_seconds`: its CPU time). The table is rewritten atomically every few seconds, so an
interrupted sweep keeps its finished cells, and a rerun skips the cells already in it.
At the end a summary prints the means and standard errors over seeds. A failed task is
reported with its settings (and not stored); the other tasks finish and the exit status is 1.

Engine: a Dask LocalCluster with one single-threaded worker process per core (--workers N),
started and stopped by the command; --scheduler tcp://HOST:PORT sends the same tasks to a
running Dask cluster (its workers must import occtrack and see the spec's folders); --sequential
runs them in this process without Dask (the same table). Dask and Parquet need the `sweep`
extra: pip install "occtrack[sweep]".

Spec (top-level keys first, as TOML wants):
  trackers = ["none", "measurement-wise", "object-wise"]
  seeds = [0]                       # a list, or K for seeds 1..K
  [work]
  kind = "mot"                      # or "highway" (steps = 1000, sensors = [...]), or
                                    #   "lidar" (ranges = [20.0], samples = 100000)
  sequences = ["../shared/data/mot17"]   # relative to the spec's folder
  detections = "det"                # or "simulated" (seeded from gt/gt.txt)
  config = "tracker.toml"           # optional settings file every cell starts from
  [base]                            # settings of every cell
  [grid]                            # NAME = [values...]: every combination
  [random]                          # samples = N, seed = S, NAME = {uniform | log_uniform |
                                    #   int_uniform = [lo, hi]} or {choice = [...]}
  [search]                          # instead of [grid] / [random]: kind = "optuna", trials = N,
                                    #   metric = "hota", direction = "maximize", seed = S,
                                    #   batch = B (trials at once), NAME = {...} as [random]

A [search] runs one Optuna study per tracker (TPE sampler seeded by `seed`): `batch` trials at
a time, each trial's cells (work items x seeds) as tasks, the trial's value the mean of
`metric` over its cells, told in trial order, so the trials do not depend on the engine. A
rerun replays the study from the table (done cells are not run again); the summary ends with
each study's best trial. Optuna comes with the `sweep` extra.

examples:
  occtrack sweep sweep.toml
  occtrack sweep sweep.toml -o runs.parquet --workers 2
  occtrack sweep sweep.toml --scheduler tcp://127.0.0.1:8786
  occtrack sweep sweep.toml --dry-run"""


def configure(parser: argparse.ArgumentParser) -> None:
    from occtrack.cli.arguments import add_engine_options

    parser.add_argument("spec", metavar="SPEC", type=Path, help="the sweep spec (TOML)")
    parser.add_argument("-o", "--output", metavar="TABLE", type=Path,
                        help="the Parquet table to fill (default: SPEC with suffix .parquet); "
                             "cells already in it are skipped")
    add_engine_options(parser, "run the tasks one by one in this process, without Dask")
    parser.add_argument("--dry-run", action="store_true",
                        help="list the cells (and which are done) without running any")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def run(args: argparse.Namespace) -> int:
    from occtrack.experiments import sweep

    spec = sweep.load_spec(args.spec)
    output = args.output or args.spec.with_suffix(".parquet")
    if args.dry_run:
        cells = sweep.plan(spec)
        table = sweep.read_table(output)
        done = set(table["cell"]) if len(table) else set()
        for cell in cells:
            mark = "done" if cell.key in done else "todo"
            print(f"{mark}  {cell.key}  {cell.describe()}")
        todo = sum(cell.key not in done for cell in cells)
        print(f"{len(cells)} cells, {len(cells) - todo} in {output}, {todo} to run")
        return 0
    engine = None if args.sequential else sweep.DaskEngine(args.scheduler, args.workers)
    try:
        outcome = sweep.sweep(spec, output, engine, quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"occtrack sweep: the cells finished so far are in {output}; run the same "
              f"command again to go on", file=sys.stderr)
        raise
    if not args.quiet:
        print(sweep.summarise(outcome.table, outcome.cells))
        if outcome.notes:
            print("\nsearch: " + "\n        ".join(outcome.notes))
        print(f"\n{len(outcome.cells)} cells: {outcome.ran} run, {outcome.skipped} already in "
              f"{output}, {len(outcome.failures)} failed; {outcome.seconds:.2f} s on "
              f"{outcome.engine}"
              + (f" (start-up {outcome.startup_seconds:.2f} s)" if outcome.ran else ""))
    if outcome.failures:
        print(f"occtrack sweep: {sweep.format_failures(outcome.failures)}", file=sys.stderr)
        return 1
    return 0
