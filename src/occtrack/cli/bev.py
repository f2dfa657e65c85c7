"""`occtrack bev DET_FILE --frame N -o PICTURE`: one frame of the 3D tracks, from above."""

from __future__ import annotations

import argparse
import sys
import time

from occtrack.cli.arguments import frame_rate, whole_number
from occtrack.cli.track import OCCLUSION_NAMES
from occtrack.errors import OcctrackError

NAME = "bev"
HELP = "draw one frame of a KITTI 3D detection file's tracks from above (bird's-eye view)"
DESCRIPTION = """\
Track a KITTI file's 3D boxes on the ground plane (as `occtrack track --3d` does: every
class in one run, occlusion seen from the sensor) from frame 0 up to --frame N (0-based, as
the file numbers them), and draw frame N from above: x across, z (forward) up the page, in
metres, in that frame's camera coordinates. The picture shows

  the sensor          a black triangle at the camera's origin, and the camera's field of
                      view as two dotted rays (from the calibration's P2 and the image
                      width; 90 degrees when no calibration is found)
  the detections      the frame's boxes, magenta, filled the more the higher their score
  the true boxes      with --gt LABEL_FILE, faint grey
  the tracks          blue with their ids; dashed while coasting (no detection this frame)
  held while hidden   orange, dashed: coasting with the miss put down to occlusion; the
                      angular shadows of the nearer boxes that overlap them, faint grey

and a legend. The camera's path comes from --poses FILE (one 3x4 [R|t] a frame, found
beside a KITTI layout as DIR/poses/NNNN.txt), else the camera is taken as still; the
calibration from --calib FILE (else DIR/calib/NNNN.txt); the frame rate from --fps, else
DIR/seqinfo/NNNN.ini, else the --config file. Scores outside [0, 1] are read as logits
(PointRCNN's). The picture's format follows its name (.png, .pdf, .svg, .jpg); it is written
whole or not at all, and an existing one is replaced only with --force. Needs the viz extra:
pip install "occtrack[viz]".

examples:
  occtrack bev kitti/det_02/pointrcnn/0000.txt --frame 50 -o bev.png
  occtrack bev kitti/det_02/pointrcnn/0000.txt --frame 50 --gt kitti/label_02/0000.txt \\
      --occlusion none -o bev-none.png"""

SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("detections", metavar="DET_FILE",
                        help="KITTI detection file with the 3D columns (e.g. PointRCNN's)")
    parser.add_argument("--frame", type=whole_number(0), metavar="N", required=True,
                        help="the frame to draw, 0-based as the file numbers them")
    parser.add_argument("-o", "--output", metavar="PICTURE", required=True,
                        help="the picture to write (.png, .pdf, .svg, .jpg)")
    parser.add_argument("--gt", metavar="LABEL_FILE",
                        help="KITTI labels of the sequence: draw the frame's true boxes faintly")
    parser.add_argument("--poses", metavar="FILE",
                        help="the camera's poses, one 3x4 [R|t] a frame (default: "
                             "DIR/poses/NNNN.txt beside a KITTI layout, else a still camera)")
    parser.add_argument("--calib", metavar="FILE",
                        help="KITTI calibration whose P2 gives the field of view (default: "
                             "DIR/calib/NNNN.txt beside a KITTI layout, else 90 degrees)")
    parser.add_argument("--classes", metavar="LIST",
                        help="comma list of types to draw, e.g. Car,Pedestrian (default: "
                             "every type in the file); every type is tracked, as with "
                             "track --3d")
    parser.add_argument("--occlusion", choices=OCCLUSION_NAMES, default=None,
                        help="occlusion model (default: object-wise, or the config file's)")
    parser.add_argument("--config", metavar="FILE", help="TOML file of tracker settings")
    parser.add_argument("--fps", type=frame_rate, metavar="HZ", default=None,
                        help="frame rate of the sequence (default: DIR/seqinfo/NNNN.ini)")
    parser.add_argument("--force", action="store_true", help="replace PICTURE if it exists")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def _config(args: argparse.Namespace, seqinfo: dict | None):
    """The ground tracker's settings (`occtrack.tracker.ground.ground_config`, as `occtrack
    track --3d` builds them): the --config file's, the frame rate of --fps, seqinfo or the
    file, the --occlusion model."""
    from occtrack.tracker.config import load_toml
    from occtrack.tracker.ground import ground_config

    values: dict = {}
    source = "command line"
    if args.config:
        source = args.config
        try:
            values = load_toml(args.config)
        except UnicodeDecodeError as err:
            raise OcctrackError(f"not valid TOML: byte {err.start} is not UTF-8",
                                args.config) from None
    if args.fps is not None:
        values["fps"] = args.fps
    elif seqinfo is not None:
        values["fps"] = float(seqinfo["fps"])
    elif "fps" not in values:
        raise OcctrackError("frame rate unknown: pass --fps HZ (no DIR/seqinfo/NNNN.ini "
                            "beside a KITTI layout DIR/det_02/NAME/NNNN.txt, no fps in a "
                            "--config file)", args.detections)
    if args.occlusion is not None:
        values["occlusion"] = args.occlusion
    return ground_config(values, source)


def _kept(table, types):
    """The rows of a KITTI table of a known type, and of the picked types (None: every one)."""
    import numpy as np

    from occtrack.io import kitti

    keep = (table.type != kitti.DONTCARE) & (table.type != kitti.UNKNOWN)
    if types is not None:
        keep &= np.isin(table.type, types)
    return table.select(keep)


def track_until(table, frame: int, config, poses=None, quiet: bool = True):
    """Track a KITTI table's 3D boxes (`occtrack.io.kitti.KittiTable`, every class at once)
    with `GroundTracker` from frame 0 to `frame`; `poses` (F, 3, 4) the camera's path (None: a
    still camera). Returns frame `frame`'s `GroundTracks`, the rows of the table in that frame
    and every row's score as a probability (`detection_scores`)."""
    import numpy as np

    from occtrack.progress import progress
    from occtrack.tracker.ground import GroundTracker, detection_scores

    tracker = GroundTracker(config)
    scores = detection_scores(table.score)
    order = np.argsort(table.frame, kind="stable")
    bounds = np.searchsorted(table.frame[order], np.arange(frame + 2))
    for f in progress(range(frame + 1), frame + 1, f"tracking 3D ({config.occlusion})", quiet):
        sel = order[bounds[f]:bounds[f + 1]]
        tracks = tracker.update(table.box3d[sel], scores[sel], table.type[sel],
                                pose=None if poses is None else poses[f])
    return tracks, sel, scores


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from occtrack.cli.arguments import existing_file
    from occtrack.extras import require
    from occtrack.io.atomic import check_output

    existing_file(args.detections, "a KITTI detection file")
    for path, what in ((args.gt, "a KITTI label file"), (args.poses, "a KITTI pose file"),
                       (args.calib, "a KITTI calibration file"),
                       (args.config, "a TOML settings file")):
        if path is not None:
            existing_file(path, what)
    if Path(args.output).suffix.lower() not in SUFFIXES:
        raise OcctrackError(f"a picture's name ends in {', '.join(SUFFIXES)}", args.output)
    require("matplotlib", "occtrack bev")

    import numpy as np

    from occtrack.io import kitti
    from occtrack.io import kitti_geometry as geometry
    from occtrack.io.mot import read_seqinfo
    from occtrack.viz.ground import FIXED_FOV, draw_ground_frame, field_of_view

    seq = kitti.find_seqinfo(args.detections)
    calib = args.calib or geometry.find_calib(args.detections)
    poses_file = args.poses or geometry.find_poses(args.detections)
    check_output(args.output, args.force,
                 (args.detections, args.gt, args.config, seq, calib, poses_file))
    if not kitti.looks_like_kitti(args.detections):
        raise OcctrackError("not a KITTI tracking file (frame id type ... h w l x y z "
                            "rotation_y [score] a row): occtrack bev draws KITTI 3D boxes",
                            args.detections)
    info = None if seq is None else read_seqinfo(seq)
    config = _config(args, info)
    types = None if args.classes is None else kitti.parse_classes(args.classes)
    table = _kept(kitti.read_kitti(args.detections), None)  # every type tracked (`track --3d`)
    unknown = np.flatnonzero(table.box3d[:, 3] <= -999)
    if len(unknown):
        line = None if table.line is None else int(table.line[unknown[0]])
        raise OcctrackError("a detection without its 3D columns (x y z = -1000): occtrack bev "
                            "needs a 3D detector's boxes (h w l x y z rotation_y)",
                            args.detections, line)
    length = info["length"] if info is not None else table.num_frames
    frame = args.frame
    if frame >= length:
        where = ("the sequence's", ", seqinfo") if info is not None else ("the file's", "")
        raise OcctrackError(f"--frame {frame} is past {where[0]} {length} frames "
                            f"(0..{length - 1}{where[1]})" if length else
                            f"--frame {frame}: the file holds no detections",
                            args.detections)
    poses = None if poses_file is None else geometry.read_poses(poses_file, frame + 1)
    calibration = None if calib is None else geometry.read_calib(calib)
    truth = None
    if args.gt is not None:
        labels = _kept(kitti.read_kitti(args.gt), types)
        known = (labels.box3d[:, 3] > -999) & (labels.box3d[:, :3] > 0).all(axis=1)
        truth = labels.box3d[(labels.frame == frame) & known]
    notes = []
    if poses is None:
        notes.append("no poses (--poses FILE): the camera is taken as still")
    if calibration is None:
        notes.append("no calibration (--calib FILE): the field of view drawn is 90 degrees")
    for note in notes:
        print(f"occtrack bev: warning: {args.detections}: {note}", file=sys.stderr)

    start = time.perf_counter()
    tracks, sel, scores = track_until(table, frame, config, poses, args.quiet)
    if types is not None:  # only the picked types drawn
        sel = sel[np.isin(table.type[sel], types)]
        tracks = tracks.select(np.isin(tracks.classes, types))
    if calibration is None:
        fov = FIXED_FOV
    else:
        width = info["width"] if info is not None else 2 * calibration.P2[0, 2]
        fov = field_of_view(calibration.P2, width)
    name = kitti.sequence_name(args.detections)
    hidden = int((tracks.occluded & tracks.coasting).sum())
    title = (f"{name}, frame {frame} ({config.occlusion}): {len(sel)} detections, "
             f"{len(tracks)} tracks, {int(tracks.coasting.sum())} coasting, "
             f"{hidden} held while hidden")
    draw_ground_frame(args.output, table.box3d[sel], scores[sel], tracks, truth, fov=fov,
                      title=title, overwrite=args.force)
    if not args.quiet:
        print(f"drew frame {frame}: {len(sel)} detections, {len(tracks)} tracks "
              f"({hidden} held while hidden) to {args.output}, "
              f"{time.perf_counter() - start:.1f} s")
    return 0
