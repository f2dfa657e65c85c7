"""Branch coverage of the filter's housekeeping: which of its branches the tests take.

    python benchmarks/coverage_housekeeping.py [--tests FILE ...] [--json PATH]

Runs the given tests (default: tests/test_housekeeping.py) under coverage.py with branch
measurement (the `dev` extra) and prints, for each method of `GaussianMixturePMB` that handles
capacity, trimming, merging and recycling, its lines and branches run and the branches never
taken (`line->line`, -N meaning the method returns). Exits 1 unless every one of those branches
is taken, so a new branch without a test shows. Not CI: coverage's tracing slows the filter
down; the whole run takes about 10 s. Needs coverage 7.6 or later (per-function JSON) and
occtrack installed editable, so that the Python modules run from src/ and the kernels from the
build (docs/development.md, "Working on the code": `pip install --no-build-isolation -e ".[dev]"`).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCE = "src/occtrack/filters/gmpmb/__init__.py"  # the class (its kernels are compiled)
CLASS = "GaussianMixturePMB"
# the housekeeping methods named by issue 15: storage growth, capacity, trimming, labels and
# recycling, merging, the existence guard, confirmation, the one-time warnings
METHODS = ("_reserve", "_reserve_slots", "_select", "_assign_labels", "_recycle_unplaced",
           "_merge", "_cap_existence", "_confirm_or_delete", "_warn_once")


def measure(tests: list[str], workdir: Path) -> dict:
    """coverage.py's JSON report of `SOURCE` after running `tests` with branch measurement."""
    data = workdir / ".coverage"
    env = {**os.environ, "COVERAGE_FILE": str(data)}  # the editable install: src/ + built kernels
    run = [sys.executable, "-m", "coverage", "run", "--branch", f"--source={ROOT / 'src'}",
           "-m", "pytest", "-q", "-p", "no:randomly", "-p", "no:xdist", "-p",
           "no:cacheprovider", *tests]
    done = subprocess.run(run, cwd=ROOT, env=env)
    if done.returncode != 0:
        sys.exit(f"the tests failed (exit {done.returncode}); coverage not reported")
    out = workdir / "coverage.json"
    subprocess.run([sys.executable, "-m", "coverage", "json", "-q", "-o", str(out),
                    f"--include=*/{SOURCE}"], cwd=ROOT, env=env, check=True)
    files = json.loads(out.read_text())["files"]
    (entry,) = [v for k, v in files.items() if k.replace(os.sep, "/").endswith(SOURCE)]
    return entry


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tests", nargs="+", metavar="FILE",
                        default=["tests/test_housekeeping.py"],
                        help="test files or node ids to run (default: tests/test_housekeeping.py)")
    parser.add_argument("--json", type=Path, help="also keep coverage.py's JSON report here")
    args = parser.parse_args()
    try:
        import coverage  # noqa: F401
    except ImportError:
        sys.exit('coverage is not installed: pip install -e ".[dev]"')
    with tempfile.TemporaryDirectory(prefix="occtrack-coverage-") as tmp:
        entry = measure(args.tests, Path(tmp))
        if args.json:
            args.json.write_text(json.dumps(entry, indent=1))
    functions = entry["functions"]
    print(f"branch coverage of {SOURCE} under {' '.join(args.tests)}\n")
    print(f"{'method':<20}{'lines':>10}{'branches':>11}   never taken")
    total_branches = taken_branches = 0
    for method in METHODS:
        f = functions[f"{CLASS}.{method}"]
        s = f["summary"]
        lines = s["num_statements"] - s["missing_lines"]
        taken = s["covered_branches"]
        total_branches += s["num_branches"]
        taken_branches += taken
        missing = " ".join(f"{a}->{b}" for a, b in f.get("missing_branches", []))
        print(f"{method:<20}{lines:>5}/{s['num_statements']:<4}{taken:>6}/{s['num_branches']:<4}"
              f"   {missing or '-'}")
    share = taken_branches / total_branches if total_branches else 1.0
    print(f"\n{taken_branches} of {total_branches} branches taken ({share:.1%})")
    return 0 if taken_branches == total_branches else 1


if __name__ == "__main__":
    sys.exit(main())
