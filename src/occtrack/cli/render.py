"""`occtrack render DET_OR_RESULT --images DIR|--video FILE -o OUT`: tracks on the real frames."""

from __future__ import annotations

import argparse
import sys
import time

from occtrack.cli.arguments import positive_float, whole_number
from occtrack.cli.track import OCCLUSION_NAMES, score_range
from occtrack.errors import OcctrackError

NAME = "render"
HELP = "draw tracks on the real frames (a video or a folder of pictures)"
DESCRIPTION = """\
Draw tracks on the frames they were made from, to a video file (.mp4, .avi, .mov, .mkv,
.webm, .gif), one picture (.png, .jpg: the last frame of --frames) or a folder of numbered
pictures (any other OUT). Each track has a colour of its
own, its id on a label and a trail through the bottom centres of its last boxes; a track
reported without a detection in that frame (coasting on the filter's estimate) is drawn
dashed, and labelled "occluded" when its miss is put down to occlusion.

DET_OR_RESULT is a MOTChallenge file:
  a detection file (every id -1)   it is tracked first, as `occtrack track` would (the image
                                   size comes from the frames; the frame rate from --fps,
                                   seqinfo.ini, the video or --config), so coasting and
                                   occluded tracks are known
  a result file (track ids)        its boxes are drawn as they are (all solid)

Frame f of the file is the f-th frame of the video, or the picture of a folder named by the
number f (MOT's img1/000001.jpg; else the f-th picture in name order). --frames A:B renders
only frames A to B. The output is written whole or not at all. Needs the viz extra:
pip install "occtrack[viz]".

examples:
  occtrack render MOT17-04-FRCNN/det/det.txt --images MOT17-04-FRCNN/img1 -o tracks.mp4
  occtrack render result.txt --video street.mp4 -o frames/ --frames 100:200
  occtrack render det.txt --images img1 --fps 30 -o frame8.png --frames 8 --scale 0.5"""


def frame_range(text: str) -> tuple[int, int | None]:
    """argparse type: A:B, A: or A (frames A to B, 1-based, inclusive)."""
    first, sep, last = text.partition(":")
    try:
        a = int(first) if first.strip() else 1
        b = int(last) if last.strip() else None
        if not sep:
            b = a
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a frame range; write A:B, e.g. "
                                         f"1:100") from None
    if a < 1 or (b is not None and b < a):
        raise argparse.ArgumentTypeError(f"{text!r}: frames start at 1 and B must be >= A")
    return a, b


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="DET_OR_RESULT",
                        help="MOTChallenge detection file (tracked first) or result file")
    frames = parser.add_mutually_exclusive_group(required=True)
    frames.add_argument("--images", metavar="DIR", help="folder of the frames as pictures")
    frames.add_argument("--video", metavar="FILE", help="video file of the frames")
    parser.add_argument("-o", "--output", metavar="OUT", required=True,
                        help="video file (.mp4, .gif, ...), picture (.png, .jpg) or folder to "
                             "write the frames to")
    parser.add_argument("--frames", type=frame_range, metavar="A:B", default=(1, None),
                        help="render only frames A to B (default: all)")
    parser.add_argument("--scale", type=positive_float, metavar="F", default=1.0,
                        help="resize the frames by F (default 1)")
    parser.add_argument("--trail", type=whole_number(0), metavar="N", default=30,
                        help="trail through each track's last N boxes (default 30; 0: none)")
    parser.add_argument("--fps", type=positive_float, metavar="HZ", default=None,
                        help="frame rate (default: seqinfo.ini, the video's, or 30 for the "
                             "output of a result file)")
    parser.add_argument("--occlusion", choices=OCCLUSION_NAMES, default=None,
                        help="occlusion model when tracking a detection file")
    parser.add_argument("--config", metavar="FILE",
                        help="TOML file of tracker settings, when tracking a detection file")
    parser.add_argument("--score-range", type=score_range, metavar="LO,HI",
                        help="map a detection file's raw scores LO..HI onto 0..1")
    parser.add_argument("--lenient", action="store_true",
                        help="skip bad detection rows and clip scores instead of stopping")
    parser.add_argument("--force", action="store_true", help="replace OUT if it exists")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def _overlay(args: argparse.Namespace, image_size: tuple[int, int], video_fps: float | None,
             last_frame: int | None):
    """The boxes to draw, the frame rate to write at, and what they came from."""
    import numpy as np

    from occtrack.io.mot import find_seqinfo, read_detections, read_mot, read_seqinfo
    from occtrack.viz.render import Overlay

    table = read_mot(args.source, "det")
    seq = find_seqinfo(args.source)
    seq_fps = float(read_seqinfo(seq)["fps"]) if seq is not None else None
    if len(table) and (table.id >= 0).any():
        if (table.id < 0).any():
            raise OcctrackError("has rows with id -1 and rows with track ids: give a detection "
                                "file (every id -1) or a result file (track ids)", args.source)
        fps = args.fps or video_fps or seq_fps or 30.0
        none = np.zeros(len(table), dtype=bool)
        return Overlay(table.frame, table.id, table.box, none, none), fps, "result file"

    from occtrack.cli.track import build_config
    from occtrack.tracker import Tracker

    track_args = argparse.Namespace(
        detections=args.source, config=args.config, image_size=tuple(map(float, image_size)),
        fps=args.fps or (video_fps if seq_fps is None else None), occlusion=args.occlusion,
        frame_step=None, format="mot")
    config, length = build_config(track_args)
    detections, warning = read_detections(args.source, config.image_size,
                                          score_range=args.score_range, lenient=args.lenient)
    if warning:
        print(f"occtrack render: warning: {warning}", file=sys.stderr)
    frames = max(length or 0, detections.num_frames)
    if last_frame is not None:
        frames = min(frames, last_frame)
    result = Tracker(config).run(detections, frames, quiet=args.quiet,
                                 desc=f"tracking ({config.occlusion})")
    overlay = Overlay(result.frame, result.id, result.box, result.coasting, result.occluded)
    return overlay, args.fps or video_fps or config.fps, f"tracked ({config.occlusion})"


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from occtrack.extras import require
    from occtrack.io.atomic import atomic_path, check_output
    from occtrack.progress import progress
    from occtrack.viz import render as rv

    require("imageio", "occtrack render")
    require("PIL", "occtrack render")
    first, last = args.frames
    to_file = rv.is_video_path(args.output) or rv.is_picture_path(args.output)
    inputs = (args.source, args.video, args.config)
    if to_file:
        check_output(args.output, args.force, inputs)
    elif Path(args.output).exists() and not args.force:
        raise OcctrackError("exists already; pass --force to replace it", args.output)

    start = time.perf_counter()
    if args.images is not None:
        files = rv.image_files(args.images)
        last_image = files[-1][0] if last is None else min(last, files[-1][0])
        wanted = [(n, p) for n, p in files if first <= n <= last_image]
        if not wanted:
            raise OcctrackError(f"no pictures for frames {first} to {last_image}", args.images)
        size = rv.read_image(wanted[0][1]).shape[1::-1]
        overlay, fps, origin = _overlay(args, size, None, last_image)
        frames = ((n, rv.read_image(p)) for n, p in wanted)
        total = len(wanted)
        suffix = wanted[0][1].suffix.lower()
    else:
        size, meta = rv.first_frame_size(None, args.video)
        video_fps = float(meta["fps"]) if meta.get("fps") else None
        overlay, fps, origin = _overlay(args, size, video_fps, last)
        frames, _ = rv.video_frames(args.video)
        total = None
        suffix = ".jpg"
    frames = progress(frames, total, "rendering", args.quiet)

    if to_file:
        with atomic_path(args.output, args.force) as tmp:
            writer = (rv.VideoWriter(tmp, fps) if rv.is_video_path(args.output)
                      else rv.PictureWriter(tmp))
            count = rv.render(overlay, frames, writer, args.trail, first, last, args.scale)
    else:
        writer = rv.FolderWriter(args.output, args.force,
                                 ".png" if suffix in (".png", ".bmp", ".tif", ".tiff") else ".jpg")
        count = rv.render(overlay, frames, writer, args.trail, first, last, args.scale)
    if not args.quiet:
        shown = overlay.frame >= first
        if last is not None:
            shown &= overlay.frame <= last
        tracks = len(np.unique(overlay.id[shown]))
        print(f"rendered {count} frame{'s' * (count != 1)} with {tracks} tracks ({origin}) "
              f"to {args.output}, "
              f"{time.perf_counter() - start:.1f} s")
    return 0
