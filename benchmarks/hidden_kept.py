"""How many objects hidden from the sensor each occlusion model keeps through, against `none`
(issue 40): on KITTI's sequences, with PointRCNN's 3D detections.

    python benchmarks/hidden_kept.py [--data DIR] [--detections pointrcnn] [--json FILE] [--quiet]

DIR is a KITTI tracking folder (label_02/, det_02/NAME/ with 3D detections, calib/, poses/,
seqinfo/): --data, else the kitti/ beside the folder $OCCTRACK_DATA names (the data folder's
kitti/, where the tests find it), else ../shared/data/kitti beside this checkout.

Every sequence is tracked under each occlusion model exactly as `occtrack benchmark DIR
--detections pointrcnn` tracks it (`benchmark_kitti.track`: the Car and Pedestrian 3D boxes on
the ground plane in one run, default settings, the sequence's poses and calibration).

A missed stretch of a true object (label_02, Car or Pedestrian, one track id) is a maximal run
of consecutive frames in which the object is labelled but no detection of its class overlaps
its box at IoU >= 0.5, with the frame just before and the frame just after labelled and
detected (IoU >= 0.5): the object was seen, went unseen, was seen again. A stretch at the
sequence's start or end, or beside a frame where the object is not labelled, has no such
flank and is not counted. The stretch is *hidden* (hidden from the sensor) when KITTI's label
calls the object occluded (the `occluded` column >= 1) in at least one of its frames.

Against the tracker's result (its 2D boxes: the detection's own while detected, else the 3D box
projected): *held before* when in the frame before the result has a box of the object's class
at IoU >= 0.5 with the true box (the best-IoU one gives the id I); *kept through* when
moreover every frame of the stretch has a box with id I at IoU >= 0.5 with the true box, and
so does the frame after; *same id after* when id I is back at IoU >= 0.5 in the frame after,
whatever happened during the stretch. Shares are of all the stretches of the row.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.experiments import benchmark_kitti
from occtrack.experiments.benchmark import MODELS
from occtrack.io.kitti import KittiTable
from occtrack.metrics.trackeval_kitti import CLASS_TYPE
from occtrack.spatial import iou
from occtrack.tracker.boxes import to_ltwh

ROOT = Path(__file__).resolve().parents[1]
CLASSES = ("car", "pedestrian")
MODEL_ORDER = ("none", "object-wise", "measurement-wise")
IOU = 0.5
"""A box overlaps a true box at IoU >= this (detections and the tracker's boxes alike)."""
assert set(MODEL_ORDER) == set(MODELS)


def data_folder(given: Path | None) -> Path:
    """The KITTI folder: --data, else $OCCTRACK_DATA's sibling kitti/, else the checkout's
    ../shared/data/kitti."""
    tried = [given] if given else []
    if os.environ.get("OCCTRACK_DATA"):
        tried.append(Path(os.environ["OCCTRACK_DATA"]).parent / "kitti")
    tried.append(ROOT.parent / "shared" / "data" / "kitti")
    for folder in tried:
        if benchmark_kitti.is_layout(folder):
            return folder.resolve()
    sys.exit("no KITTI tracking folder (label_02/ and det_02/) found in "
             + ", ".join(str(f) for f in tried) + ": pass --data DIR or set OCCTRACK_DATA")


def ltwh(box: np.ndarray) -> np.ndarray:
    """x1 y1 x2 y2 boxes (N, 4) as left, top, width, height (what `spatial.iou` takes)."""
    return to_ltwh(np.asarray(box, float).reshape(-1, 4), "xyxy")


def overlaps(truth: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """IoU of one true x1 y1 x2 y2 box with each of `boxes` (N, 4)."""
    if len(boxes) == 0:
        return np.zeros(0)
    return iou(ltwh(truth), ltwh(boxes))[0]


def rows_by_frame(table: KittiTable) -> dict[int, np.ndarray]:
    """The table's row indices, frame by frame."""
    order = np.argsort(table.frame, kind="stable")
    frames, starts = np.unique(table.frame[order], return_index=True)
    return {int(f): rows for f, rows in zip(frames, np.split(order, starts[1:]), strict=True)}


def detected(gt: KittiTable, det: KittiTable) -> np.ndarray:
    """Per row of `gt`, whether a detection of its type in its frame overlaps it at
    IoU >= 0.5."""
    out = np.zeros(len(gt), bool)
    dets = rows_by_frame(det)
    for f, rows in rows_by_frame(gt).items():
        here = dets.get(f, np.zeros(0, np.int64))
        for kind in np.unique(gt.type[rows]):
            mine = rows[gt.type[rows] == kind]
            theirs = here[det.type[here] == kind]
            if len(theirs):
                out[mine] = (iou(ltwh(gt.box[mine]), ltwh(det.box[theirs])) >= IOU).any(axis=1)
    return out


def missed_stretches(frames, seen, occluded) -> list[tuple[int, int, bool]]:
    """One object's missed stretches: (first frame, last frame, hidden) for each maximal run of
    consecutive labelled frames where it is not `seen`, flanked by labelled frames where it is
    (the frame just before the run and the one just after). `frames` the object's labelled
    frames, `seen` and `occluded` (KITTI's column) per frame; hidden: occluded >= 1 somewhere
    in the run."""
    frames = np.asarray(frames, np.int64)
    order = np.argsort(frames, kind="stable")
    frames = frames[order]
    seen = np.asarray(seen, bool)[order]
    occluded = np.asarray(occluded, float)[order]
    out = []
    i, n = 0, len(frames)
    while i < n:
        if seen[i]:
            i += 1
            continue
        j = i  # the run: i..j, consecutive frames, none seen
        while j + 1 < n and not seen[j + 1] and frames[j + 1] == frames[j] + 1:
            j += 1
        before = i > 0 and seen[i - 1] and frames[i - 1] == frames[i] - 1
        after = j + 1 < n and seen[j + 1] and frames[j + 1] == frames[j] + 1
        if before and after:
            out.append((int(frames[i]), int(frames[j]), bool((occluded[i:j + 1] >= 1).any())))
        i = j + 1
    return out


@dataclass(frozen=True)
class Outcome:
    """What the tracker's result did with one missed stretch."""

    held_before: bool  # a box of the class on the object in the frame before (id I)
    kept: bool  # id I on the object in every frame of the stretch and in the frame after
    same_after: bool  # id I on the object in the frame after


def outcome(truth: dict[int, np.ndarray], kind: int, first: int, last: int,
            result: KittiTable, by_frame: dict[int, np.ndarray] | None = None) -> Outcome:
    """The result against one stretch (frames first..last) of a true object of type `kind`
    whose x1 y1 x2 y2 box in frame f is truth[f] (the frames first - 1 .. last + 1)."""
    by_frame = rows_by_frame(result) if by_frame is None else by_frame
    empty = np.zeros(0, np.int64)

    def on(f: int, rows: np.ndarray) -> np.ndarray:
        return rows[overlaps(truth[f], result.box[rows]) >= IOU] if len(rows) else rows

    before = by_frame.get(first - 1, empty)
    before = before[result.type[before] == kind]
    scores = overlaps(truth[first - 1], result.box[before])
    if not len(before) or scores.max() < IOU:
        return Outcome(False, False, False)
    ident = result.id[before[int(np.argmax(scores))]]

    def holds(f: int) -> bool:
        return bool(np.any(result.id[on(f, by_frame.get(f, empty))] == ident))

    after = holds(last + 1)
    kept = after and all(holds(f) for f in range(first, last + 1))
    return Outcome(True, kept, after)


def count_sequence(gt: KittiTable, det: KittiTable, result: KittiTable,
                   classes=CLASSES) -> dict[str, dict[str, dict[str, int]]]:
    """Per class, per set ("hidden", "missed": every missed stretch), the counts: stretches,
    held_before, kept, same_after."""
    seen = detected(gt, det)
    by_frame = rows_by_frame(result)
    out = {}
    for cls in classes:
        kind = CLASS_TYPE[cls]
        counts = {key: dict.fromkeys(("stretches", "held_before", "kept", "same_after"), 0)
                  for key in ("hidden", "missed")}
        objects = (gt.type == kind) & (gt.id >= 0)
        for ident in np.unique(gt.id[objects]):
            rows = np.flatnonzero(objects & (gt.id == ident))
            truth = {int(f): gt.box[r] for f, r in zip(gt.frame[rows], rows, strict=True)}
            for first, last, hidden in missed_stretches(gt.frame[rows], seen[rows],
                                                        gt.occluded[rows]):
                got = outcome(truth, kind, first, last, result, by_frame)
                for key in ("hidden", "missed") if hidden else ("missed",):
                    part = counts[key]
                    part["stretches"] += 1
                    part["held_before"] += got.held_before
                    part["kept"] += got.kept
                    part["same_after"] += got.same_after
        out[cls] = counts
    return out


def add(total: dict, part: dict) -> None:
    """Sum `part`'s counts (count_sequence's layout) into `total`."""
    for cls, sets in part.items():
        for key, counts in sets.items():
            into = total.setdefault(cls, {}).setdefault(key, dict.fromkeys(counts, 0))
            for name, value in counts.items():
                into[name] += value


def share(n: int, of: int) -> str:
    return f"{n / of:6.1%}" if of else f"{'-':>6}"


def format_table(totals: dict) -> str:
    """Per model and class: the hidden stretches, then all the missed ones; counts and shares
    of the row's stretches."""
    lines = [f"  {'model':<18}{'class':<12}{'stretches':<11}{'count':>6}{'held before':>19}"
             f"{'kept through':>20}{'same id after':>21}"]
    for model, per_class in totals.items():
        for cls, sets in per_class.items():
            for key, label in (("hidden", "hidden"), ("missed", "all missed")):
                c = sets[key]
                n = c["stretches"]
                lines.append(
                    f"  {model:<18}{cls:<12}{label:<11}{n:>6}"
                    f"{c['held_before']:>11} {share(c['held_before'], n)}"
                    f"{c['kept']:>12} {share(c['kept'], n)}"
                    f"{c['same_after']:>13} {share(c['same_after'], n)}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=None,
                        help="the KITTI tracking folder (default: $OCCTRACK_DATA/../kitti, "
                             "else ../shared/data/kitti)")
    parser.add_argument("--detections", default="pointrcnn",
                        help="the 3D detector folder det_02/NAME (default pointrcnn)")
    parser.add_argument("--json", type=Path, default=None, help="also write the counts here")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    args = parser.parse_args()
    root = data_folder(args.data)
    detections = benchmark_kitti.pick_detections(root, args.detections)
    names = benchmark_kitti.sequence_names(root, detections)
    sequences = [benchmark_kitti.load_sequence(root, detections, name) for name in names]
    three_d, note = benchmark_kitti.has_3d(sequences)
    if not three_d:
        sys.exit(f"det_02/{detections} holds no 3D detections (x y z = -1000)"
                 + (f": {note}" if note else ""))
    sequences = [benchmark_kitti.with_geometry(root, seq) for seq in sequences]
    still = [seq.name for seq in sequences if seq.poses is None]

    totals: dict = {model: {} for model in MODEL_ORDER}
    per_sequence: dict = {}
    for seq in sequences:
        assert seq.table is not None
        for model in MODEL_ORDER:
            result = benchmark_kitti.track(model, seq, CLASSES)
            counts = count_sequence(seq.gt, seq.table, result)
            per_sequence.setdefault(seq.name, {})[model] = counts
            add(totals[model], counts)
            if not args.quiet:
                c = counts
                print(f"{seq.name} {model}: hidden stretches car "
                      f"{c['car']['hidden']['kept']}/{c['car']['hidden']['stretches']} kept, "
                      f"pedestrian {c['pedestrian']['hidden']['kept']}/"
                      f"{c['pedestrian']['hidden']['stretches']} kept", flush=True)

    print(f"{root} det_02/{detections}: {len(sequences)} sequences, each occlusion model as "
          f"`occtrack benchmark DIR --detections {detections}` tracks them (car and pedestrian "
          f"in one run, ground plane, default settings)"
          + (f"; no poses for {', '.join(still)} (a still camera)" if still else ""))
    print("A stretch: frames where the detector missed a true object (no detection of its "
          f"class at IoU >= {IOU:g}), seen the frame before and the frame after; hidden: "
          "KITTI labels it occluded (>= 1) in a frame of it. Shares of the row's stretches.")
    print(format_table(totals))
    if args.json:
        args.json.write_text(json.dumps({
            "folder": str(root), "detections": detections, "iou": IOU,
            "sequences": [seq.name for seq in sequences], "totals": totals,
            "per_sequence": per_sequence}, indent=1) + "\n")
    parts = []
    for model in MODEL_ORDER:
        hidden = [totals[model][cls]["hidden"] for cls in CLASSES]
        kept, n = sum(c["kept"] for c in hidden), sum(c["stretches"] for c in hidden)
        parts.append(f"{model} {kept}/{n}")
    print("Hidden stretches kept through (car + pedestrian): " + ", ".join(parts)
          + (f"; counts written to {args.json}" if args.json else ""))


if __name__ == "__main__":
    main()
