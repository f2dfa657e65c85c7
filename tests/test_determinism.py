"""Every random thing takes a seed: `occtrack demo` and `occtrack reproduce table2` / `table3`
run twice with the same seed print the same bytes and write the same files, in fresh
processes with different hash seeds (so no set or dict order can leak in); another seed
changes the numbers that depend on it and nothing else. The only text that may differ between
two runs is a measured speed, masked here where a command prints one."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sequences import write_sequence


def occtrack(args: list[str], cwd: Path, hash_seed: int) -> tuple[str, str]:
    """Run `occtrack ARGS` in a fresh interpreter in `cwd` (made here: each run writes its
    files, under the same names, into a folder of its own); its stdout and stderr."""
    cwd.mkdir()
    env = {**os.environ, "PYTHONHASHSEED": str(hash_seed)}  # the installed occtrack
    done = subprocess.run([sys.executable, "-m", "occtrack", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout, done.stderr


def differing(a: str, b: str) -> list[int]:
    """Indices of the lines that differ (the two texts have the same number of lines)."""
    la, lb = a.splitlines(), b.splitlines()
    assert len(la) == len(lb)
    return [i for i, (x, y) in enumerate(zip(la, lb, strict=True)) if x != y]


# -- demo -----------------------------------------------------------------------------------

DEMO = ["demo", "--quiet", "--frames", "240", "--people", "8"]
# the speed's width varies (999 against 1000 steps/s), so the padding before it is masked too
DEMO_ROW = re.compile(r"^((?:none|object-wise|measurement-wise)(?:\s+\S+){8})\s+\d+$", re.M)


def demo(tmp_path: Path, seed: int, name: str, hash_seed: int) -> tuple[str, bytes]:
    """The demo's stdout with its steps/s column masked, and the PNG it drew."""
    out, err = occtrack([*DEMO, "--seed", str(seed), "--figure", "demo.png"], tmp_path / name,
                        hash_seed)
    assert err == ""
    masked, rows = DEMO_ROW.subn(r"\1 #", out)
    assert rows == 3, out  # one row per occlusion model, each ending in its speed
    return masked, (tmp_path / name / "demo.png").read_bytes()


def test_demo_repeats_byte_for_byte_by_seed(tmp_path):
    pytest.importorskip("motmetrics", reason="the demo scores with the eval extra")
    pytest.importorskip("matplotlib", reason="the demo's figure needs the viz extra")
    first = demo(tmp_path, 0, "a", hash_seed=1)
    again = demo(tmp_path, 0, "b", hash_seed=2)
    assert again == first
    other = demo(tmp_path, 1, "c", hash_seed=1)
    assert other[1] != first[1]  # another scene, another picture
    changed = differing(first[0], other[0])
    lines = first[0].splitlines()
    # the title names the seed, the detector line, the occlusions and the scores follow the
    # scene, the figure's note names the occlusion drawn; the table header names neither
    assert lines[0].startswith("Street, seed 0") and 0 in changed
    assert lines[1].startswith("detector measured on MOT17:") and 1 in changed
    assert set(changed) - {0, 1} and all(
        re.match(r"(none|object-wise|measurement-wise) |full occlusions|person |no full ",
                 lines[i]) for i in changed[2:])
    header = next(i for i, line in enumerate(lines) if line.startswith("occlusion"))
    assert header not in changed


# -- reproduce table2 -----------------------------------------------------------------------

TABLE2 = ["reproduce", "table2", "--detections", "simulated", "--no-norfair", "--quiet",
          "--gospa-figure", "gospa.png", "--frame-figure", "frame.png"]
TIMING = re.compile(r"^tracked \d+ frames x 3 models in [\d.]+ s \(\d+ frames per second\)"
                    r"(; \S+ [\d.]+ s)*$")


def table2(tmp_path: Path, seed: int, name: str, hash_seed: int) -> tuple[str, bytes, bytes]:
    """Table II's stdout (no speed in it) and its two figures; stderr holds only the timing
    line."""
    args = [*TABLE2, "--data", str(tmp_path / "data"), "--seed", str(seed)]
    out, err = occtrack(args, tmp_path / name, hash_seed)
    assert TIMING.match(err.strip()), err
    return (out, (tmp_path / name / "gospa.png").read_bytes(),
            (tmp_path / name / "frame.png").read_bytes())


def test_reproduce_table2_repeats_byte_for_byte_by_seed(tmp_path):
    """On a small synthetic MOT17-04 folder (the real one takes 15 s a run), with the
    detector simulator seeded: the same seed gives the same table and figures, another seed
    other detections, so other scores for every tracker, while the paper's rows, the headers
    and the notes stay."""
    pytest.importorskip("motmetrics", reason="Table II scores with the eval extra")
    pytest.importorskip("matplotlib", reason="the figures need the viz extra")
    write_sequence(tmp_path / "data" / "MOT17-04-FRCNN", "MOT17-04-FRCNN", people=8,
                   frames=60, length=60, seed=4)
    first = table2(tmp_path, 0, "a", hash_seed=1)
    again = table2(tmp_path, 0, "b", hash_seed=2)
    assert again == first
    other = table2(tmp_path, 1, "c", hash_seed=1)
    assert other[1] != first[1] and other[2] != first[2]
    lines = first[0].splitlines()
    changed = differing(first[0], other[0])
    assert "(seed 0): recall" in lines[0] and 0 in changed
    ours = [i for i, line in enumerate(lines)
            if re.match(r"  (none|measurement-wise|object-wise|bytetrack|ocsort) ", line)]
    assert len(ours) >= 6 and set(changed) <= {0, *ours}
    assert len(set(changed) & set(ours)) >= len(ours) - 1  # (a row may tie by chance)
    assert all("[paper]" not in lines[i] for i in changed)


# -- reproduce table3 -----------------------------------------------------------------------

SECONDS = re.compile(r"(Tracker seconds per run: |^\d+ steps, \d+ tracks, ).*$", re.M)


def table3(tmp_path: Path, seeds: int, jobs: int, hash_seed: int) -> str:
    out, err = occtrack(["reproduce", "table3", "--steps", "40", "--seeds", str(seeds),
                         "--jobs", str(jobs), "--quiet"], tmp_path / f"{seeds}-{jobs}",
                        hash_seed)
    text = out + "\n--- stderr\n" + err
    masked, timings = SECONDS.subn(r"\1#", text)
    assert timings == 2, text
    return masked


def test_reproduce_table3_repeats_byte_for_byte_whatever_the_workers(tmp_path):
    """The highway table at its smallest (40 steps, one seed): the same bytes from one worker
    and from two (cells finish in any order), and seeds 1..2 instead of 1..1 change every
    GOSPA cell but not the paper's values in brackets."""
    first = table3(tmp_path, 1, 1, hash_seed=1)
    assert table3(tmp_path, 1, 2, hash_seed=2) == first
    other = table3(tmp_path, 2, 1, hash_seed=1)
    assert other != first
    ours = re.compile(r"(\d+\.\d+)(?: \[(\d+\.\d+)\])")
    cells, other_cells = ours.findall(first), ours.findall(other)
    assert len(cells) == len(other_cells) == 6
    assert [paper for _, paper in cells] == [paper for _, paper in other_cells]
    assert all(a != b for (a, _), (b, _) in zip(cells, other_cells, strict=True))
