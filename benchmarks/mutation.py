"""Mutation testing of the core with mutmut 3: how many small faults the tests notice.

    python benchmarks/mutation.py [--modules filters models ...] [--tests all | FILE ...]
                                  [--max-children 1] [--budget MINUTES] [--workdir DIR]

Slow (tens of minutes per module group on one core), so never part of CI. mutmut (the `dev`
extra: pip install -e ".[dev]") plants one small fault (a mutant) at a time in each function
of the chosen modules and runs the tests that call that function; a mutant that no test
notices survives. Its settings are [tool.mutmut] in pyproject.toml; this script runs it in a
copy of src/, tests/ and pyproject.toml (so the checkout gets no mutants/ folder), with the
modules and tests chosen here, by default each module group's own tests.

Compiled loops are not mutated: the kernels are Cython (the _*.pyx beside each package's
modules), which mutmut does not read, so they get no mutants and count in no score. What
notices a fault in them is their comparison with plain numpy:
tests/test_kernels.py for the filter's kernels, test_scaling.py for the box model's,
test_highway_kernels.py for the highway's, and the hand-worked values of
tests/test_housekeeping.py.

Prints, per module: killed (a timeout counts: a fault that hangs the code is noticed),
survived (no test failed, including functions no test calls), equivalent (survivors listed in
benchmarks/mutation_equivalent.md: they change nothing observable, so no test can kill them),
and the score killed / (killed + survived - equivalent); then every other survivor, to be
read with `mutmut show NAME` in the work directory. With --budget the run stops after that
many minutes and the score covers the mutants checked by then; --workdir DIR keeps the work
directory and a second run with the same DIR resumes where the first stopped.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EQUIVALENT = ROOT / "benchmarks" / "mutation_equivalent.md"

# module group -> (files mutated, the tests that exercise them). The highway's particle filter,
# sensor model and occlusion handlers and the detector calibration are groups of their own. The
# highway's loops are compiled kernels (no mutants), so its group mutates the Python around
# them, checked by the kernels' bit-for-bit comparison with numpy, the tracker's and
# simulator's tests and tests/test_highway_mutants.py. The compiled kernels (the _*.pyx) are
# no Python for mutmut: build them in place first (occtrack's src/ then imports them).
BOX_MODELS = [f"src/occtrack/models/{name}.py" for name in ("birth", "box", "markov", "motion")]
# the box tracker's occlusion models (the highway's, extents.py and highway.py, go with it)
BOX_OCCLUSION = ("base", "boxes", "box_geometry", "box_measurementwise", "box_objectwise")
GROUPS = {
    "filters": (["src/occtrack/filters/gmpmb/*", "src/occtrack/filters/beam_bernoulli.py"],
                ["test_housekeeping.py", "test_tracker.py", "test_kernels.py", "test_lidar.py"]),
    "association": (["src/occtrack/association/*"], ["test_lbp.py", "test_association_exact.py"]),
    "occlusion": ([f"src/occtrack/occlusion/{name}.py" for name in BOX_OCCLUSION],
                  ["test_box_occlusion.py", "test_occlusion_terms.py", "test_tracker.py",
                   "test_housekeeping.py"]),
    "models": ([*BOX_MODELS, "src/occtrack/models/beam.py"],
               ["test_gaussian.py", "test_box_occlusion.py", "test_housekeeping.py",
                "test_tracker.py", "test_scaling.py", "test_lidar.py", "test_kernels.py"]),
    "densities": (["src/occtrack/densities/*"], ["test_gaussian.py"]),
    "io-mot": (["src/occtrack/io/mot.py"],
               ["test_io_mot.py", "test_eval.py", "test_cli_track.py"]),
    "gospa": (["src/occtrack/metrics/gospa.py", "src/occtrack/spatial.py"],
              ["test_gospa.py", "test_gospa_exact.py", "test_eval.py", "test_scaling.py"]),
    "highway": (["src/occtrack/filters/particle_tomb.py", "src/occtrack/models/highway_sensor.py",
                 "src/occtrack/occlusion/extents.py", "src/occtrack/occlusion/highway.py"],
                ["test_highway_kernels.py", "test_highway_tracker.py", "test_highway_sim.py",
                 "test_highway_mutants.py"]),
    "calibration": (["src/occtrack/models/calibration.py"], ["test_calibrate.py"]),
    # (not test_scaling's hard-limit warning test: it checks the warning's stacklevel, which
    # mutmut's wrappers shift; not test_faults: its interrupted child processes time out
    # under mutmut)
    "tracker": (["src/occtrack/tracker/tracker.py", "src/occtrack/tracker/camera.py",
                 "src/occtrack/tracker/boxes.py"],
                ["test_tracker.py", "test_api.py", "test_validation_messages.py",
                 "test_supervision.py", "test_cli_track.py", "test_cli_errors.py",
                 "test_properties.py",
                 *(f"test_scaling.py::test_{name}" for name in (
                     "sparse_camera_shift_equals_the_all_pairs_one",
                     "sparse_candidates_are_the_all_pairs_ones",
                     "sparse_candidates_reach_the_edge_of_what_qualifies",
                     "the_camera_pairs_boxes_by_their_own_extent_on_each_axis",
                     "camera_shift_needs_min_pairs_and_finds_the_majority",
                     "the_camera_mode_counts_every_vote_of_the_all_pairs_rule",
                     "gated_and_ungated_runs_give_the_same_tracks",
                     "a_crowd_of_150_is_reported_whole_with_the_default_capacity",
                     "a_crowd_missed_at_random_is_reported_within_95_to_105_percent",
                     "the_pool_stays_bounded_over_a_long_run"))]),
}
SLOW: set[str] = set()  # groups that take hours on one core: only when asked for (none now)
DETECTED = {"killed", "timeout", "segfault"}
UNDETECTED = {"survived", "no tests", "suspicious"}


def mutmut_executable() -> str:
    found = shutil.which("mutmut", path=str(Path(sys.executable).parent)) or shutil.which(
        "mutmut")
    if found is None:
        sys.exit('mutmut is not installed: pip install -e ".[dev]"')
    return found


def mutmut_table(only_mutate: list[str], tests: list[str]) -> str:
    quoted = ", ".join(f'"{t}"' for t in tests)
    globs = ", ".join(f'"{g}"' for g in only_mutate)
    return ("[tool.mutmut]\n"
            'source_paths = ["src"]\n'
            f"only_mutate = [{globs}]\n"
            f"pytest_add_cli_args_test_selection = [{quoted}]\n"
            'pytest_add_cli_args = ["-p", "no:xdist", "-p", "no:cacheprovider"]\n\n')


def prepare(workdir: Path, only_mutate: list[str], tests: list[str]) -> None:
    """Copy the project into `workdir` with [tool.mutmut] set to this run's choice."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache")
    for folder in ("src", "tests"):
        shutil.copytree(ROOT / folder, workdir / folder, ignore=ignore, dirs_exist_ok=True)
    text = (ROOT / "pyproject.toml").read_text()
    table = re.compile(r"^\[tool\.mutmut\]\n.*?(?=^\[)", re.S | re.M)
    if not table.search(text):
        sys.exit("pyproject.toml has no [tool.mutmut] table")
    (workdir / "pyproject.toml").write_text(table.sub(mutmut_table(only_mutate, tests), text))


def run_mutmut(workdir: Path, max_children: int, budget: float | None) -> bool:
    """Run `mutmut run`; True if it finished, False if the budget stopped it."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # mutmut sets the path
    env["OCCTRACK_HYPOTHESIS_PROFILE"] = "mutation"  # no shrinking (tests/conftest.py)
    command = [mutmut_executable(), "run", "--max-children", str(max_children)]
    with open(workdir / "mutmut-run.log", "a") as log:
        proc = subprocess.Popen(command, cwd=workdir, env=env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        try:
            proc.wait(timeout=None if budget is None else budget * 60)
            return True
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGTERM)  # mutmut and the workers it forked
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            return False


def results(workdir: Path) -> dict[str, str]:
    """mutant name -> status, as `mutmut results --all true` lists them."""
    out = subprocess.run([mutmut_executable(), "results", "--all", "true"], cwd=workdir,
                         capture_output=True, text=True, check=True).stdout
    return dict(re.findall(r"^\s+(\S+): (.+?)\s*$", out, re.M))


def equivalent_names() -> set[str]:
    if not EQUIVALENT.is_file():
        return set()
    return set(re.findall(r"`(occtrack\.\S+?__mutmut_\d+)`", EQUIVALENT.read_text()))


def module_of(mutant: str) -> str:
    return re.split(r"\.x[ǁ_]", mutant, maxsplit=1)[0]


def report(status: dict[str, str], equivalent: set[str]) -> float:
    by_module: dict[str, Counter] = defaultdict(Counter)
    for name, s in status.items():
        c = by_module[module_of(name)]
        if s in DETECTED:
            c["killed"] += 1
        elif s in UNDETECTED:
            c["survived"] += 1
            c["equivalent"] += name in equivalent
        else:
            c["other"] += 1  # not checked (budget), skipped, interrupted
    total: Counter = Counter()
    print(f"{'module':<42}{'killed':>8}{'survived':>10}{'equivalent':>12}{'unchecked':>11}"
          f"{'score':>9}")
    for module in sorted(by_module) + ["all"]:
        c = total if module == "all" else by_module[module]
        if module != "all":
            total.update(c)
        scored = c["killed"] + c["survived"] - c["equivalent"]
        score = c["killed"] / scored if scored else float("nan")
        print(f"{module:<42}{c['killed']:>8}{c['survived']:>10}{c['equivalent']:>12}"
              f"{c['other']:>11}{format(score, '.1%') if scored else '-':>9}")
    scored = total["killed"] + total["survived"] - total["equivalent"]
    return total["killed"] / scored if scored else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--modules", nargs="+", choices=sorted(GROUPS),
                        default=sorted(set(GROUPS) - SLOW),
                        help="module groups to mutate (default: all"
                             + (f" but the slow {', '.join(sorted(SLOW))})" if SLOW else ")"))
    parser.add_argument("--tests", nargs="+", metavar="FILE",
                        help="test files (in tests/) to run, or 'all' (default: the groups' own)")
    parser.add_argument("--max-children", type=int, default=1,
                        help="mutants tested at once (default 1: one core)")
    parser.add_argument("--budget", type=float, metavar="MINUTES",
                        help="stop mutmut after this many minutes")
    parser.add_argument("--workdir", type=Path,
                        help="keep the work here; an existing one resumes (default: a temporary "
                             "folder, removed afterwards)")
    args = parser.parse_args()

    only_mutate = [g for m in args.modules for g in GROUPS[m][0]]
    if args.tests == ["all"]:
        tests = ["tests/"]
    else:
        names = args.tests or dict.fromkeys(t for m in args.modules for t in GROUPS[m][1])
        tests = [f"tests/{Path(t).name}" for t in names]
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="occtrack-mutation-"))
    workdir.mkdir(parents=True, exist_ok=True)
    try:
        if not (workdir / "mutants").is_dir():
            prepare(workdir, only_mutate, tests)
        print(f"mutating {' '.join(only_mutate)}\nwith {' '.join(tests)}\nin {workdir} "
              f"(log: mutmut-run.log)", flush=True)
        start = time.monotonic()
        finished = run_mutmut(workdir, args.max_children, args.budget)
        minutes = (time.monotonic() - start) / 60
        print(f"mutmut {'finished' if finished else 'stopped by the budget'} after "
              f"{minutes:.1f} min\n")
        status = results(workdir)
        if not status:
            print("no mutants were checked; see mutmut-run.log")
            return 1
        equivalent = equivalent_names()
        score = report(status, equivalent)
        if score != score:  # nan: no mutant was killed or survived, so there is no score
            print("\nno mutant was run by the tests (every one is "
                  f"{', '.join(sorted(set(status.values())))}): the tests import an occtrack "
                  "other than the mutated copy, as a regular (not in-place) install does; "
                  "build in place with pip install --no-build-isolation -e . and run again",
                  file=sys.stderr)
            return 1
        survivors = sorted(n for n, s in status.items() if s in UNDETECTED and n not in equivalent)
        print(f"\nmutation score {score:.1%} (killed / (killed + survived - equivalent))")
        if survivors:
            where = (f"cd {workdir} && mutmut show NAME" if args.workdir else
                     "run with --workdir DIR to keep them for `mutmut show NAME`")
            print(f"\n{len(survivors)} survivors not listed as equivalent ({where}):")
            for name in survivors:
                print(f"  {name}: {status[name]}")
    finally:
        if args.workdir is None:
            shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
