"""Speed of `occtrack sweep` on Dask: 1 against 2 local workers on one 24-task sweep, in one run.

The sweep: the highway simulation, 2 simulated occlusions x 3 trackers x 4 seeds = 24 tasks of
--steps steps each. It runs on fresh tables in this process (no Dask), then --repeats times on
a LocalCluster of 1 worker and on one of 2 workers, alternated so that a change in the
machine's load hits both (each cluster is started before the clock starts and stopped after;
its start-up, workers' imports included, is printed apart). Printed: the wall time of the
tasks, the sum of the tasks' own times and CPU times, the cores the workers had (CPU / wall),
the speed-up from 1 to 2 workers, and the per-task overhead of the machinery,
(wall - sum of task times) / tasks with 1 worker: scheduling, moving cells and rows, the
progress bar and the table's writes.

    PYTHONPATH=src python benchmarks/bench_sweep.py [--steps 300]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from occtrack.experiments import sweep

SPEC = """\
trackers = ["object-wise-expval", "object-wise-grid", "measurement-wise"]
seeds = 4
[work]
kind = "highway"
steps = {steps}
sensors = ["object-wise", "measurement-wise"]
"""


def timed(spec, output: Path, engine=None) -> dict:
    outcome = sweep.sweep(spec, output, engine)
    if outcome.failures:
        sys.exit(sweep.format_failures(outcome.failures))
    table = outcome.table
    return {"wall": outcome.seconds, "busy": float(table["task_seconds"].sum()),
            "cpu": float(table["cpu_seconds"].sum()), "tasks": outcome.ran}


def on_cluster(spec, output: Path, workers: int) -> dict:
    start = time.perf_counter()
    with sweep.DaskEngine(workers=workers) as engine:
        engine.warm(spec.kind)
        startup = time.perf_counter() - start
        result = timed(spec, output, engine)
    return {**result, "startup": startup}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=2,
                        help="pairs of 1- and 2-worker runs, alternated (default 2)")
    args = parser.parse_args()
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = folder / "spec.toml"
        path.write_text(SPEC.format(steps=args.steps))
        spec = sweep.load_spec(path)
        n = len(sweep.plan(spec))
        print(f"sweep: highway, {n} tasks of {args.steps} steps; machine: "
              f"{sweep.available_cores()} cores, load average {load} before")
        runs = [("this process", {**timed(spec, folder / "sequential.parquet"),
                                  "startup": 0.0})]
        for k in range(args.repeats):
            for workers in (1, 2):
                name = f"LocalCluster, {workers} worker{'s' * (workers > 1)}"
                runs.append((name, on_cluster(spec, folder / f"d{workers}-{k}.parquet",
                                              workers)))
        print(f"  {'engine':<26}{'start-up s':>11}{'wall s':>9}{'sum of tasks s':>16}"
              f"{'CPU s':>8}{'cores had':>11}{'overhead ms/task':>18}")
        for name, r in runs:
            overhead = (r["wall"] - r["busy"]) / r["tasks"] * 1000
            shown = f"{overhead:>18.1f}" if "2 workers" not in name else f"{'-':>18}"
            print(f"  {name:<26}{r['startup']:>11.2f}{r['wall']:>9.2f}{r['busy']:>16.2f}"
                  f"{r['cpu']:>8.2f}{r['cpu'] / r['wall']:>11.2f}{shown}")
        pairs = [(runs[1 + 2 * k][1], runs[2 + 2 * k][1]) for k in range(args.repeats)]
        ratios = [one["wall"] / two["wall"] for one, two in pairs]
        overheads = [(one["wall"] - one["busy"]) / one["tasks"] * 1000 for one, _ in pairs]
        print(f"speed-up 1 -> 2 workers (wall): {', '.join(f'{r:.2f}' for r in ratios)} "
              f"(target >= 1.7); per-task overhead with 1 worker: "
              f"{', '.join(f'{o:.1f}' for o in overheads)} ms (target < 50 ms)")
        print("cores had = CPU seconds of the tasks / wall seconds: what the machine gave the "
              "workers (2 workers on 2 idle cores: about 2)")
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
