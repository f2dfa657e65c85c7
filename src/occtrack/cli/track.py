"""`occtrack track DET_FILE -o RESULT_FILE`: the box tracker on a MOTChallenge detection file."""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

from occtrack.cli.arguments import positive_int
from occtrack.errors import OcctrackError
from occtrack.io.mot import find_seqinfo, read_mot, read_seqinfo, write_mot
from occtrack.progress import summary
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig
from occtrack.tracker.config import load_toml

NAME = "track"
HELP = "track the boxes of a MOTChallenge detection file (PMB tracker with occlusion)"
DESCRIPTION = """\
Track pedestrians (or any boxes) through a MOTChallenge detection file with the
Gaussian-mixture Poisson multi-Bernoulli tracker, and write a MOTChallenge result file
(frame,id,left,top,width,height,existence,-1,-1,-1), one row per reported object and frame.

Detection rows are frame,id,left,top,width,height,score[,...] (the id is ignored). Occlusion:
  none              a missed detection is evidence that the object is gone
  object-wise       objects hide objects (expected-value approximation)
  measurement-wise  detections hide detections, as a detector's non-maximum suppression does

The image size comes from --image-size, else from seqinfo.ini when the file sits in a
MOTChallenge sequence folder (SEQ/det/det.txt), else from the --config file; so does the frame
rate (default 30). Every --frame-step-th frame is tracked (default 2, as in the paper); the
frames between are reported with the tracks carried along their velocities.

--config takes a TOML file of TrackerConfig settings (see occtrack.tracker.config), e.g.
  occlusion = "object-wise"
  edge_std = 10.0
Flags given on the command line win over the file."""


def image_size(text: str) -> tuple[float, float]:
    """argparse type: WxH in pixels."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*[xX,]\s*(\d+(?:\.\d*)?)\s*", text)
    if not match or float(match[1]) <= 0 or float(match[2]) <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not an image size; write WxH, "
                                         f"e.g. 1920x1080")
    return float(match[1]), float(match[2])


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("detections", metavar="DET_FILE", help="MOTChallenge detection file")
    parser.add_argument("-o", "--output", metavar="RESULT_FILE", required=True,
                        help="where to write the MOTChallenge result file")
    parser.add_argument("--occlusion", choices=OCCLUSION_NAMES, default=None,
                        help="occlusion model (default: measurement-wise, or the config "
                             "file's)")
    parser.add_argument("--config", metavar="FILE", help="TOML file of tracker settings")
    parser.add_argument("--frame-step", type=positive_int, metavar="N", default=None,
                        help="track every N-th frame (default 2, or the config file's)")
    parser.add_argument("--image-size", type=image_size, metavar="WxH", default=None,
                        help="image size in pixels (default: from seqinfo.ini)")
    parser.add_argument("--force", action="store_true", help="overwrite RESULT_FILE")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def build_config(args: argparse.Namespace) -> tuple[TrackerConfig, int | None]:
    """The tracker settings and the sequence length (None if unknown) from the flags, the
    sequence's seqinfo.ini and the config file."""
    values: dict = {}
    source = "command line"
    if args.config:
        source = args.config
        values = load_toml(args.config)
    length = None
    seq = find_seqinfo(args.detections)
    if seq is not None:
        info = read_seqinfo(seq)
        length = int(info["length"])
        if args.image_size is None:
            values["image_size"] = (info["width"], info["height"])
        values["fps"] = float(info["fps"])
    if args.image_size is not None:
        values["image_size"] = args.image_size
    if "image_size" not in values:
        raise OcctrackError("image size unknown: pass --image-size WxH (no seqinfo.ini beside "
                            "the detection folder, no image_size in a --config file)",
                            args.detections)
    if args.occlusion is not None:
        values["occlusion"] = args.occlusion
    if args.frame_step is not None:
        values["frame_step"] = args.frame_step
    return TrackerConfig.from_dict(values, source), length


def run(args: argparse.Namespace) -> int:
    config, length = build_config(args)
    out = Path(args.output)
    if out.exists() and not args.force:
        raise OcctrackError("exists already; pass --force to overwrite it", str(out))
    if not out.parent.is_dir():
        raise OcctrackError("folder does not exist", str(out.parent))
    detections = read_mot(args.detections, "det")
    frames = max(length or 0, detections.num_frames)
    start = time.perf_counter()
    result = Tracker(config).run(detections, frames, quiet=args.quiet,
                                 desc=f"tracking ({config.occlusion})")
    write_mot(out, result.frame, result.id, result.box, result.existence, overwrite=args.force)
    if not args.quiet:
        print(summary(result.frames, result.num_tracks, time.perf_counter() - start))
    return 0
