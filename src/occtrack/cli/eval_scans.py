"""`occtrack eval-scans GT TRACKS`: the leg-tracker benchmark's CLEAR MOT of a tracks file."""

from __future__ import annotations

import argparse
import json
import sys

from occtrack.errors import OcctrackError

NAME = "eval-scans"
HELP = "score a tracks file against the leg-tracker benchmark's people (CLEAR MOT, 0.75 m)"
DESCRIPTION = """\
Score a tracks file (occtrack track-scans' output) against the annotated people of the
leg-tracker benchmark (Leigh, Pineau, Olmedo and Zhang, ICRA 2015) by the benchmark's own
rules (its clear_mot.py; occtrack.metrics.leg_benchmark):

- each annotated position is scored against the tracks of the last scan at or before its
  time (a scan is a time of TRACKS, or of --scans); positions before every scan are misses;
- a track and a person match when closer than --threshold (0.75 m); last scan's matches are
  kept while they hold, the rest assigned by least total distance (Hungarian), then gated;
- an ID switch: a track matched to another person than last time, or a person matched to a
  new track; valid matches + ID switches + misses = the annotated positions;
- MOTP: the mean distance of all matches (m); MOTA = 1 - (misses + switches + false
  positives) / positions. The benchmark ignores false positives on person_following_outdoor_1
  (only the followed person is annotated): the MOTA-FP column. False positives are the
  tracks that match nobody on annotated scans.

GT is the benchmark's ground_truth_people_tracks.csv: bag_time,id,x,y,z rows (the bag's
record time, s; metres in the laser's frame). TRACKS is time,id,x,y,vx,vy,existence,
confidence,occluded rows, in the same frame. A malformed row stops the run with the file and
line.

A tracks file has no row for a scan where nothing was reported, so such a scan is not one of
its times, and a position annotated then would be scored against the scan before it (a
warning counts the gaps longer than 1.5 scan periods). --scans SCANS, the scan file the
tracks came from (time,angle,range rows, or the ROS bag), adds every scan, empty or not.

Prints a table (valid, ID sw, misses, FP, MOTP m, MOTA, MOTA-FP, tracks/scan, FP/scan) and a
one-line summary. --json FILE writes the scores as one JSON object (replaced atomically; an
existing file is refused without --force; --json - prints it instead of the table):
  {"gt", "tracks", "threshold", "scans", "all_scans", "truth", "early", "duplicates",
   "valid", "id_switches", "misses", "false_positives", "false_positives_all_scans",
   "track_rows", "motp", "mota", "mota_without_fp", "tracks_per_scan",
   "false_tracks_per_scan"}
ratios as fractions (null where undefined), motp in metres.

Example (published on person_following_outdoor_1, valid / ID switches / misses, MOTP:
leg_tracker "Joint Leg" 6,073 / 21 / 104, 0.09 m):
  occtrack eval-scans person_following_outdoor_1/ground_truth_people_tracks.csv tracks.csv"""


def _threshold(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number of metres: {text!r}")
    return value


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("gt", metavar="GT",
                        help="the benchmark's annotated people (bag_time,id,x,y,z rows)")
    parser.add_argument("tracks", metavar="TRACKS",
                        help="tracks file (occtrack track-scans' output)")
    parser.add_argument("--scans", metavar="SCANS",
                        help="the scan file or ROS bag the tracks came from, so that scans "
                             "with no reported object count (default: the tracks file's "
                             "times)")
    parser.add_argument("--threshold", type=_threshold, default=0.75, metavar="M",
                        help="a track matches a person closer than this (default: 0.75 m, "
                             "the benchmark's)")
    parser.add_argument("--json", metavar="FILE",
                        help="write the scores as JSON to FILE (- prints them instead of the "
                             "table)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing JSON file")
    parser.add_argument("--quiet", action="store_true", help="no summary or warning")


def _warn(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        print(f"occtrack eval-scans: warning: {text}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from occtrack.io.atomic import atomic_write, check_output
    from occtrack.io.scans import read_people, read_scans, read_tracks
    from occtrack.metrics import leg_benchmark

    if args.json is not None:
        check_output(args.json, args.force, (args.gt, args.tracks, args.scans))
    people = read_people(args.gt)
    tracks = read_tracks(args.tracks)
    scan_time = None
    if args.scans is not None:
        from occtrack.io.rosbag import is_bag, read_bag_scans

        scan_time = (read_bag_scans(args.scans)[0] if is_bag(args.scans)
                     else read_scans(args.scans)).time
        stray = np.setdiff1d(np.round(tracks.time, 6), np.round(scan_time, 6))
        if len(stray):
            raise OcctrackError(f"time {stray[0]:.6f} is no scan's time in {args.scans} "
                                f"({len(stray)} such times): give the scan file the tracks "
                                f"came from", args.tracks)
    if len(people) == 0:
        _warn(args, f"{args.gt} holds no annotated position: nothing to score")
    if len(tracks) == 0:
        _warn(args, f"{args.tracks} holds no reported object: every position is a miss")
    times = np.unique(tracks.time)
    if scan_time is None and len(times) > 2:
        step = np.diff(times)
        gaps = int(np.sum(step > 1.5 * np.median(step)))
        if gaps:
            _warn(args, f"{args.tracks}: {gaps} gaps longer than 1.5 scan periods; a scan with "
                        f"no reported object has no row, and positions annotated then are "
                        f"scored against the scan before; pass --scans SCANS to count it")
    scores = leg_benchmark.score(people.time, people.id, people.position, tracks.time,
                                 tracks.id, tracks.position, args.threshold, scan_time)
    if scores.early:
        first = np.r_[times, [] if scan_time is None else scan_time]
        when = f"the first scan ({first.min():.6f})" if len(first) else "any scan (none)"
        _warn(args, f"{args.gt}: {scores.early} positions come before {when} and count as "
                    f"misses")
    report = {"gt": str(args.gt), "tracks": str(args.tracks), **scores.as_dict()}
    text = json.dumps(report, indent=1, allow_nan=False) + "\n"
    if args.json is not None:  # (atomic_write takes "-" for standard output)
        with atomic_write(args.json, args.force) as fh:
            fh.write(text)
    if args.json != "-":
        print(leg_benchmark.table(scores, name=str(args.tracks)))
    if not args.quiet:
        print(leg_benchmark.summary(scores), file=sys.stderr if args.json == "-" else sys.stdout)
    return 0
