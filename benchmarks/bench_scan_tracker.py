"""The lidar scan tracker on the simulated walkway (issue 24, item 2): GOSPA per scan
(c = 1 m), identity kept through full occlusions shorter than 2 s, scans a second, for
measurement-wise occlusion and none (`occtrack.experiments.scan_tracking`).

    python benchmarks/bench_scan_tracker.py [--seeds 0 1] [--scans 600]
        [--report-min-confidence 0.5]
"""

from __future__ import annotations

import argparse

from occtrack.config.scan import ScanTrackerConfig
from occtrack.experiments.scan_tracking import run_scene, table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--scans", type=int, default=600)
    parser.add_argument("--occlusion", nargs="+", default=["measurement-wise", "none"])
    parser.add_argument("--report-min-confidence", type=float, default=0.0,
                        help="ScanTrackerConfig.report_min_confidence (default 0: off)")
    args = parser.parse_args()
    tracker = ScanTrackerConfig(report_min_confidence=args.report_min_confidence)
    runs = [run_scene(seed, occ, args.scans, tracker=tracker)
            for seed in args.seeds for occ in args.occlusion]
    print(table(runs))


if __name__ == "__main__":
    main()
