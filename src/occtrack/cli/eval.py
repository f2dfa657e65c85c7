"""`occtrack eval GT_FILE RESULT_FILE`: score a tracker's result file against ground truth."""

from __future__ import annotations

import argparse
import json
import sys
import time

from occtrack.cli.arguments import DAY_AT_30_FPS, whole_number
from occtrack.errors import OcctrackError
from occtrack.metrics import protocol_text as protocols
from occtrack.metrics.protocol_text import KEYS

NAME = "eval"
KITTI_PROTOCOLS = ("kitti", "kitti-bev")
HELP = "score a result file against ground truth (CLEAR MOT, IDF1, HOTA, GOSPA; MOT17 or KITTI)"
DESCRIPTION = f"""\
Score a tracker's MOTChallenge result file against a ground-truth file and print MOTA, MOTP,
IDF1, HOTA, mostly tracked / lost, FP, FN, ID switches, GOSPA and the cardinality error.

Files are read as TrackEval reads them (comma or space separated, CRLF line ends, frames and
ids written 3 or 3.0, extra columns ignored); a malformed row, such as a frame of 2.5, stops
with its file and line.
The sequence length is the ground truth's seqinfo.ini (SEQ/gt/gt.txt layout), --frames, or the
last frame in either file; result ids must be unique within a frame. A ground truth without one
box the protocol scores (no rows, or none a pedestrian marked to be scored) is an error, exit
1: every metric is then undefined, and a 0 would read as a tracker that failed.

Protocols:

{protocols.DESCRIPTION["paper"]}

{protocols.DESCRIPTION["mot17"]}

{protocols.GOSPA_DESCRIPTION}

kitti: KITTI tracking's official evaluation, run by TrackEval (Kitti2DBox: its
  preprocessing, CLEAR, Identity, HOTA), on KITTI files (label_02/NNNN.txt and a result in
  KITTI's format, 0-based frames, the score as the 18th column). Classes car and pedestrian
  are scored apart (--classes car or pedestrian picks one): result boxes matched at IoU >= 0.5
  to a van (for car) or a sitting person (for pedestrian), or to a true box that is truncated
  or largely hidden, are removed, and so are unmatched boxes 25 px tall or less or more than
  half inside a DontCare region. GT_FILE and RESULT_FILE may be two folders: the ground truth
  a KITTI folder (DIR/label_02/, or label_02/ itself; the sequences its
  evaluate_tracking.seqmap names, else every NNNN.txt), the result a folder of NNNN.txt.
  Printed per class: HOTA, DetA, AssA, LocA, MOTA, IDF1, IDSW, FP, FN, MT, ML, MOTP per
  sequence and TrackEval's COMBINED_SEQ over them. A sequence's length is --frames, else
  DIR/seqinfo/NNNN.ini or DIR/evaluate_tracking.seqmap, else its last frame + 1. --json prints
  {{"protocol": "kitti", "classes": {{CLASS: {{"sequences": {{NAME: SCORES}}, "combined":
  SCORES[, "calibration": TABLE]}}}}, "notes": [...]}}. The protocol is picked by itself when
  GT_FILE is a KITTI file or folder.

kitti-bev: KITTI 3D tracking scored on the ground plane (TrackEval has no such protocol):
  TrackEval's HOTA, CLEAR and Identity on the (x, z) centres of the 3D boxes (columns 14 and
  16, metres in the rectified camera frame) with the similarity max(0, 1 - d / 2 m), so
  HOTA's thresholds 0.05 .. 0.95 are distances 1.9 .. 0.1 m, and CLEAR, Identity and
  --calibration count a match within 1 m; MOTP is the mean similarity of CLEAR's matches.
  Files, folders, classes, sequence lengths, the tables and --json are the kitti protocol's
  ("protocol": "kitti-bev", and "distance": 2.0), and so are its rules with distance for IoU:
  result rows matched (Hungarian, within 1 m) to a van (for car), a sitting person (for
  pedestrian) or a truncated or largely hidden object are removed; its 2D rules (25 px,
  DontCare regions) are not applied. A true row without a 3D box (-1000) is left out with a
  note; a result row of a scored class without one is an error.

--json prints one object with the keys
  {", ".join(KEYS[:6])},
  {", ".join(KEYS[6:])}:
fractions in [0, 1] (not percent), counts as integers, null where undefined (hota under
paper).

--out-dir DIR (mot17) also writes the files TrackEval itself writes, made by its own writers:
DIR/pedestrian_summary.txt (one header line and one line of values, space separated: HOTA,
DetA, AssA, DetRe, DetPr, AssRe, AssPr, LocA, ..., MOTA, MOTP, ..., Frag, IDF1, IDR, IDP, ...,
in percent as TrackEval gives them) and DIR/pedestrian_detailed.csv (every field, HOTA's at
each of its 19 thresholds too, a row for the sequence and one for COMBINED), for tools that
read TrackEval's output. --out-dir - prints the summary file instead of the table.

--calibration (mot17) also prints the reliability table of the result's confidence column
(the 7th: a probability in [0, 1], as occtrack track writes it; a peer's detector score works
too): the result boxes binned by confidence into 10 equal bins, per bin the boxes, their mean
confidence and the share right, and the expected calibration error
ECE = sum over bins of (boxes / all boxes) |mean confidence - share right|. A box is right when
it is matched one to one to a true pedestrian at IoU >= 0.5 (boxes on distractors left out, as
the protocol does); a confidence that keeps its word has ECE near 0. With --json the object
gains "calibration": {"ece", "bins", "boxes", "confidence", "right"} (lists a bin, null for an
empty bin).

examples:
  occtrack eval MOT17-04-FRCNN/gt/gt.txt result.txt
  occtrack eval MOT17-04-FRCNN/gt/gt.txt result.txt --calibration
  occtrack eval MOT17-04-FRCNN/gt/gt.txt result.txt --protocol paper --json
  occtrack eval MOT17-04-FRCNN/gt/gt.txt result.txt --out-dir scores/
  occtrack eval kitti/label_02/0000.txt result.txt --protocol kitti --calibration
  occtrack eval kitti/ results/ --protocol kitti --classes car
  occtrack eval kitti/ results_3d/ --protocol kitti-bev"""

LABELS = {
    "mota": "MOTA", "motp": "MOTP", "idf1": "IDF1", "hota": "HOTA",
    "mostly_tracked": "mostly tracked", "mostly_lost": "mostly lost", "fp": "FP", "fn": "FN",
    "id_switches": "ID switches", "gospa": "GOSPA", "cardinality_error": "cardinality error",
}

NOTES = {
    "paper": {
        "mota": "normalised by the number of result boxes (roles swapped)",
        "motp": "mean 1 - IoU of matched pairs, lower is better",
        "idf1": "any pair may match",
        "hota": "not part of the paper protocol",
        "mostly_tracked": "result tracks matched >= 80 % of their frames",
        "mostly_lost": "result tracks matched < 20 % of their frames",
        "fp": "IDFP: true boxes the identity matching leaves out",
        "fn": "IDFN: result boxes the identity matching leaves out",
        "id_switches": "motmetrics switches, roles swapped",
    },
    "mot17": {
        "mota": "TrackEval CLEAR, IoU >= 0.5",
        "motp": "mean IoU of matches, higher is better",
        "idf1": "TrackEval Identity",
        "hota": "TrackEval HOTA, mean over thresholds 0.05..0.95",
        "mostly_tracked": "pedestrian tracks matched > 80 % of their frames",
        "mostly_lost": "pedestrian tracks matched < 20 % of their frames",
        "fp": "result boxes not matched",
        "fn": "pedestrian boxes not matched",
        "id_switches": "TrackEval IDSW",
    },
}
COMMON_NOTES = {
    "gospa": "summed over frames; c = 1, p = 1, alpha = 2, 1 - IoU",
    "cardinality_error": "result boxes / true boxes - 1",
}


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("gt", metavar="GT_FILE",
                        help="ground-truth file (MOTChallenge gt.txt, KITTI label_02/NNNN.txt; "
                             "kitti, kitti-bev: or a folder)")
    parser.add_argument("result", metavar="RESULT_FILE",
                        help="tracker result file (kitti, kitti-bev: or a folder)")
    parser.add_argument("--protocol", choices=(*protocols.PROTOCOLS, *KITTI_PROTOCOLS),
                        default=None,
                        help="scoring protocol (default: kitti for KITTI ground truth, else "
                             "mot17, the official MOTChallenge one; paper: the paper's Table "
                             "II scoring; kitti-bev: KITTI 3D results on the ground plane; "
                             "see above)")
    parser.add_argument("--classes", metavar="LIST",
                        help="kitti, kitti-bev: comma list of the classes to score (car, "
                             "pedestrian; default both)")
    parser.add_argument("--frames", type=int, metavar="N",
                        help="sequence length (default: seqLength from the ground truth's "
                             "seqinfo.ini, else the last frame in either file)")
    parser.add_argument("--max-gap-frames", type=whole_number(0), metavar="N",
                        default=DAY_AT_30_FPS,
                        help="refuse more than N empty frames in a row in either file, so "
                             "that a stray frame number "
                             "cannot make the scoring walk billions of frames (default "
                             f"{DAY_AT_30_FPS}, a day at 30 fps)")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object instead of the table")
    parser.add_argument("--calibration", action="store_true",
                        help="also print the reliability table and ECE of the confidence "
                             "column (mot17, kitti, kitti-bev; see above)")
    parser.add_argument("--out-dir", metavar="DIR",
                        help="also write TrackEval's pedestrian_summary.txt and "
                             "pedestrian_detailed.csv here (mot17; '-': print the summary)")
    parser.add_argument("--force", action="store_true",
                        help="replace the files in --out-dir if they exist")


def _num_frames(args: argparse.Namespace) -> int | None:
    if args.frames is not None:
        if args.frames < 1:
            raise OcctrackError(f"--frames must be at least 1, got {args.frames}")
        return args.frames
    from occtrack.io.mot import find_seqinfo, read_seqinfo

    folder = find_seqinfo(args.gt)
    return int(read_seqinfo(folder)["length"]) if folder is not None else None


def _scoring_length(gt, result, stated: int | None) -> int | None:
    """The frames to score: the stated sequence length, checked against both files, cut to
    the last frame either file has a row in. The frames after it hold no box, so no number
    changes (every metric sums over frames, GOSPA included), and a seqinfo.ini or --frames
    of 10^8 costs nothing rather than memory for 10^8 empty frames."""
    if stated is None:
        return None
    from occtrack.metrics.protocols import check_tables

    check_tables(gt, result, stated)
    return min(stated, max(gt.num_frames, result.num_frames, 1))


def _format(key: str, value) -> str:
    if value is None:
        return "-"
    if isinstance(value, int):
        return str(value)
    if key == "gospa":
        return f"{value:.1f}"
    return f"{value:.4f}"


def _out_files(args: argparse.Namespace) -> dict[str, object] | None:
    """Where --out-dir's files go ({name: path}), checked before any scoring; None without
    --out-dir, {} for '-'."""
    if args.out_dir is None:
        return None
    if args.protocol != "mot17":
        raise OcctrackError("--out-dir writes TrackEval's files, which only the mot17 protocol "
                            "makes; use --protocol mot17 (or --json)")
    if args.out_dir == "-":
        if args.json:
            raise OcctrackError("--out-dir - and --json both print to standard output; give "
                                "--out-dir a folder")
        return {}
    from pathlib import Path

    from occtrack.io.atomic import check_output
    from occtrack.metrics.trackeval_mot17 import DETAILED_FILE, SUMMARY_FILE

    folder = Path(args.out_dir)
    if folder.exists() and not folder.is_dir():
        raise OcctrackError("is a file; --out-dir takes a folder", str(folder))
    if not folder.resolve().parent.is_dir():
        raise OcctrackError("folder does not exist", str(folder.parent))
    paths = {}
    for name in (SUMMARY_FILE, DETAILED_FILE):
        paths[name] = folder / name
        if folder.is_dir():
            check_output(paths[name], args.force, (args.gt, args.result))
    return paths


def _sequence_name(args: argparse.Namespace) -> str:
    from pathlib import Path

    from occtrack.io.mot import find_seqinfo, read_seqinfo

    folder = find_seqinfo(args.gt)
    if folder is not None:
        return str(read_seqinfo(folder)["name"])
    return Path(args.result).stem


def _pick_protocol(args: argparse.Namespace) -> None:
    """--protocol, or kitti when the ground truth is a KITTI file or folder, else mot17."""
    if args.protocol is None:
        from pathlib import Path

        from occtrack.io.kitti import looks_like_kitti

        gt = Path(args.gt)
        kitti = (gt.is_dir() and ((gt / "label_02").is_dir() or any(gt.glob("*.txt")))
                 or gt.is_file() and looks_like_kitti(gt))
        args.protocol = "kitti" if kitti else "mot17"
    if args.classes is not None and args.protocol not in KITTI_PROTOCOLS:
        raise OcctrackError("--classes picks KITTI's classes; use --protocol kitti or "
                            "kitti-bev")


def run(args: argparse.Namespace) -> int:
    from occtrack.io.mot import read_mot
    from occtrack.metrics import protocols
    from occtrack.metrics.evaluate import check_truth, evaluate_frames

    start = time.perf_counter()
    _pick_protocol(args)
    if args.protocol in KITTI_PROTOCOLS:
        return _run_kitti(args, start)
    if args.calibration and args.protocol != "mot17":
        raise OcctrackError("--calibration decides which boxes are right as the mot17 protocol "
                            "does; use --protocol mot17")
    out_files = _out_files(args)
    stated = _num_frames(args)
    gt = read_mot(args.gt, "gt", max_gap_frames=args.max_gap_frames)
    result = read_mot(args.result, "result", max_gap_frames=args.max_gap_frames)
    num_frames = _scoring_length(gt, result, stated)
    left_out = int(protocols.result_classes_left_out(result, args.protocol).sum())
    if left_out:
        print(f"occtrack eval: note: {left_out} of {len(result)} result rows name a class other "
              f"than pedestrian (column 8) and are not scored", file=sys.stderr)
    frames = protocols.scored_frames(gt, result, args.protocol, num_frames)
    check_truth(frames, gt)
    trackeval_results = None
    if out_files is not None:
        from occtrack.metrics.trackeval_mot17 import SUMMARY_FILE, output_files, sequence_results

        trackeval_results = sequence_results(frames.trackeval)
        texts = output_files({_sequence_name(args): trackeval_results})
    values = evaluate_frames(frames, gt, result, trackeval_results)
    table = _calibration(args, frames, result) if args.calibration else None
    seconds = time.perf_counter() - start

    if out_files == {}:
        sys.stdout.write(texts[SUMMARY_FILE])
        return 0
    if out_files:
        from occtrack.io.atomic import atomic_write

        next(iter(out_files.values())).parent.mkdir(exist_ok=True)
        for name, path in out_files.items():
            with atomic_write(path, args.force) as fh:
                fh.write(texts[name])
    if args.json:
        print(json.dumps(values if table is None else {**values,
                                                        "calibration": table.as_dict()}))
        return 0
    notes = {**NOTES[args.protocol], **COMMON_NOTES}
    print(f"{args.result} against {args.gt}")
    print(f"protocol {args.protocol}: {protocols.SUMMARY[args.protocol]}")
    print()
    for key in KEYS:
        print(f"  {LABELS[key]:<18} {_format(key, values[key]):>10}   {notes[key]}")
    print()
    if table is not None:
        print(format_reliability(table))
        print()
    print(f"scored {stated or frames.num_frames} frames, {frames.num_truth} true boxes, "
          f"{frames.num_estimates} result boxes, {seconds:.2f} s")
    if out_files:
        print(f"TrackEval's files: {', '.join(str(p) for p in out_files.values())}")
    return 0


def _calibration(args: argparse.Namespace, frames, result):
    """The reliability table of the result's confidence column, which must hold
    probabilities."""
    import numpy as np

    from occtrack.metrics.reliability import reliability

    bad = np.flatnonzero(~((result.score >= 0) & (result.score <= 1)))
    if len(bad):
        line = bad[0] if result.line is None else result.line[bad[0]]
        raise OcctrackError(f"line {line}: confidence (column 7) {result.score[bad[0]]} is not "
                            f"a probability in [0, 1], which --calibration needs", args.result)
    return reliability(frames, result.score)


def format_reliability(table) -> str:
    """The reliability table as text: one line a bin, then the ECE."""
    lines = ["  calibration of the confidence column (right: matched at IoU >= 0.5)",
             f"  {'confidence':<12}{'boxes':>8}{'mean':>9}{'right':>9}"]
    for b in range(len(table.boxes)):
        lo, hi = table.edges[b], table.edges[b + 1]
        close = "]" if b == len(table.boxes) - 1 else ")"
        mean = "-" if table.boxes[b] == 0 else f"{table.confidence[b]:.3f}"
        right = "-" if table.boxes[b] == 0 else f"{table.right[b]:.3f}"
        lines.append(f"  [{lo:.1f}, {hi:.1f}{close}  {int(table.boxes[b]):>8}{mean:>9}{right:>9}")
    lines.append(f"  ECE {table.ece:.4f} over {table.num_boxes} boxes")
    return "\n".join(lines)


KITTI_COLUMNS = (("hota", "HOTA", ".3f"), ("deta", "DetA", ".3f"), ("assa", "AssA", ".3f"),
                 ("loca", "LocA", ".3f"), ("mota", "MOTA", ".3f"), ("idf1", "IDF1", ".3f"),
                 ("id_switches", "IDSW", "d"), ("fp", "FP", "d"), ("fn", "FN", "d"),
                 ("mostly_tracked", "MT", "d"), ("mostly_lost", "ML", "d"),
                 ("motp", "MOTP", ".3f"))


def _run_kitti(args: argparse.Namespace, start: float) -> int:
    """`occtrack eval --protocol kitti`: TrackEval's Kitti2DBox, per class and combined
    (`--protocol kitti-bev`: the same on the ground plane, `occtrack.metrics.kitti_bev`)."""
    from occtrack.metrics import trackeval_kitti

    if args.protocol == "kitti-bev":
        from occtrack.metrics import kitti_bev as scoring
    else:
        scoring = trackeval_kitti
    if args.out_dir is not None:
        raise OcctrackError(f"--out-dir writes TrackEval's MOTChallenge files; the "
                            f"{args.protocol} protocol prints its tables (or --json)")
    classes = list(trackeval_kitti.parse_classes(args.classes))
    if args.frames is not None and args.frames < 1:
        raise OcctrackError(f"--frames must be at least 1, got {args.frames}")
    pairs = trackeval_kitti.sequence_pairs(args.gt, args.result)
    report = scoring.evaluate(pairs, classes, args.frames, args.calibration,
                              args.max_gap_frames)
    for note in report["notes"]:
        print(f"occtrack eval: note: {note}", file=sys.stderr)
    if args.json:
        for entry in report["classes"].values():
            if "calibration" in entry:
                entry["calibration"] = entry["calibration"].as_dict()
        print(json.dumps(report))
        return 0
    print(format_kitti(report))
    if args.calibration:
        for cls, entry in report["classes"].items():
            print()
            print(f"{cls}:")
            print(format_reliability(entry["calibration"]))
    print()
    print(f"scored {len(pairs)} sequence{'s' * (len(pairs) != 1)}, classes "
          f"{', '.join(classes)}, {time.perf_counter() - start:.2f} s")
    return 0


KITTI_TITLES = {
    "kitti": "KITTI tracking's official evaluation, run by TrackEval (Kitti2DBox); HOTA, DetA, "
             "AssA, LocA: means over the 19 localisation thresholds",
    "kitti-bev": "KITTI 3D tracking on the ground plane: TrackEval's HOTA, CLEAR and Identity "
                 "with similarity max(0, 1 - d / 2 m) between (x, z) centres; HOTA, DetA, "
                 "AssA, LocA: means over the 19 thresholds (1.9 .. 0.1 m); MOTA, IDF1: within "
                 "1 m; MOTP: mean similarity",
}


def format_kitti(report: dict) -> str:
    """The kitti and kitti-bev protocols' tables: per class a row a sequence and TrackEval's
    combined row."""
    lines = [f"protocol {report['protocol']}: {KITTI_TITLES[report['protocol']]}"]
    header = f"  {'sequence':<12}" + "".join(f"{title:>8}" for _, title, _ in KITTI_COLUMNS)

    def row(name: str, values: dict) -> str:
        return f"  {name:<12}" + "".join(
            f"{'-' if values[key] is None else format(values[key], fmt):>8}"
            for key, _, fmt in KITTI_COLUMNS)

    for cls, entry in report["classes"].items():
        lines += ["", cls, header]
        lines += [row(name, values) for name, values in entry["sequences"].items()]
        if len(entry["sequences"]) > 1:
            lines.append(row("COMBINED", entry["combined"]))
    return "\n".join(lines)
