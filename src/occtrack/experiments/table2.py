"""Paper Table II: pedestrian boxes on MOT17-04 with none / object-wise / measurement-wise
occlusion, plus norfair as the baseline a user would pick instead.

The public Faster-RCNN detections are not available here, so the detections are simulated from
the ground truth (`occtrack.scenarios.detector`, seeded). Like the authors' prototype, each
tracker updates on every other frame (15 Hz) and reports at 30 Hz. Every result is scored
under both protocols: `paper` (the authors' script, to be read beside the paper's values) and
`mot17` (the official protocol, the one to quote).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from occtrack.cli.arguments import positive_int, seed_int
from occtrack.errors import OcctrackError
from occtrack.io.data import find_sequence
from occtrack.io.mot import MotTable, read_mot, read_seqinfo
from occtrack.metrics.evaluate import evaluate_frames, frame_gospa
from occtrack.metrics.protocols import scored_frames
from occtrack.scenarios.detector import detection_recall_precision, simulate_detections
from occtrack.tracker import Tracker, TrackerConfig

NAME = "table2"
HELP = "MOT17-04 pedestrians (paper Table II): three occlusion models and norfair"
DESCRIPTION = __doc__ + """
Data: --data DIR, else $OCCTRACK_DATA, else ../shared/data/mot17; the folder holds
MOT17-04-FRCNN/gt/gt.txt and seqinfo.ini. norfair runs in an environment of its own, installed
on first use (see occtrack.baselines.norfair_baseline); --no-norfair leaves it out."""

MODELS = ("none", "measurement-wise", "object-wise")
PROTOCOLS = ("paper", "mot17")
FRAME_STEP = 2

PAPER = {
    "none": {"mota": .351, "motp": .408, "idf1": .755, "hota": None, "mostly_tracked": 86,
             "mostly_lost": 0, "fp": 18721, "fn": 12, "id_switches": 8, "gospa": 14002,
             "cardinality_error": -.39},
    "measurement-wise": {"mota": .426, "motp": .418, "idf1": .777, "hota": None,
                         "mostly_tracked": 78, "mostly_lost": 0, "fp": 17339, "fn": 0,
                         "id_switches": 13, "gospa": 13947, "cardinality_error": -.36},
    "object-wise": {"mota": .427, "motp": .400, "idf1": .777, "hota": None,
                    "mostly_tracked": 76, "mostly_lost": 0, "fp": 17317, "fn": 0,
                    "id_switches": 9, "gospa": 13826, "cardinality_error": -.36},
}
"""The paper's Table II (FRCNN detections, `paper` protocol), shown beside ours only."""

COLUMNS = (("mota", "MOTA", ".3f"), ("motp", "MOTP", ".3f"), ("idf1", "IDF1", ".3f"),
           ("hota", "HOTA", ".3f"), ("mostly_tracked", "MT", "d"), ("mostly_lost", "ML", "d"),
           ("fp", "FP", "d"), ("fn", "FN", "d"), ("id_switches", "IDSW", "d"),
           ("gospa", "GOSPA", ".0f"), ("cardinality_error", "card.", "+.2f"))


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", metavar="DIR", help="folder holding MOT17-04-FRCNN/")
    parser.add_argument("--seed", type=seed_int, default=0, help="detector simulator seed (0)")
    parser.add_argument("--json", action="store_true",
                        help='print {"paper": {"none": {...}, ..., "norfair": {...}}, '
                             '"mot17": {...}} with the keys of `occtrack eval --json`')
    parser.add_argument("--no-norfair", action="store_true", help="leave the baseline out")
    parser.add_argument("--frame-figure", metavar="PNG", type=Path,
                        help="draw one frame: ground truth, detections, measurement-wise tracks")
    parser.add_argument("--frame", type=positive_int, default=None,
                        help="frame to draw (default: the one with most ground-truth people)")
    parser.add_argument("--gospa-figure", metavar="PNG", type=Path,
                        help="plot per-frame GOSPA of the three models (paper protocol)")
    parser.add_argument("--force", action="store_true", help="overwrite existing figures")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")


def result_table(result) -> MotTable:
    n = len(result.frame)
    return MotTable(result.frame, result.id, result.box, result.existence,
                    np.full(n, -1), np.full(n, -1.0), "<tracker>")


def run(args: argparse.Namespace) -> int:
    seq = find_sequence(args.data)
    info = read_seqinfo(seq)
    gt = read_mot(seq / "gt" / "gt.txt", "gt")
    n, size = info["length"], (info["width"], info["height"])
    det = simulate_detections(gt, args.seed, image_size=size, num_frames=n)
    recall, precision = detection_recall_precision(gt, det)

    results: dict[str, MotTable] = {}
    seconds: dict[str, float] = {}
    for model in MODELS:
        config = TrackerConfig(occlusion=model, image_size=size, fps=info["fps"],
                               frame_step=FRAME_STEP)
        start = time.perf_counter()
        out = Tracker(config).run(det, n, quiet=args.quiet, desc=model)
        seconds[model] = time.perf_counter() - start
        results[model] = result_table(out)
    if not args.no_norfair:
        from occtrack.baselines.norfair_baseline import NorfairConfig, track_norfair

        start = time.perf_counter()
        results["norfair"] = track_norfair(det, FRAME_STEP, NorfairConfig(hit_counter_max=15),
                                           num_frames=n, quiet=args.quiet)
        seconds["norfair"] = time.perf_counter() - start

    scores: dict[str, dict[str, dict]] = {p: {} for p in PROTOCOLS}
    per_frame: dict[str, np.ndarray] = {}
    for protocol in PROTOCOLS:
        for name, table in results.items():
            frames = scored_frames(gt, table, protocol, n)
            scores[protocol][name] = evaluate_frames(frames, gt, table)
            if protocol == "paper":
                per_frame[name] = frame_gospa(frames)

    if args.json:
        print(json.dumps(scores, indent=2))
    else:
        print(format_tables(scores, recall, precision, args.seed))
    if args.gospa_figure is not None:
        from occtrack.viz.runs import plot_gospa_per_frame

        plot_gospa_per_frame(args.gospa_figure, {m: per_frame[m] for m in MODELS},
                             "MOT17-04, simulated detections: GOSPA per frame (paper protocol)",
                             overwrite=args.force)
    if args.frame_figure is not None:
        draw_crowded_frame(args, gt, det, results, size)
    tracked = sum(seconds[m] for m in MODELS)
    print(f"tracked {n} frames x {len(MODELS)} models in {tracked:.1f} s "
          f"({len(MODELS) * n / tracked:.0f} frames per second)"
          + (f"; norfair {seconds['norfair']:.1f} s" if "norfair" in seconds else ""),
          file=sys.stderr)
    return 0


def draw_crowded_frame(args, gt: MotTable, det: MotTable, results: dict[str, MotTable],
                       size) -> None:
    """One crowded frame, a panel per occlusion model."""
    from occtrack.viz.frame import check_new, draw_panels

    path = check_new(args.frame_figure, args.force)
    people = gt.select((gt.score == 1) & (gt.cls == 1))
    frame = args.frame or int(np.bincount(people.frame).argmax())
    if not 1 <= frame <= people.num_frames:
        raise OcctrackError(f"--frame {frame} is outside 1..{people.num_frames}")
    truth = people.box[people.frame == frame]
    centre = np.median(truth[:, :2] + truth[:, 2:] / 2, axis=0)
    w, h = size
    x0 = float(np.clip(centre[0] - w / 4, 0, w / 2))
    y0 = float(np.clip(centre[1] - h / 4, 0, h / 2))
    panels = []
    for model in MODELS:
        at = results[model].frame == frame
        panels.append(dict(truth=truth,
                           detections=det.box[det.frame == frame],
                           track_boxes=results[model].box[at], track_ids=results[model].id[at],
                           title=f"occlusion: {model}"))
    draw_panels(path, size, panels, window=(x0, y0, x0 + w / 2, y0 + h / 2),
                caption=f"MOT17-04 frame {frame} (the quarter of the image around its "
                        f"people): ground-truth pedestrians grey, simulated "
                        f"detections dashed magenta, tracks blue with their labels")


def _cell(value, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def format_tables(scores: dict, recall: float, precision: float, seed: int) -> str:
    lines = [f"MOT17-04, simulated Faster-RCNN-like detections (seed {seed}: recall "
             f"{recall:.3f}, precision {precision:.3f} against the mot17 pedestrians); "
             f"tracked at 15 Hz, reported at 30 Hz."]
    header = f"  {'tracker':<22}" + "".join(f"{title:>8}" for _, title, _ in COLUMNS)
    for protocol in PROTOCOLS:
        lines += ["", {"paper": "Protocol `paper` (the authors' scoring script; the paper's "
                                "Table II in brackets, on the real FRCNN detections):",
                       "mot17": "Protocol `mot17` (official MOTChallenge scoring, "
                                "TrackEval):"}[protocol], header]
        for name, values in scores[protocol].items():
            lines.append(f"  {name:<22}" + "".join(
                f"{_cell(values[k], fmt):>8}" for k, _, fmt in COLUMNS))
            if protocol == "paper" and name in PAPER:
                lines.append(f"  {'  [paper]':<22}" + "".join(
                    f"{_cell(PAPER[name][k], fmt):>8}" for k, _, fmt in COLUMNS))
    lines += ["", "MOTP is a distance (1 - IoU, lower is better) under `paper` and TrackEval's "
                  "similarity (IoU, higher is better) under `mot17`. Under `paper`, FP and FN "
                  "are the script's swapped ID-level counts (see `occtrack eval --help`)."]
    return "\n".join(lines)
