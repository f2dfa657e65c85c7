"""`occtrack benchmark DIR`: occtrack and the box-only peers on every sequence folder in DIR."""

from __future__ import annotations

import argparse
import sys
import time

NAME = "benchmark"
HELP = "occtrack's occlusion models and the peer trackers on MOTChallenge or KITTI folders"
DESCRIPTION = """\
Track every sequence folder under DIR (or DIR itself, if it is one) with occtrack under each
occlusion model (none, measurement-wise, object-wise; every other setting the default) and
with the box-only peers of Roboflow's `trackers` package (sort, bytetrack, ocsort, botsort,
cbiou; library defaults, the sequence's frame rate, every frame; BoT-SORT without its
camera-motion step, which needs the images), score each result under the mot17 protocol
(TrackEval) and print a table per sequence: HOTA, IDF1, MOTA, DetA, AssA, LocA, FP, FN, IDSW,
ECE and the frames per second of the tracker call (scoring not counted). With more than one
sequence, two tables follow: TrackEval's COMBINED_SEQ scores (counts summed, HOTA and its parts
from the summed counts, as MOTChallenge reports a benchmark) and the plain mean over sequences.

Engine: each (sequence, tracker) run is one task of occtrack sweep's engine, a Dask
LocalCluster with one single-threaded worker process per core (--workers N), started and
stopped by the command; --scheduler tcp://HOST:PORT sends the tasks to a running Dask cluster
(its workers must import occtrack and see DIR); --sequential runs them in this process. The
report is the same on every engine (run times aside). Without Dask (the `sweep` extra) the
runs go in this process, with a note.

A sequence folder holds det/det.txt (detections, rows in any frame order), gt/gt.txt and
seqinfo.ini (image size, frame rate, length), as MOT17's do. The peers need the `peers` extra
(pip install "occtrack[peers]"); without it they are left out with a note.

--json FILE writes one JSON object to FILE (replaced atomically; `--json -` prints it instead
of the tables):
  {"protocol": "mot17", "trackers": [names],
   "sequences": {NAME: {"folder", "frames", "fps", "image_size": [w, h],
                        "trackers": {TRACKER: SCORES}, "calibration": {TRACKER: TABLE}}},
   "combined": {"method", "trackers": {TRACKER: SCORES}, "calibration": {TRACKER: TABLE}},
   "mean": {"method", "trackers": {TRACKER: {hota, idf1, mota, deta, assa, loca, motp, ece}}}}
SCORES holds hota, idf1, mota, motp, deta, assa, loca (fractions in [0, 1], MOTA can be
negative), ece (the expected calibration error of the result's confidence column, as
`occtrack eval --calibration` prints it; combined: of all boxes pooled), mostly_tracked,
mostly_lost, fp, fn, id_switches, tracks (counts), seconds and frames_per_second of the
tracker call. TABLE is the reliability table (`occtrack eval --calibration --json`'s):
{"ece", "bins", "boxes", "confidence", "right"}, per bin the boxes, their mean confidence and
the share right (null for an empty bin); combined: the boxes of all sequences pooled.

What `occtrack report` draws is added to each sequence on request, on the boxes the mot17
protocol scores, lists with one entry a frame (entry t is frame t + 1):
  --per-frame   "per_frame": {"truth": [true objects],
                              "trackers": {TRACKER: {"gospa", "missed", "false", "estimates"}}}
                (GOSPA with c = 1, p = 1, alpha = 2 and 1 - IoU, as occtrack eval sums it; the
                true objects it misses, the reported boxes it counts false, the reported
                boxes scored)
  --keep-boxes  the per-frame lists and "boxes": {"truth": BOXES, "trackers": {TRACKER: BOXES}}
                BOXES: {"frame": [f], "id": [i], "ltwh": [[left, top, width, height]]}, one
                entry a box in frame order; a tracker's also "ignored" (indices of the boxes
                the protocol leaves out: on a distractor, or of another class) and, for
                occtrack, "state" (0 detected, 1 coasting without a detection, 2 coasting and
                put down to occlusion). MOT17's three sequences, five trackers: 9 MB.

KITTI: a KITTI tracking folder (DIR/label_02/NNNN.txt, DIR/det_02/NAME/NNNN.txt,
DIR/seqinfo/NNNN.ini, DIR/evaluate_tracking.seqmap naming the sequences) is recognised by its
layout (or --layout kitti). The detections are det_02/NAME (--detections NAME; default: the
only folder there, else rrc). Every sequence is scored by KITTI's protocol (TrackEval's
Kitti2DBox, as occtrack eval --protocol kitti) for car and pedestrian apart (--classes picks):
occtrack tracks all classes in one run (a track keeps its class; every box hides the others
for the occlusion models), each peer one class at a time. Tables per class: each sequence with
a scored true box of the class, TrackEval's COMBINED_SEQ, the mean over those sequences; the
frame rate is seqinfo's. The JSON is
  {"protocol": "kitti", "layout": "kitti", "folder", "detections", "trackers", "classes",
   "sequences": {NAME: {"frames", "fps", "image_size",
                        "classes": {CLASS: {"truth": scored true boxes,
                                            "trackers": {TRACKER: SCORES},
                                            "calibration": {TRACKER: TABLE}}}}},
   "combined": {"method", "classes": {CLASS: {"trackers": {TRACKER: SCORES},
                                              "calibration": {TRACKER: TABLE}}}},
   "mean": {"method", "classes": {CLASS: {"trackers": {TRACKER: {hota, ...}}}}}}
and occtrack report draws it (tables and calibration; --per-frame and --keep-boxes are
MOTChallenge's only).

KITTI with 3D detections (every row has its 3D columns, x y z not -1000, e.g. det_02/pointrcnn;
decided by the files' content): occtrack's models track the 3D boxes on the ground plane (as
occtrack track --3d) with each sequence's camera poses DIR/poses/NNNN.txt (without one the
camera is taken as still, with a note) and calibration DIR/calib/NNNN.txt (required: its P2
projects a coasting box into the image for the 2D columns), all classes in one run; the peers
track the same detections' 2D boxes class by class, the scores read as probabilities (logits,
PointRCNN's, through the logistic function, as the ground tracker reads them). Every run is
scored by Kitti2DBox as above, and occtrack's also on the ground plane (as occtrack eval
--protocol kitti-bev: HOTA, CLEAR and Identity on the boxes' (x, z) centres, similarity
max(0, 1 - d / 2 m)); the tables add a ground-plane table after each one, a peer's row "-".
The JSON adds "detections_3d" (true), "notes", "ground": {"protocol": "kitti-bev", "distance",
"method"}, per sequence "poses" (whether a pose file was used), and beside each class's
"trackers" (per sequence, combined and mean) a "ground" object: {"truth" (per sequence),
"trackers": {TRACKER: SCORES or null for a peer}, "calibration": {TRACKER: TABLE}} (SCORES
without the run times, the same run's as the 2D scores).

--config FILE takes a TOML file of TrackerConfig settings for occtrack's models (the JSON then
holds them under "settings"): e.g. learn_size_noise = false to see what the learnt size noise
buys.

examples:
  occtrack benchmark $OCCTRACK_DATA
  occtrack benchmark ../shared/data/kitti --json kitti.json --quiet
  occtrack benchmark ../shared/data/kitti --detections pointrcnn --json kitti3d.json
  occtrack benchmark MOT17-04-FRCNN --trackers measurement-wise,bytetrack,botsort
  occtrack benchmark $OCCTRACK_DATA --json benchmark.json --quiet
  occtrack benchmark $OCCTRACK_DATA --json run.json --keep-boxes  # for occtrack report run.json
  occtrack benchmark $OCCTRACK_DATA --scheduler tcp://127.0.0.1:8786"""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("root", metavar="DIR",
                        help="a sequence folder, or a folder of sequence folders")
    parser.add_argument("--trackers", metavar="LIST",
                        help="comma list of trackers (default: none, measurement-wise, "
                             "object-wise, and sort, bytetrack, ocsort, botsort, cbiou when "
                             "the peers extra is installed); boxmot's, with the boxmot "
                             "extra: occluboost, boxmot-botsort, boosttrack, "
                             "boxmot-bytetrack, boxmot-ocsort, sfsort, hybridsort, "
                             "deepocsort")
    parser.add_argument("--config", metavar="FILE",
                        help="TOML file of TrackerConfig settings for occtrack's models (as "
                             "occtrack track --config takes; the image size, frame rate and "
                             "occlusion model stay the sequence's and the model's)")
    parser.add_argument("--layout", choices=("auto", "mot", "kitti"), default="auto",
                        help="the folder's layout (default auto: kitti when DIR holds "
                             "label_02/ and det_02/, else MOTChallenge sequence folders)")
    parser.add_argument("--detections", metavar="NAME",
                        help="kitti: the detector folder det_02/NAME (default: the only one, "
                             "else rrc); 3D boxes there (e.g. pointrcnn) are tracked on the "
                             "ground plane by occtrack's models")
    parser.add_argument("--classes", metavar="LIST",
                        help="kitti: comma list of classes to score (car, pedestrian; default "
                             "both)")
    parser.add_argument("--json", metavar="FILE",
                        help="write the scores as JSON to FILE (- prints them instead of the "
                             "tables)")
    parser.add_argument("--per-frame", action="store_true",
                        help="with --json: also each frame's GOSPA and counts, for "
                             "occtrack report's plots")
    parser.add_argument("--keep-boxes", action="store_true",
                        help="with --json: also every box of the ground truth and the trackers "
                             "(and the per-frame counts), for occtrack report's frame viewer")
    from occtrack.cli.arguments import add_engine_options

    add_engine_options(parser, "run the trackers one by one in this process, without Dask")
    parser.add_argument("--force", action="store_true", help="overwrite an existing JSON file")
    parser.add_argument("--quiet", action="store_true", help="no progress bar, note or summary")


def run(args: argparse.Namespace) -> int:
    from occtrack.errors import OcctrackError
    from occtrack.experiments import benchmark, benchmark_kitti, sweep
    from occtrack.io.atomic import atomic_write, check_output
    from occtrack.progress import summary

    kitti = args.layout == "kitti" or (args.layout == "auto"
                                        and benchmark_kitti.is_layout(args.root))
    classes = _kitti_options(args, kitti)
    if args.json is not None:
        inputs = [args.root]
        if kitti:
            from pathlib import Path

            root = Path(args.root)
            inputs += [*root.glob("evaluate_tracking.seqmap*"), *root.glob("label_02/*"),
                       *root.glob("det_02/*/*"), *root.glob("seqinfo/*"),
                       *root.glob("calib/*"), *root.glob("poses/*")]
        else:
            for folder in benchmark.find_sequences(args.root):
                inputs += [folder / "seqinfo.ini", folder / "det" / "det.txt",
                           folder / "gt" / "gt.txt"]
        check_output(args.json, args.force, inputs)
    if (args.per_frame or args.keep_boxes) and args.json is None:
        option = "--keep-boxes" if args.keep_boxes else "--per-frame"
        raise OcctrackError(f"{option} keeps data for the JSON file only; add --json FILE")
    if args.trackers is None:
        trackers, note = benchmark.default_trackers()
        if note and not args.quiet:
            print(f"occtrack benchmark: note: {note}", file=sys.stderr)
    else:
        trackers = benchmark.parse_trackers(args.trackers)

    engine = None
    if not args.sequential:
        if args.scheduler or sweep.dask_available():
            engine = sweep.DaskEngine(args.scheduler, args.workers)
        elif not args.quiet:
            print("occtrack benchmark: note: Dask is not installed (pip install "
                  "\"occtrack[sweep]\"): the runs go one by one in this process",
                  file=sys.stderr)
    settings = _settings(args.config)
    start = time.perf_counter()
    if kitti:
        report = benchmark_kitti.benchmark(args.root, trackers, args.detections, classes,
                                           quiet=args.quiet, engine=engine, settings=settings)
    else:
        report = benchmark.benchmark(args.root, trackers, quiet=args.quiet,
                                     per_frame=args.per_frame, keep_boxes=args.keep_boxes,
                                     engine=engine, settings=settings)
    if settings:
        report["settings"] = settings
    seconds = time.perf_counter() - start
    if not args.quiet:
        for note in report.get("notes", ()):
            print(f"occtrack benchmark: note: {note}", file=sys.stderr)

    text = benchmark.to_json(report)
    if args.json is not None:  # (atomic_write takes "-" for standard output)
        with atomic_write(args.json, args.force) as fh:
            fh.write(text)
    if args.json != "-":
        print((benchmark_kitti if kitti else benchmark).format_report(report))
    if not args.quiet:
        frames = sum(entry["frames"] for entry in report["sequences"].values()) * len(trackers)
        combined = ([part["trackers"] for part in report["combined"]["classes"].values()]
                    if kitti else [report["combined"]["trackers"]])
        tracks = sum(values["tracks"] for part in combined for values in part.values())
        print(summary(frames, tracks, seconds),
              file=sys.stderr if args.json == "-" else sys.stdout)
    return 0


def _kitti_options(args: argparse.Namespace, kitti: bool) -> tuple[str, ...]:
    """The classes to score (kitti), after refusing the options that do not fit the layout."""
    from occtrack.errors import OcctrackError

    if not kitti:
        for option, value in (("--detections", args.detections), ("--classes", args.classes)):
            if value is not None:
                raise OcctrackError(f"{option} is for a KITTI folder (label_02/, det_02/); "
                                    f"{args.root} is not one (or pass --layout kitti)")
        return ()
    if args.per_frame or args.keep_boxes:
        option = "--keep-boxes" if args.keep_boxes else "--per-frame"
        raise OcctrackError(f"{option} is for MOTChallenge folders; a KITTI run keeps the "
                            f"tables and calibration only")
    from occtrack.metrics.trackeval_kitti import parse_classes

    return parse_classes(args.classes)


def _settings(path: str | None) -> dict:
    """The --config file's settings, checked (every name and value a TrackerConfig takes)
    before any run."""
    if path is None:
        return {}
    from occtrack.tracker import TrackerConfig
    from occtrack.tracker.config import load_toml

    values = {k: v for k, v in load_toml(path).items()
              if k not in ("image_size", "fps", "occlusion")}
    TrackerConfig.from_dict(values, path)
    return values
