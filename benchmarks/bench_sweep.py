"""Speed of `occtrack sweep` on Dask: 1 against 2 local workers on one 24-task sweep, in one run.

The sweep: the highway simulation, 2 simulated occlusions x 3 trackers x 4 seeds = 24 tasks of
--steps steps each. It runs three times on fresh tables: in this process (no Dask), on a
LocalCluster of 1 worker and on one of 2 workers (each cluster started before the clock starts
and stopped after; its start-up, workers' imports included, is printed apart). Printed: the
wall time of the tasks, the sum of the tasks' own times, the speed-up from 1 to 2 workers, and
the per-task overhead of the machinery, (wall - sum of task times) / tasks with 1 worker:
scheduling, moving cells and rows, the progress bar and the table's writes.

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


def timed(spec, output: Path, engine=None) -> tuple[float, float, int]:
    outcome = sweep.sweep(spec, output, engine)
    if outcome.failures:
        sys.exit(sweep.format_failures(outcome.failures))
    busy = float(outcome.table["task_seconds"].sum())
    return outcome.seconds, busy, outcome.ran


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = folder / "spec.toml"
        path.write_text(SPEC.format(steps=args.steps))
        spec = sweep.load_spec(path)
        n = len(sweep.plan(spec))
        print(f"sweep: highway, {n} tasks of {args.steps} steps; machine: "
              f"{sweep.available_cores()} cores, load average "
              f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        rows = []
        wall, busy, ran = timed(spec, folder / "sequential.parquet")
        rows.append(("this process", 0.0, wall, busy, ran))
        for workers in (1, 2):
            start = time.perf_counter()
            with sweep.DaskEngine(workers=workers) as engine:
                engine.warm(spec.kind)
                startup = time.perf_counter() - start
                wall, busy, ran = timed(spec, folder / f"dask{workers}.parquet", engine)
            rows.append((f"LocalCluster, {workers} worker{'s' * (workers > 1)}", startup, wall,
                         busy, ran))
        print(f"  {'engine':<26}{'start-up s':>11}{'tasks wall s':>14}{'sum of tasks s':>16}"
              f"{'overhead ms/task':>18}")
        for name, startup, wall, busy, ran in rows:
            overhead = (wall - busy) / ran * 1000 if "2 workers" not in name else float("nan")
            print(f"  {name:<26}{startup:>11.2f}{wall:>14.2f}{busy:>16.2f}"
                  + (f"{overhead:>18.1f}" if overhead == overhead else f"{'-':>18}"))
        one, two = rows[1][2], rows[2][2]
        print(f"speed-up 1 -> 2 workers: {one / two:.2f} (target >= 1.7); per-task overhead "
              f"with 1 worker: {(rows[1][2] - rows[1][3]) / rows[1][4] * 1000:.1f} ms "
              f"(target < 50 ms)")
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
