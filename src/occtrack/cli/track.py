"""`occtrack track DET_FILE -o RESULT_FILE`: the box tracker on a MOTChallenge detection file."""

from __future__ import annotations

import argparse
import math
import re
import sys
import time

from occtrack.cli.arguments import frame_rate, positive_int, seconds, whole_number
from occtrack.errors import OcctrackError

OCCLUSION_NAMES = ("none", "object-wise", "measurement-wise")
"""`occtrack.tracker.OCCLUSION_NAMES`, repeated so that `--help` loads no tracker (a test keeps
the two equal)."""

NAME = "track"
HELP = "track the boxes of a MOTChallenge or KITTI detection file (PMB tracker with occlusion)"
DESCRIPTION = """\
Track pedestrians (or any boxes) through a MOTChallenge detection file with the
Gaussian-mixture Poisson multi-Bernoulli tracker, and write a MOTChallenge result file
(frame,id,left,top,width,height,confidence,-1,-1,-1), one row per reported object and frame.
The confidence is the probability that the box is a real object at that place (exists and
overlaps the true box at IoU >= 0.5); `occtrack eval --calibration` measures how well it
keeps its word.

Detection rows are frame,id,left,top,width,height,score[,...] (the id is ignored), or KITTI
tracking rows (told apart by content, or --format kitti; see below). Occlusion:
  none              a missed detection is evidence that the object is gone
  object-wise       objects hide objects (expected-value approximation; the default)
  measurement-wise  detections hide detections, as a detector's non-maximum suppression does

The image size comes from --image-size, else from seqinfo.ini when the file sits in a
MOTChallenge sequence folder (SEQ/det/det.txt), else from the --config file; so does the frame
rate (--fps); where neither flag, seqinfo.ini nor config file gives one, the run stops and
says so: the tracker's noises and rates are per second and its lengths in box heights, so
they hold for any camera once the frame rate is known. Every frame is tracked
(--frame-step N tracks every N-th, as the paper did with 2; the frames between are reported
with the tracks carried along their velocities).

Rows are checked, not altered in silence: a box of zero or negative size and a score outside
[0, 1] stop the run with the file and line. A detector whose scores are not probabilities
(MOT17's DPM, for one) takes --score-range LO,HI, which maps LO..HI linearly onto 0..1;
--lenient skips such boxes and clips such scores, with one warning giving the counts and the
first line. A box partly outside the image is tracked; one wholly outside it (real detectors
report them) is skipped, with a warning giving the count and the first line. More than
--max-gap-frames empty frames in a row (default: a day at the frame rate) is an error too, so a
stray frame number cannot make the tracker step through billions of empty frames.

KITTI: a KITTI tracking file (space separated, frame id type truncated occluded alpha x1 y1
x2 y2 h w l x y z rotation_y [score], frames 0-based; a file without the 18th column has score
1) is tracked class by class in one run: each row's type is its class, a track keeps its class
for life and never takes another class's box, and every class's boxes hide the others' for
the occlusion models. --classes Car,Pedestrian picks the types (default: every type in the
file); DontCare rows, unknown types and types not picked are skipped with a count. The result
is KITTI's result format (the label columns with the reported box; for a box taken from a
detection, that detection's alpha and 3D columns, else -1 / -1000 / -10; the confidence as
the score), frames numbered as they came. The image size and frame rate come from the flags,
else from DIR/seqinfo/NNNN.ini when the file sits in a KITTI layout (DIR/det_02/NAME/NNNN.txt).

3D (--3d, KITTI files with the 3D columns, e.g. PointRCNN's): each class's boxes are tracked
on the ground plane (occtrack.tracker.ground: the footprint's centre, velocity and size in
metres and seconds; height, elevation and heading carried from the detections), occlusion
seen from the sensor (nearer boxes hide the angles behind them). Two boxes whose footprints
overlap by half of the smaller one or more are one object seen twice (under two classes, say):
the lower-scored one is dropped, with a count. With --classes every type is still tracked (an
unpicked one can hide a picked one or be the box it duplicates) and only the picked types'
tracks are written. The camera's path comes from
--poses FILE (one 3x4 [R|t] a frame, KITTI's poses/NNNN.txt, found beside a KITTI layout),
else the camera is taken as still; the calibration's P2 (--calib FILE, KITTI's calib/NNNN.txt,
found beside a KITTI layout; required) projects a coasting box into the image for the 2D
columns, clipped to the image (a box that projects nowhere is left out). Scores outside [0, 1]
are read as logits (PointRCNN's). The result is KITTI's format with the 3D columns in each
frame's camera coordinates: `occtrack eval --protocol kitti` scores its 2D boxes, `--protocol
kitti-bev` its ground positions.

The result file is written whole or not at all: to a temporary file beside it, renamed into
place when complete, so an interrupted run leaves the old file (or none). -o - writes the
result to standard output (the summary then goes to standard error).

--config takes a TOML file of TrackerConfig settings (see occtrack.tracker.config), e.g.
  occlusion = "measurement-wise"
  edge_noise = 0.05
Flags given on the command line win over the file."""


def image_size(text: str) -> tuple[float, float]:
    """argparse type: WxH in pixels."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*[xX,]\s*(\d+(?:\.\d*)?)\s*", text)
    if not match or float(match[1]) <= 0 or float(match[2]) <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not an image size; write WxH, "
                                         f"e.g. 1920x1080")
    from occtrack.config import MAX_IMAGE_SIDE

    if max(float(match[1]), float(match[2])) > MAX_IMAGE_SIDE:
        raise argparse.ArgumentTypeError(f"{text}: an image side is at most "
                                          f"{MAX_IMAGE_SIDE:g} px")
    return float(match[1]), float(match[2])


def score_range(text: str) -> tuple[float, float]:
    """argparse type: LO,HI with LO < HI, the raw scores that map to 0 and 1."""
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a score range; write LO,HI, e.g. "
                                         f"-3,60") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise argparse.ArgumentTypeError(f"{text!r}: LO and HI must be numbers with LO < HI")
    return low, high


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("detections", metavar="DET_FILE",
                        help="MOTChallenge or KITTI detection file")
    parser.add_argument("-o", "--output", metavar="RESULT_FILE", required=True,
                        help="where to write the result file, in the detection file's format "
                             "('-': standard output)")
    parser.add_argument("--format", choices=("auto", "mot", "kitti"), default="auto",
                        help="the detection file's format (default auto: KITTI when the third "
                             "field of its first row is a type name, else MOTChallenge)")
    parser.add_argument("--classes", metavar="LIST",
                        help="KITTI: comma list of types to track, e.g. Car,Pedestrian "
                             "(default: every type in the file)")
    parser.add_argument("--occlusion", choices=OCCLUSION_NAMES, default=None,
                        help="occlusion model (default: object-wise, or the config "
                             "file's)")
    parser.add_argument("--config", metavar="FILE", help="TOML file of tracker settings")
    parser.add_argument("--frame-step", type=positive_int, metavar="N", default=None,
                        help="track every N-th frame (default 1, or the config file's)")
    parser.add_argument("--fps", type=frame_rate, metavar="HZ", default=None,
                        help="frame rate of the sequence (default: from seqinfo.ini)")
    parser.add_argument("--image-size", type=image_size, metavar="WxH", default=None,
                        help="image size in pixels (default: from seqinfo.ini)")
    parser.add_argument("--score-range", type=score_range, metavar="LO,HI",
                        help="map the detector's raw scores LO..HI linearly onto 0..1")
    parser.add_argument("--lenient", action="store_true",
                        help="skip boxes of zero or negative size and clip "
                             "scores to [0, 1], with one warning, instead of stopping")
    parser.add_argument("--max-gap-frames", type=whole_number(0), metavar="N",
                        help="most empty frames allowed in a row (default: a day at the "
                             "frame rate)")
    parser.add_argument("--3d", dest="three_d", action="store_true",
                        help="KITTI 3D detections: track the 3D boxes on the ground plane")
    parser.add_argument("--poses", metavar="FILE",
                        help="with --3d: the camera's poses, one 3x4 [R|t] a frame (default: "
                             "DIR/poses/NNNN.txt beside a KITTI layout, else a still camera)")
    parser.add_argument("--calib", metavar="FILE",
                        help="with --3d: KITTI calibration whose P2 projects coasting boxes "
                             "(default: DIR/calib/NNNN.txt beside a KITTI layout)")
    parser.add_argument("--lookahead", type=seconds, metavar="SECONDS", default=None,
                        help="with --3d: seconds of later frames whose scores weigh on each "
                             "frame's confidence, as the file is written after the frames "
                             "(default 0.2; 0: each frame's confidence as an online loop "
                             "gets it)")
    parser.add_argument("--force", action="store_true", help="overwrite RESULT_FILE")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def build_config(args: argparse.Namespace):
    """The tracker settings (a TrackerConfig) and the sequence length (None if unknown) from
    the flags, the sequence's seqinfo.ini and the config file."""
    from occtrack.io.mot import read_seqinfo
    from occtrack.tracker import TrackerConfig
    from occtrack.tracker.config import load_toml

    values: dict = {}
    source = "command line"
    if args.config:
        source = args.config
        try:
            values = load_toml(args.config)
        except UnicodeDecodeError as err:
            raise OcctrackError(f"not valid TOML: byte {err.start} is not UTF-8",
                                args.config) from None
    length = None
    seq = seqinfo_path(args)
    if seq is not None:
        info = read_seqinfo(seq)
        length = int(info["length"])
        if args.image_size is None:
            values["image_size"] = (info["width"], info["height"])
        values["fps"] = float(info["fps"])
    if args.image_size is not None:
        values["image_size"] = args.image_size
    if args.fps is not None:
        values["fps"] = args.fps
    for key, flag in (("image_size", "--image-size WxH"), ("fps", "--fps HZ")):
        if key not in values:
            where = ("DIR/seqinfo/NNNN.ini beside a KITTI layout DIR/det_02/NAME/NNNN.txt"
                     if is_kitti(args) else "seqinfo.ini beside the detection folder")
            raise OcctrackError(f"{key.replace('_', ' ')} unknown: pass {flag} (no {where}, no "
                                f"{key} in a --config file)", args.detections)
    if args.occlusion is not None:
        values["occlusion"] = args.occlusion
    if args.frame_step is not None:
        values["frame_step"] = args.frame_step
    if getattr(args, "three_d", False):
        from occtrack.tracker.ground import ground_config

        return ground_config(values, source), length
    return TrackerConfig.from_dict(values, source), length


def is_kitti(args: argparse.Namespace) -> bool:
    """Whether the detection file is read as KITTI's (--format, else its content; a caller's
    namespace without --format reads MOTChallenge)."""
    if getattr(args, "format", "mot") == "auto":
        from occtrack.io.kitti import looks_like_kitti

        args.format = "kitti" if looks_like_kitti(args.detections) else "mot"
    return getattr(args, "format", "mot") == "kitti"


def seqinfo_path(args: argparse.Namespace):
    """The sequence information beside the detection file: SEQ/seqinfo.ini for SEQ/det/det.txt,
    DIR/seqinfo/NNNN.ini for KITTI's DIR/det_02/NAME/NNNN.txt; None where there is none."""
    from occtrack.io import kitti, mot

    if is_kitti(args):
        return kitti.find_seqinfo(args.detections)
    return mot.find_seqinfo(args.detections)


def run(args: argparse.Namespace) -> int:
    from occtrack.cli.arguments import existing_file
    from occtrack.io import kitti as kitti_io
    from occtrack.io import mot
    from occtrack.io.atomic import check_output
    from occtrack.progress import summary
    from occtrack.tracker import Tracker

    existing_file(args.detections, "a detection file")
    seq = mot.find_seqinfo(args.detections)  # either layout's, before the file is opened
    check_output(args.output, args.force,
                 (args.detections, args.config, seq and seq / "seqinfo.ini",
                  kitti_io.find_seqinfo(args.detections)))
    kitti = is_kitti(args)
    if args.classes is not None and not kitti:
        raise OcctrackError("--classes picks KITTI types; this is a MOTChallenge file (pass "
                            "--format kitti if it is not)", args.detections)
    if (args.poses or args.calib or args.lookahead is not None) and not args.three_d:
        raise OcctrackError("--poses, --calib and --lookahead go with --3d")
    if args.three_d:
        if not kitti:
            raise OcctrackError("--3d tracks KITTI files with the 3D columns; this is a "
                                "MOTChallenge file", args.detections)
        if args.score_range or args.lenient:
            raise OcctrackError("--score-range and --lenient are for 2D detections, not --3d")
    config, length = build_config(args)
    if args.three_d:
        return _track_3d(args, config, length)
    gap = args.max_gap_frames
    if gap is None:
        gap = math.ceil(24 * 3600 * config.fps)
    detections, notes, source = _read(args, config, gap, length)
    for note in notes:
        print(f"occtrack track: warning: {note}", file=sys.stderr)
    if len(detections.frame) == 0:
        print(f"occtrack track: warning: {args.detections} holds no detections, so the "
              f"result has no tracks", file=sys.stderr)
    frames = max(length or 0, detections.num_frames)
    start = time.perf_counter()
    tracker = Tracker(config)
    desc = f"tracking ({config.occlusion})"
    if kitti:
        result = tracker.run(detections, frames, quiet=args.quiet, desc=desc, classes=True)
        _write_kitti(args, config, result, source)
        done, tracks = result.frames, result.num_tracks
    else:
        done, tracks = _stream_mot(args, tracker.run_frames(detections, frames,
                                                            quiet=args.quiet, desc=desc))
    if not args.quiet:
        print(summary(done, tracks, time.perf_counter() - start),
              file=sys.stderr if args.output == "-" else sys.stdout)
    return 0


def _stream_mot(args: argparse.Namespace, reports) -> tuple[int, int]:
    """Write each frame's rows as it is tracked (frame by frame, ids in order: the order
    `occtrack.io.mot.write_mot` sorts into), so a result of any length takes no memory; the
    file is still whole or not at all. Returns the frames and the distinct tracks."""
    import numpy as np

    from occtrack.io.atomic import atomic_write
    from occtrack.io.mot import mot_rows

    frames, ids = 0, set()
    with atomic_write(args.output, args.force) as fh:
        for report in reports:
            frames += 1
            shown = report.tracks
            ids.update(shown.ids.tolist())
            fh.write(mot_rows(np.full(len(shown), report.frame), shown.ids, shown.boxes,
                              shown.confidence))
    return frames, len(ids)


def _read(args: argparse.Namespace, config, gap: int, length: int | None):
    """The detections to track (a MotTable, checked), the warnings to print, and for KITTI the
    file's table with each tracked row's row in it (None for MOTChallenge)."""
    import numpy as np

    from occtrack.io.mot import check_detections, read_detections

    check = {"score_range": args.score_range, "lenient": args.lenient, "max_gap_frames": gap,
             "num_frames": length}
    if not is_kitti(args):
        detections, warning = read_detections(args.detections, config.image_size, **check)
        return detections, [warning] if warning else [], None
    from occtrack.io import kitti

    table = kitti.read_kitti(args.detections)
    classes = None if args.classes is None else kitti.parse_classes(args.classes)
    mot, rows, note = kitti.detections_to_mot(table, classes)
    if length is not None and len(mot) and mot.num_frames > length:
        i = int(np.argmax(mot.frame))
        raise OcctrackError(f"frame {mot.frame[i] - 1} is past the sequence's {length} frames "
                            f"(0..{length - 1}, seqinfo)", args.detections, int(mot.line[i]))
    checked, warning = check_detections(mot, config.image_size, **check)
    kept = np.isin(mot.line, checked.line)  # --lenient may skip rows
    return checked, [w for w in (note, warning) if w], (table, rows[kept])


def _write_kitti(args: argparse.Namespace, config, result, source) -> None:
    """The KITTI result file: frames back to 0-based, corners clipped to the image (as KITTI's
    labels are), the type of each track, and the 3D columns of the detection a box was taken
    from."""
    import numpy as np

    from occtrack.io.kitti import UNKNOWN_3D, clip_to_image, write_kitti
    from occtrack.tracker.boxes import from_ltwh

    table, rows = source
    took = result.detection_row
    n = len(result.frame)
    box3d = np.tile(UNKNOWN_3D, (n, 1))
    alpha = np.full(n, -10.0)
    hit = took >= 0
    box3d[hit] = table.box3d[rows[took[hit]]]
    alpha[hit] = table.alpha[rows[took[hit]]]
    corners = clip_to_image(from_ltwh(result.box, "xyxy"), config.image_size)
    write_kitti(args.output, result.frame - 1, result.id, result.classes, corners,
                result.confidence, box3d, alpha, overwrite=args.force)


def _track_3d(args: argparse.Namespace, config, length: int | None) -> int:
    """--3d: the ground tracker on a KITTI file's 3D boxes, written as a KITTI result."""
    import numpy as np

    from occtrack.io import kitti
    from occtrack.io import kitti_geometry as geometry
    from occtrack.io.mot import check_gaps
    from occtrack.progress import summary
    from occtrack.tracker.ground import EVIDENCE_LOOKAHEAD, track_kitti

    table = kitti.read_kitti(args.detections)
    types = (None if args.classes is None else kitti.parse_classes(args.classes))
    keep = (table.type != kitti.DONTCARE) & (table.type != kitti.UNKNOWN)
    skipped = int((~keep).sum())
    table = table.select(keep)  # (every type tracked: an unpicked one hides and duplicates)
    unpicked = 0 if types is None else int((~np.isin(table.type, types)).sum())
    frames = max(length or 0, table.num_frames)
    if length is not None and len(table) and table.num_frames > length:
        i = int(np.argmax(table.frame))
        raise OcctrackError(f"frame {table.frame[i]} is past the sequence's {length} frames "
                            f"(0..{length - 1}, seqinfo)", args.detections, int(table.line[i]))
    gap = args.max_gap_frames
    check_gaps(table, math.ceil(24 * 3600 * config.fps) if gap is None else gap)
    calib = args.calib or geometry.find_calib(args.detections)
    if calib is None:
        raise OcctrackError("--3d needs the camera's calibration (its P2 projects a coasting "
                            "box into the image): pass --calib FILE (no DIR/calib/NNNN.txt "
                            "beside a KITTI layout)", args.detections)
    calibration = geometry.read_calib(calib)
    poses_file = args.poses or geometry.find_poses(args.detections)
    poses = None if poses_file is None else geometry.read_poses(poses_file, frames)
    notes = [f"{skipped} rows skipped (DontCare or unknown types)"] if skipped else []
    if unpicked:
        notes.append(f"{unpicked} rows of types not picked (--classes) tracked, their tracks "
                     f"not written")
    if poses is None:
        notes.append("no poses (--poses FILE): the camera is taken as still")
    for note in notes:
        print(f"occtrack track: warning: {args.detections}: {note}", file=sys.stderr)
    start = time.perf_counter()
    dropped: list[str] = []
    lookahead = EVIDENCE_LOOKAHEAD if args.lookahead is None else args.lookahead
    result = track_kitti(table, frames, config, poses, calibration, config.image_size,
                         quiet=args.quiet, notes=dropped, written=types, lookahead=lookahead)
    for note in dropped:
        print(f"occtrack track: note: {args.detections}: {note}", file=sys.stderr)
    theta = np.arctan2(result.box3d[:, 3], result.box3d[:, 5])
    alpha = (result.box3d[:, 6] - theta + np.pi) % (2 * np.pi) - np.pi
    kitti.write_kitti(args.output, result.frame, result.id, result.type, result.box,
                      result.score, result.box3d, alpha, overwrite=args.force)
    if not args.quiet:
        print(summary(frames, len(np.unique(result.id)), time.perf_counter() - start),
              file=sys.stderr if args.output == "-" else sys.stdout)
    return 0
