"""Each chosen setting, chosen on some data sets and checked on the one left out (issue 37:
"validation that shows generality").

    python benchmarks/leave_one_set_out.py ../shared/data/mot17 ../shared/data/mot17-yolox \
        ../shared/data/kitti [--settings tail_weight,tail_scale] [--json out.json]

The sets are the folders given: a MOTChallenge folder of sequences (MOT17 with FRCNN boxes,
MOT17 with YOLOX-X boxes) or a KITTI tracking folder (its cars and its pedestrians are one set:
their two mean HOTAs averaged). For each setting in `GRIDS` and each value of its grid, the
default tracker (object-wise occlusion, every other setting its default) is scored on every
set: mean HOTA over the set's sequences, TrackEval as `occtrack benchmark` scores. Then, for
each set left out, the value with the best mean over the other sets is "chosen", and the table
shows the left-out set's HOTA under that value beside its HOTA under the default and under the
value best for it alone. A setting transfers when the value chosen without a set is the
default, or scores within a hair of it on that set.

Every run is `occtrack.experiments`' own benchmark, a (set, value) pair a process
(`--workers`, 2 by default): about 25 minutes for every setting on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from occtrack.experiments import benchmark as mot_benchmark
from occtrack.experiments import benchmark_kitti

GRIDS = {
    "tail_weight": [0.0, 0.02, 0.05, 0.1, 0.2],
    "tail_scale": [2.0, 3.0, 5.0],
    "edge_noise": [0.04, 0.069, 0.1],
    "position_noise": [0.033, 0.066, 0.13],
    "report_min_confidence": [0.3, 0.5, 0.7],
}
"""Grids of the settings this table checks, each holding its default."""


def set_name(root: Path) -> str:
    return root.resolve().name


def set_score(root: Path, settings: dict) -> float:
    """Mean HOTA of the default object-wise tracker with `settings` on the set at `root`: the
    mean over its sequences (KITTI: of cars' and pedestrians' means)."""
    if benchmark_kitti.is_layout(root):
        report = benchmark_kitti.benchmark(root, ["object-wise"], quiet=True, settings=settings)
        means = report["mean"]["classes"]
        return float(np.mean([means[cls]["trackers"]["object-wise"]["hota"] for cls in means]))
    report = mot_benchmark.benchmark(root, ["object-wise"], quiet=True, settings=settings)
    return float(report["mean"]["trackers"]["object-wise"]["hota"])


def leave_one_out(scores: dict[str, dict[float, float]], default: float) -> list[dict]:
    """Per set left out: the value chosen on the others (best mean; ties to the default, then
    to the first in the grid), and the left-out set's HOTA under it, the default and its own
    best. `scores[set][value]` is a set's mean HOTA."""
    sets = list(scores)
    values = list(next(iter(scores.values())))
    rows = []
    for out in sets:
        rest = [s for s in sets if s != out]
        means = {v: float(np.mean([scores[s][v] for s in rest])) for v in values}
        top = max(means.values())
        chosen = default if means[default] >= top - 1e-12 else next(
            v for v in values if means[v] >= top - 1e-12)
        own = max(values, key=lambda v: scores[out][v])
        rows.append({"left_out": out, "chosen": chosen, "hota_chosen": scores[out][chosen],
                     "hota_default": scores[out][default], "best_alone": own,
                     "hota_best_alone": scores[out][own]})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sets", nargs="+", type=Path, help="data set folders (two or more)")
    parser.add_argument("--settings", default=",".join(GRIDS),
                        help=f"which settings (default: all of {', '.join(GRIDS)})")
    parser.add_argument("--json", type=Path, help="also write every score to this file")
    parser.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    args = parser.parse_args(argv)
    names = [s.strip() for s in args.settings.split(",") if s.strip()]
    unknown = [n for n in names if n not in GRIDS]
    if unknown or len(args.sets) < 2:
        parser.error(f"unknown setting {unknown[0]}" if unknown else "give two sets or more")
    if args.json and args.json.exists():
        parser.error(f"{args.json} exists; give a new file name")
    from occtrack import TrackerConfig

    for root in args.sets:  # (checked before the first long run)
        if not (benchmark_kitti.is_layout(root) or mot_benchmark.find_sequences(root)):
            parser.error(f"{root}: neither a KITTI folder nor a folder of MOTChallenge "
                         f"sequences")
    everything = {}
    print("| setting (default) | left out | chosen on the others | HOTA there: chosen / "
          "default / best alone (value) |")
    print("|---|---|---|---|")
    for name in names:
        default = getattr(TrackerConfig(), name)
        tasks = [(root, {name: v}) for root in args.sets for v in GRIDS[name]]
        with ProcessPoolExecutor(args.workers) as pool:
            done = list(pool.map(set_score, [t[0] for t in tasks], [t[1] for t in tasks]))
        scores: dict[str, dict[float, float]] = {}
        for (root, value), hota in zip(tasks, done, strict=True):
            scores.setdefault(set_name(root), {})[value[name]] = hota
        everything[name] = {s: {str(v): h for v, h in row.items()} for s, row in scores.items()}
        for row in leave_one_out(scores, default):
            print(f"| `{name}` ({default:g}) | {row['left_out']} | {row['chosen']:g} | "
                  f"{row['hota_chosen']:.3f} / {row['hota_default']:.3f} / "
                  f"{row['hota_best_alone']:.3f} ({row['best_alone']:g}) |", flush=True)
    if args.json:  # (whole or not at all: a temporary file renamed into place)
        part = args.json.with_name(args.json.name + ".part")
        part.write_text(json.dumps(everything, indent=1))
        os.replace(part, args.json)
    return 0


if __name__ == "__main__":
    from occtrack.errors import OcctrackError

    try:
        sys.exit(main())
    except OcctrackError as err:
        sys.exit(f"leave_one_set_out.py: error: {err}")
