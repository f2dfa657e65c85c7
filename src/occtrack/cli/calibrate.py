"""`occtrack calibrate GT DET [GT DET ...] -o detector.toml`: the tracker's detector model
measured on labelled sequences."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from occtrack.errors import OcctrackError

NAME = "calibrate"
HELP = "estimate the tracker's detector model (P_D, clutter, edge noise) from labelled data"
DESCRIPTION = """\
Match each detection file to its ground truth (per frame, Hungarian on IoU >= 0.5, against the
pedestrians and the distractor classes as TrackEval does) and measure the detector as the
tracker models it: detection probability against visibility and box height (and the memory
of detection from frame to frame), false detections per frame against the score, and the
noise of each box edge relative to the box height, each with a 95 % interval that allows for
the runs in a person's detections and the bursts of false boxes (cluster bootstrap over people
and over one-second blocks of frames). Several GT DET pairs are pooled.

-o writes a TOML file of TrackerConfig fields only (detectability, detectability_ratio,
clutter_rate, clutter_score_power, edge_noise) that `occtrack track --config` and a sweep's
[work] config load; each setting's interval and every measurement are TOML comments. With
--occlusion none the detectability is that of tracked pedestrians, P(detected | detected
within the last 0.67 s, a tracker's coasting horizon): no occlusion model explains the
misses behind others, and the people the tracker does not hold are misses it never weighs;
else that of visible ones (visibility >= 0.75). The detectability chain's memory
(detectability_ratio) is that of tracked people for every model: the chain carries the runs
of misses a model does not explain (behind others for none; behind what the box geometry
does not see for an occlusion model). The report is printed too (--quiet: not).

The image size and frame rate come from seqinfo.ini when GT sits at SEQ/gt/gt.txt, else from
--image-size and --fps. Ground truth with class and visibility columns (MOT17's 9 columns)
gives every statistic; without them every row is a person in full view.

examples:
  occtrack calibrate $OCCTRACK_DATA/MOT17-04-FRCNN/gt/gt.txt \\
      $OCCTRACK_DATA/MOT17-04-FRCNN/det/det.txt -o detector.toml
  occtrack track $OCCTRACK_DATA/MOT17-11-FRCNN/det/det.txt --config detector.toml -o out.txt"""


def configure(parser: argparse.ArgumentParser) -> None:
    from occtrack.cli.arguments import frame_rate, seed_int
    from occtrack.cli.track import image_size

    parser.add_argument("files", metavar="GT DET", nargs="+", type=Path,
                        help="pairs of ground-truth and detection files")
    parser.add_argument("-o", "--output", metavar="TOML", type=Path,
                        help="write the tracker settings (TOML) here ('-': standard output)")
    parser.add_argument("--occlusion", choices=("none", "object-wise", "measurement-wise"),
                        default="object-wise",
                        help="the occlusion model the settings are for (default "
                             "object-wise, the tracker's): decides which detectability is "
                             "written")
    parser.add_argument("--image-size", type=image_size, metavar="WxH",
                        help="image size where there is no seqinfo.ini")
    parser.add_argument("--fps", type=frame_rate, help="frame rate where there is no "
                                                           "seqinfo.ini")
    parser.add_argument("--seed", type=seed_int, default=0,
                        help="seed of the bootstrap (default 0)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing TOML")
    parser.add_argument("--quiet", action="store_true", help="print no report")


def run(args: argparse.Namespace) -> int:
    from occtrack.config.arguments import DAY_AT_30_FPS
    from occtrack.io.atomic import atomic_write, check_output
    from occtrack.io.mot import check_gaps, find_seqinfo, read_mot, read_seqinfo
    from occtrack.models.calibration import Labelled, calibrate, report_lines, to_toml

    if len(args.files) % 2:
        raise OcctrackError("give ground truth and detections in pairs: GT DET [GT DET ...]")
    if args.output is not None:
        check_output(args.output, args.force, args.files)
    from occtrack.cli.arguments import existing_file

    for path, expected in zip(args.files, ("a ground-truth file", "a detection file") *
                              (len(args.files) // 2), strict=True):
        existing_file(path, expected)
    sequences = []
    for gt_path, det_path in zip(args.files[::2], args.files[1::2], strict=True):
        folder = find_seqinfo(gt_path)
        info = read_seqinfo(folder) if folder is not None else {}
        size = args.image_size or ((info["width"], info["height"]) if info else None)
        fps = args.fps or info.get("fps")
        if size is None or fps is None:
            raise OcctrackError("the image size and frame rate are unknown: no seqinfo.ini "
                                "in the sequence folder; pass --image-size WxH and --fps F",
                                str(gt_path))
        gt = read_mot(gt_path, "gt")
        det = read_mot(det_path, "det")
        frames = int(info.get("length") or max(gt.num_frames, det.num_frames))
        for table, what in ((gt, "ground truth"), (det, "detections")):
            if table.num_frames > frames:
                raise OcctrackError(f"{what} reach frame {table.num_frames} but seqinfo.ini "
                                    f"says the sequence has {frames} frames", table.path)
        # Every frame is counted (a rate is per frame) and walked, so a stray frame number
        # or a seqinfo.ini of 10^8 frames is refused, as `occtrack track` refuses it.
        later = det if det.num_frames >= gt.num_frames else gt
        for table in (gt, det):
            check_gaps(table, DAY_AT_30_FPS, frames if table is later else None, flag=None)
        name = str(info.get("name") or Path(gt_path).resolve().parent.parent.name)
        sequences.append(Labelled(name, gt, det, (float(size[0]), float(size[1])),
                                  float(fps), frames))
    cal = calibrate(sequences, seed=args.seed)
    if args.output is not None:
        command = "occtrack calibrate " + " ".join(shlex.quote(str(f)) for f in args.files)
        text = to_toml(cal, occlusion=args.occlusion != "none", command=command)
        with atomic_write(args.output, overwrite=args.force) as fh:
            fh.write(text)
    if not args.quiet:
        out = sys.stderr if str(args.output) == "-" else sys.stdout
        print("\n".join(report_lines(cal)), file=out)
        settings = cal.settings(args.occlusion != "none")
        print("\ntracker settings: " + ", ".join(f"{k} = {v:.4g}" for k, v in settings.items())
              + (f" (written to {args.output})" if args.output not in (None, Path("-"))
                 else ""), file=out)
    return 0
