"""How long `occtrack reproduce table2` takes, against the issue's 30-second budget.

Runs the command as a user would (a fresh process, MOT17-04 found as the command finds it) and
prints the wall time of the whole job, with and without the baselines (norfair, ByteTrack and
OC-SORT), and the tracking rate of the three occtrack models the command itself reports.

    python benchmarks/bench_table2.py
"""

from __future__ import annotations

import subprocess
import sys
import time

BUDGET = 30.0


def timed(args: list[str]) -> tuple[float, str]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "occtrack", "reproduce", "table2", "--json",
                           "--quiet", *args], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(done.stderr.strip())
    return seconds, done.stderr.strip().splitlines()[-1]


def main() -> None:
    print(f"occtrack reproduce table2 (MOT17-04, 1050 frames, budget {BUDGET:.0f} s)")
    for label, args in (("three occlusion models", ["--no-norfair", "--no-peers"]),
                        ("three models + baselines", [])):
        seconds, summary = timed(args)
        print(f"  {label:<24} {seconds:6.1f} s wall  ({seconds / BUDGET:.2f} of the budget)"
              f"   [{summary}]")


if __name__ == "__main__":
    main()
