"""Calibrated settings carried from one sequence to another, against the defaults.

For every sequence S of the folder, `occtrack calibrate` writes two settings files from S's
ground truth and detections: one for `occlusion = none` (detectability of tracked people) and
one for the occlusion models (detectability of visible people). Every other sequence T is then
tracked with each of them and with the defaults, by the three occlusion models, as tasks of
`occtrack sweep` (Dask LocalCluster, or --sequential), and scored under the mot17 protocol
(TrackEval). Printed: HOTA / IDF1 / MOTA per target sequence and tracker, the defaults first,
then each source; '>=' when the calibrated file scores at least the defaults on all three.

The table (--table, Parquet) keeps every cell: a rerun only runs what is missing.

    PYTHONPATH=src python benchmarks/bench_calibration.py ../shared/data/mot17 [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from occtrack.cli import main as occtrack
from occtrack.experiments import sweep
from occtrack.experiments.benchmark import MODELS, find_sequences
from occtrack.io.mot import read_seqinfo

METRICS = ("hota", "idf1", "mota")
SPEC = """\
trackers = {trackers}
[work]
kind = "mot"
sequences = [{sequence}]
{config}
"""


def calibrate(folder: Path, occlusion: str, out: Path) -> Path:
    if not out.exists():
        code = occtrack(["calibrate", str(folder / "gt" / "gt.txt"),
                         str(folder / "det" / "det.txt"), "--occlusion", occlusion, "-o",
                         str(out), "--quiet"])
        if code:
            sys.exit(f"occtrack calibrate failed on {folder}")
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("root", type=Path, help="a folder of sequence folders (MOT17)")
    parser.add_argument("--table", type=Path, help="Parquet table to keep (default: a "
                                                   "temporary one)")
    parser.add_argument("--workers", type=int, help="LocalCluster workers (default: cores)")
    parser.add_argument("--sequential", action="store_true", help="run without Dask")
    args = parser.parse_args()

    folders = find_sequences(args.root)
    names = {folder: str(read_seqinfo(folder)["name"]) for folder in folders}
    work = Path(tempfile.mkdtemp(prefix="occtrack-calibration-"))
    table = args.table or work / "table.parquet"
    specs = []
    for target in folders:
        quoted = json.dumps(str(target.resolve()))
        specs.append((names[target], "defaults", SPEC.format(
            trackers=json.dumps(list(MODELS)), sequence=quoted, config="")))
        for source in folders:
            if source == target:
                continue
            for occlusion, trackers in (("none", ["none"]),
                                        ("measurement-wise", [m for m in MODELS if m != "none"])):
                toml = calibrate(source, occlusion, work / f"{names[source]}-{occlusion}.toml")
                specs.append((names[target], names[source], SPEC.format(
                    trackers=json.dumps(trackers), sequence=quoted,
                    config=f"config = {json.dumps(str(toml))}")))
    engine = None if args.sequential else sweep.DaskEngine(workers=args.workers)
    results: dict = {}
    try:
        if engine is not None:
            engine.__enter__()
        for i, (target, source, text) in enumerate(specs):
            path = work / f"spec{i}.toml"
            path.write_text(text)
            spec = sweep.load_spec(path)
            outcome = sweep.sweep(spec, table, engine, quiet=False)
            if outcome.failures:
                sys.exit(sweep.format_failures(outcome.failures))
            keys = {cell.key: cell.tracker for cell in outcome.cells}
            rows = outcome.table[outcome.table["cell"].isin(keys)]
            for _, row in rows.iterrows():
                results[(target, row["tracker"], source)] = tuple(row[m] for m in METRICS)
    finally:
        if engine is not None:
            engine.__exit__(None, None, None)

    sources = list(dict.fromkeys(names.values()))
    print(f"HOTA / IDF1 / MOTA, mot17 protocol; settings files in {work}")
    print(f"  {'sequence':<16}{'tracker':<18}{'defaults':<23}"
          + "".join(f"{'calibrated on ' + s[:8]:<26}" for s in sources))
    for target in sources:
        for tracker in MODELS:
            base = results[(target, tracker, "defaults")]
            cells = [f"{' / '.join(f'{v:.3f}' for v in base):<23}"]
            for source in sources:
                got = results.get((target, tracker, source))
                if got is None:
                    cells.append(f"{'-':<26}")
                    continue
                mark = ">=" if all(round(g, 3) >= round(b, 3)
                                   for g, b in zip(got, base, strict=True)) else "  "
                cells.append(f"{' / '.join(f'{v:.3f}' for v in got)} {mark}".ljust(26))
            print(f"  {target:<16}{tracker:<18}" + "".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
