"""Paper Table II: pedestrian boxes on MOT17-04 with none / object-wise / measurement-wise
occlusion, beside the trackers a user would pick instead: norfair, ByteTrack and OC-SORT.

The detections are the public Faster-RCNN ones the paper used (MOT17-04-FRCNN/det/det.txt), so
our rows read beside the paper's; `--detections simulated` swaps in the seeded stand-in made
from the ground truth (`occtrack.scenarios.detector`). Like the authors' prototype, occtrack
updates on every other frame (15 Hz) and reports at 30 Hz (frame_step 2, set here whatever the
tracker's default); norfair likewise, interpolated between. ByteTrack and OC-SORT (Roboflow's
`trackers`, `occtrack.peers`) run with their library defaults on every frame. Every result is
scored under both protocols: `paper` (the authors' script, to be read beside the paper's
values) and `mot17` (the official protocol, the one to quote).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from occtrack.config.arguments import positive_int, seed_int
from occtrack.errors import OcctrackError
from occtrack.io.data import find_sequence
from occtrack.io.mot import MotTable, read_mot, read_seqinfo
from occtrack.metrics.evaluate import evaluate_frames, frame_gospa
from occtrack.metrics.protocols import scored_frames
from occtrack.scenarios.detector import detection_recall_precision, simulate_detections
from occtrack.tracker import Tracker, TrackerConfig

NAME = "table2"
HELP = "MOT17-04 pedestrians (paper Table II): three occlusion models and the peers"
DESCRIPTION = __doc__ + """
Data: --data DIR, else $OCCTRACK_DATA, else ../shared/data/mot17; the folder holds
MOT17-04-FRCNN/ with det/det.txt, gt/gt.txt and seqinfo.ini. norfair runs in an environment of
its own, installed on first use (see occtrack.baselines.norfair_baseline); --no-norfair leaves
it out. ByteTrack and OC-SORT need the peers extra (pip install "occtrack[peers]"): without it
they are left out with a note; --no-peers leaves them out."""

MODELS = ("none", "measurement-wise", "object-wise")
PEERS = ("bytetrack", "ocsort")
DETECTIONS = ("real", "simulated")
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
    parser.add_argument("--detections", choices=DETECTIONS, default="real",
                        help="real: the public Faster-RCNN detections (default); simulated: "
                             "the seeded stand-in made from the ground truth")
    parser.add_argument("--seed", type=seed_int, default=None,
                        help="detector simulator seed, with --detections simulated (default 0)")
    parser.add_argument("--json", action="store_true",
                        help='print {"paper": {"none": {...}, ..., "norfair": {...}, '
                             '"bytetrack": {...}, "ocsort": {...}}, "mot17": {...}} with the '
                             'keys of `occtrack eval --json`')
    parser.add_argument("--no-norfair", action="store_true", help="leave norfair out")
    parser.add_argument("--no-peers", action="store_true", help="leave ByteTrack and OC-SORT out")
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
    return MotTable(result.frame, result.id, result.box, result.confidence,
                    np.full(n, -1), np.full(n, -1.0), "<tracker>")


def run(args: argparse.Namespace) -> int:
    from occtrack import peers

    if args.seed is not None and args.detections != "simulated":
        raise OcctrackError("--seed seeds the detector simulator: use it with "
                            "--detections simulated")
    seq = find_sequence(args.data)
    info = read_seqinfo(seq)
    gt = read_mot(seq / "gt" / "gt.txt", "gt")
    n, size = info["length"], (info["width"], info["height"])
    if args.detections == "real":
        det = read_mot(seq / "det" / "det.txt", "det")
        if det.num_frames > n:
            raise OcctrackError(f"detections reach frame {det.num_frames} but seqinfo.ini says "
                                f"seqLength={n}", det.path)
        source = "public Faster-RCNN detections"
    else:
        seed = 0 if args.seed is None else args.seed
        det = simulate_detections(gt, seed, image_size=size, num_frames=n)
        source = f"simulated Faster-RCNN-like detections (seed {seed})"
    recall, precision = detection_recall_precision(gt, det)
    notes = []
    run_peers = not args.no_peers and peers.available()
    if not args.no_peers and not run_peers:
        notes.append("ByteTrack and OC-SORT left out: " + peers.INSTALL_HINT)

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
    if run_peers:
        for name in PEERS:
            start = time.perf_counter()
            results[name] = peers.track_peer(name, det, n, info["fps"])
            seconds[name] = time.perf_counter() - start

    scores: dict[str, dict[str, dict]] = {p: {} for p in PROTOCOLS}
    per_frame: dict[str, np.ndarray] = {}
    for protocol in PROTOCOLS:
        for name, table in results.items():
            frames = scored_frames(gt, table, protocol, n)
            scores[protocol][name] = evaluate_frames(frames, gt, table)
            if protocol == "paper":
                per_frame[name] = frame_gospa(frames)

    for note in notes:
        print(f"occtrack reproduce table2: note: {note}", file=sys.stderr)
    if args.json:
        print(json.dumps(scores, indent=2))
    else:
        print(format_tables(scores, recall, precision, source))
    if args.gospa_figure is not None:
        from occtrack.viz.runs import plot_gospa_per_frame

        plot_gospa_per_frame(args.gospa_figure, {m: per_frame[m] for m in MODELS},
                             f"MOT17-04, {source}: GOSPA per frame (paper protocol)",
                             overwrite=args.force)
    if args.frame_figure is not None:
        draw_crowded_frame(args, gt, det, results, size, source)
    tracked = sum(seconds[m] for m in MODELS)
    others = "".join(f"; {name} {seconds[name]:.1f} s" for name in seconds if name not in MODELS)
    print(f"tracked {n} frames x {len(MODELS)} models in {tracked:.1f} s "
          f"({len(MODELS) * n / tracked:.0f} frames per second){others}", file=sys.stderr)
    return 0


def draw_crowded_frame(args, gt: MotTable, det: MotTable, results: dict[str, MotTable],
                       size, source: str) -> None:
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
                        f"people): ground-truth pedestrians grey, {source.split(' (')[0]} "
                        f"dashed magenta, tracks blue with their labels")


def _cell(value, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def format_tables(scores: dict, recall: float, precision: float, source: str) -> str:
    lines = [f"MOT17-04, {source}: recall {recall:.3f}, precision {precision:.3f} against the "
             f"mot17 pedestrians. occtrack and norfair tracked at 15 Hz and reported at 30 Hz, "
             f"as in the paper; ByteTrack and OC-SORT (library defaults) on every frame."]
    header = f"  {'tracker':<22}" + "".join(f"{title:>8}" for _, title, _ in COLUMNS)
    for protocol in PROTOCOLS:
        lines += ["", {"paper": "Protocol `paper` (the authors' scoring script; the paper's "
                                "Table II in brackets, on the public FRCNN detections):",
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
