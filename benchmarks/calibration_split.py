"""Where occtrack's confidence is off: said against right, by the kind of reported box.

    python benchmarks/calibration_split.py [--data DIR] [--confidence-centre detection]

Each occlusion model, default settings, on MOT17-04, -05 and -11 (`--data`, else
$OCCTRACK_DATA or ../shared/data/mot17). The reported boxes are scored as `occtrack eval
--calibration` scores them (one to one at IoU >= 0.5 after the mot17 protocol's distractor
step) and split: boxes that took a detection, coasting boxes, and of those the ones within 3 %
of the image border; per group the boxes, their mean confidence and the share right; and of the
wrong detected boxes, how many lie on a true box at IoU 0.3 to 0.5 and how visible that person
is. docs/confidence.md quotes these.
"""

from __future__ import annotations

import argparse

import numpy as np

from occtrack.experiments.benchmark import PROTOCOL, load_sequence
from occtrack.io.data import find_sequence
from occtrack.io.mot import MotTable
from occtrack.metrics.protocols import scored_frames
from occtrack.metrics.reliability import reliability_table, right_boxes
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig

SEQUENCES = "MOT17-04-FRCNN,MOT17-05-FRCNN,MOT17-11-FRCNN"
NEAR = 0.03  # a box within this share of the image's width or height of its border


def split(sequence, occlusion: str, centre: str) -> list[tuple[str, int, float, float]]:
    config = TrackerConfig(occlusion=occlusion, image_size=(sequence.width, sequence.height),
                           fps=sequence.fps, confidence_centre=centre)
    out = Tracker(config).run(sequence.det, sequence.length)
    n = len(out.frame)
    result = MotTable(out.frame, out.id, out.box, out.confidence, np.full(n, -1),
                      np.full(n, -1.0), "<occtrack>")
    rows, right = right_boxes(scored_frames(sequence.gt, result, PROTOCOL, sequence.length))
    said, box, coasting = out.confidence[rows], out.box[rows], out.coasting[rows]
    W, H = sequence.width, sequence.height
    near = ((box[:, 0] < NEAR * W) | (box[:, 0] + box[:, 2] > (1 - NEAR) * W)
            | (box[:, 1] < NEAR * H) | (box[:, 1] + box[:, 3] > (1 - NEAR) * H))
    groups = [(f"all (ECE {reliability_table(said, right).ece:.3f})",
               np.ones(len(rows), bool)),
              ("detected", ~coasting), ("coasting", coasting),
              ("coasting near the border", coasting & near)]
    table = [(name, int(m.sum()), float(said[m].mean()) if m.any() else float("nan"),
              float(right[m].mean()) if m.any() else float("nan")) for name, m in groups]
    return table, _wrong_detected(sequence, out, rows[~coasting & ~right])


def _wrong_detected(sequence, out, wrong: np.ndarray) -> str:
    """Of the detected boxes that are wrong: how many lie at IoU 0.3 to 0.5 on a true box
    (the box is off, not false) and the median visibility of that true box."""
    gt = sequence.gt
    slices = gt.frame_slices(sequence.length)
    best, seen = [], []
    for row in wrong:
        rows = np.arange(len(gt))[slices[out.frame[row] - 1]]
        if not len(rows):
            best.append(0.0)
            seen.append(np.nan)
            continue
        b, g = out.box[row], gt.box[rows]
        lo = np.maximum(b[:2], g[:, :2])
        hi = np.minimum(b[:2] + b[2:], g[:, :2] + g[:, 2:])
        inter = np.prod(np.clip(hi - lo, 0, None), axis=1)
        iou = inter / (np.prod(b[2:]) + np.prod(g[:, 2:], axis=1) - inter)
        best.append(float(iou.max()))
        seen.append(float(gt.visibility[rows[np.argmax(iou)]]))
    best, seen = np.array(best), np.array(seen)
    off = (best >= 0.3) & (best < 0.5)
    visibility = float(np.nanmedian(seen[off])) if off.any() else float("nan")
    return (f"wrong detected boxes: {len(best)}, of them {int(off.sum())} at IoU 0.3-0.5 on a "
            f"true box (its visibility, median {visibility:.2f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=None, help="folder of the MOT17 sequences")
    parser.add_argument("--sequences", default=SEQUENCES)
    parser.add_argument("--confidence-centre", default="posterior",
                        choices=("detection", "posterior"))
    args = parser.parse_args()
    for name in args.sequences.split(","):
        sequence = load_sequence(find_sequence(args.data, name))
        for occlusion in OCCLUSION_NAMES:
            print(f"{name} {occlusion}")
            table, wrong = split(sequence, occlusion, args.confidence_centre)
            for group, count, said, right in table:
                print(f"  {group:<28} {count:6d} boxes  say {said:.3f}  right {right:.3f}")
            print(f"  {wrong}")


if __name__ == "__main__":
    main()
