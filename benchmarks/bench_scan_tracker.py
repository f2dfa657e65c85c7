"""The lidar scan tracker on the simulated walkway (issue 24, item 2): GOSPA per scan
(c = 1 m), identity kept through full occlusions shorter than 2 s, scans a second, for
measurement-wise occlusion and none (`occtrack.experiments.scan_tracking`).

    python benchmarks/bench_scan_tracker.py [--seeds 0 1] [--scans 600]
"""

from __future__ import annotations

import argparse

from occtrack.experiments.scan_tracking import run_scene, table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--scans", type=int, default=600)
    parser.add_argument("--occlusion", nargs="+", default=["measurement-wise", "none"])
    args = parser.parse_args()
    runs = [run_scene(seed, occ, args.scans) for seed in args.seeds for occ in args.occlusion]
    print(table(runs))


if __name__ == "__main__":
    main()
