"""Speed of the highway trackers: steps per second of each occlusion handler.

Simulates the highway once (measurement-wise sensor, seed 1), keeps the scans, then times each
tracker alone over the same steps (default 10,000, the paper's run length). Issue 10's budget
is 8 s for 10,000 steps of one tracker; the authors' prototype needs about 300 s. Each tracker
first runs 50 steps untimed (its compiled loops arrive built with the install; the warm-up
fills the caches).

    python benchmarks/bench_highway.py [--steps 10000] [--sensor measurement-wise] [--repeats 3]

The time is CPU time of this process (time.process_time), the fastest of --repeats runs: on a
machine shared with other work, wall-clock time measures the others too.
"""

from __future__ import annotations

import argparse
import time

from occtrack.config.highway import HighwayTrackerConfig, SimulationConfig
from occtrack.filters.particle_tomb import HighwayTracker
from occtrack.occlusion.highway import TRACKER_NAMES
from occtrack.scenarios.highway import simulate

BUDGET = 8.0
PROTOTYPE = 300.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--sensor", default="measurement-wise",
                        choices=("object-wise", "measurement-wise"))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    simulation = SimulationConfig()
    start = time.perf_counter()
    scans = [scan for _, scan in simulate(simulation, args.sensor, args.steps, args.seed)]
    sim_seconds = time.perf_counter() - start
    print(f"simulation ({args.sensor} sensor): {args.steps} steps in {sim_seconds:.2f} s "
          f"({args.steps / sim_seconds:.0f} steps/s)")
    config = HighwayTrackerConfig.matching(simulation)
    print(f"tracker: {config.particles} particles per track, {config.undetected_particles} + "
          f"{config.birth_particles} per lane for undetected cars")
    print(f"CPU time, fastest of {args.repeats} runs")
    for name in TRACKER_NAMES:
        warm = HighwayTracker(config, name, seed=args.seed)
        for scan in scans[:50]:
            warm.step(scan)
        cpu = float("inf")
        for _ in range(args.repeats):
            tracker = HighwayTracker(config, name, seed=args.seed)
            start = time.process_time()
            for scan in scans:
                tracker.step(scan)
            cpu = min(cpu, time.process_time() - start)
        per_10k = cpu * 10_000 / args.steps
        print(f"{name:<20} {args.steps / cpu:7.0f} steps/s  {1e3 * cpu / args.steps:5.2f} ms/step"
              f"  10,000 steps: {per_10k:5.1f} s  = {per_10k / BUDGET:.2f} x budget, "
              f"{PROTOTYPE / per_10k:.0f} x faster than the prototype")


if __name__ == "__main__":
    main()
