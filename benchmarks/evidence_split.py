"""How the ground tracker's score evidence was chosen (issue 40): each (weight, lookahead) pair
run on KITTI's sequences with PointRCNN's 3D detections, scored on the five sequences it was
chosen on and on the five it was checked on.

    python benchmarks/evidence_split.py [--data DIR] [--pairs W,S ...] [--quiet]

DIR is a KITTI tracking folder (as `benchmarks/hidden_kept.py` finds it). A pair W,S is
`track_kitti`'s `evidence_weight` W (what one frame's score log-likelihood ratio counts for)
and `lookahead` S seconds; the default pairs are docs/kitti-3d.md's table. Each pair is run as
`occtrack benchmark DIR --detections pointrcnn` runs object-wise occtrack, those two options
aside.

Per class and half: HOTA per sequence weighted by the sequence's scored true boxes (a half's
sequences pooled as a user's would be), and the ECE of the half's boxes pooled (the
reliability bins summed over its sequences); then the ten sequences combined as the benchmark
reports them (TrackEval's COMBINED_SEQ HOTA, the pooled ECE).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from occtrack.experiments import benchmark_kitti
from occtrack.metrics.reliability import Reliability, pooled

sys.path.insert(0, str(Path(__file__).resolve().parent))
from hidden_kept import data_folder  # noqa: E402 (a script beside this one)

CHOSEN_ON = ("0000", "0003", "0005", "0009", "0017")
"""The sequences the weight and the lookahead were chosen on; the others checked them."""
PAIRS = ((1.0, 0.0), (0.5, 0.0), (0.5, 0.2), (0.5, 0.3), (0.5, 0.5), (1.0, 0.3))
CLASSES = ("car", "pedestrian")
MODEL = "object-wise"


def half_scores(report: dict, cls: str, sequences: list[str]) -> tuple[float, float]:
    """(HOTA weighted by each sequence's scored true boxes, ECE of the pooled reliability
    bins) of `cls` over `sequences` of a benchmark report."""
    entries = [report["sequences"][name]["classes"][cls] for name in sequences]
    truth = sum(entry["truth"] for entry in entries)
    hota = sum(entry["trackers"][MODEL]["hota"] * entry["truth"] for entry in entries)
    tables = [Reliability.from_dict(entry["calibration"][MODEL]) for entry in entries]
    return hota / max(truth, 1.0), pooled(tables).ece


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=None, help="KITTI tracking folder")
    parser.add_argument("--pairs", nargs="+", default=None, metavar="W,S",
                        help="evidence weight and lookahead seconds (default: the docs' table)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    try:
        pairs = PAIRS if args.pairs is None else tuple(
            tuple(float(v) for v in text.split(",", 1)) for text in args.pairs)
    except ValueError:
        parser.error("each pair is WEIGHT,SECONDS, e.g. 0.5,0.2")
    if any(len(pair) != 2 for pair in pairs):
        parser.error("each pair is WEIGHT,SECONDS, e.g. 0.5,0.2")
    root = data_folder(args.data)
    print(f"{root}: chosen on {', '.join(CHOSEN_ON)}; checked on the others. Per class: "
          f"chosen-on / checked-on HOTA (weighted by true boxes) / ECE (pooled), then all ten "
          f"combined")
    print(f"{'weight':>6} {'ahead':>6}  " + "  ".join(
        f"{cls + ' chosen':>17} {cls + ' checked':>18} {cls + ' all':>14}" for cls in CLASSES))
    for weight, lookahead in pairs:
        report = benchmark_kitti.benchmark(root, [MODEL], "pointrcnn", CLASSES, args.quiet,
                                           ground={"evidence_weight": weight,
                                                   "lookahead": lookahead})
        names = list(report["sequences"])
        cells = []
        for cls in CLASSES:
            chosen = half_scores(report, cls, [s for s in names if s in CHOSEN_ON])
            checked = half_scores(report, cls, [s for s in names if s not in CHOSEN_ON])
            combined = report["combined"]["classes"][cls]["trackers"][MODEL]
            cells.append(f"{chosen[0]:9.3f} / {chosen[1]:.3f} {checked[0]:10.3f} / "
                         f"{checked[1]:.3f} {combined['hota']:6.3f} / {combined['ece']:.3f}")
        print(f"{weight:6g} {lookahead:6g}  " + "  ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
