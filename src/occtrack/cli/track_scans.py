"""`occtrack track-scans SCANS -o TRACKS`: the lidar scan tracker on a scan file or a ROS bag."""

from __future__ import annotations

import argparse
import sys
import time

from occtrack.errors import OcctrackError

SCAN_OCCLUSION_NAMES = ("none", "measurement-wise")
SCAN_LIKELIHOOD_NAMES = ("derived", "hand-made", "cluster")
"""`occtrack.config.scan`'s names, repeated so that `--help` loads no tracker (a test keeps
them equal)."""
BAG_STAMPS = ("record", "header")  # occtrack.io.rosbag.STAMPS
BAG_OPTIONS = ("topic", "fixed_frame", "stamps")

NAME = "track-scans"
HELP = "track people through a 2-D lidar scan file or ROS bag (PMB tracker with occlusion)"
DESCRIPTION = """\
Track people (discs) through a 2-D lidar scan file with the scan tracker (the box tracker's
Poisson multi-Bernoulli filter fed whole scans, occtrack.tracker.ScanTracker), and write a
tracks file, one row a reported object a scan, in the world frame:

  time,id,x,y,vx,vy,existence,confidence,occluded

time s, id an integer kept by the object, position m, velocity m/s, existence the probability
that the object is there, confidence the probability that it is there and its true centre
within one radius of the reported one (<= existence), occluded 1 when the object was missed
this scan and is more likely hidden than gone (never under occlusion none).

SCANS is the format occtrack simulate lidar writes (occtrack.io.scans): one row a beam,
time,angle,range: seconds, radians counter-clockwise from the sensor's heading, metres, inf
where the beam returned nothing; the beams of a scan share its time and come in increasing
angle; # lines are comments. Beams a scan and the scan rate come from the file (the rate
from the median time between scans). A malformed row stops the run with the file and line.

SCANS may also be a ROS bag (needs the ros extra: pip install "occtrack[ros]"): a ROS 1 .bag
file, a ROS 2 bag folder (holding metadata.yaml), or its .db3 or .mcap file. Its
sensor_msgs/LaserScan messages are the scans (among several, /scan, ROS's conventional name
for a robot's laser; --topic chooses another): beam k at angle_min + k angle_increment
(reversed when angle_increment < 0), ranges as sent, inf for no return. A reading REP 117
calls invalid (nan, -inf, or outside [range_min, range_max]) says nothing about its beam and
is left out of its scan, with a warning giving the count. A scan's time is the bag's record
time, the clock the benchmark annotations of recorded bags use (a header stamp may come from
another machine's clock); --stamps header takes header.stamp. The sensor's range_max is the
tracker's max_range unless the --config file sets max_range.
The tracks are in the scanner's frame (header.frame_id), unless --fixed-frame FRAME gives
the sensor's pose a scan in FRAME from the bag's /tf and /tf_static transforms (or a
nav_msgs/Odometry topic), interpolated to each scan's time.

The sensor stands at the origin heading along +x unless --poses gives its pose a scan, a
time,x,y,heading file with one row a scan at the scans' times (occtrack simulate lidar writes
one, sensor.csv, beside scans.csv; it is used only when given). A beam's world angle is then
its angle plus the heading, from the pose's x, y.

Occlusion:
  none              a missed person is evidence that the person is gone
  measurement-wise  a nearer return hides a person (paper section V; the default)
Likelihood: derived (the default; the beams of a segment jointly and the closed-form term on
the person's other beams), hand-made (the fixed shape of the separable-likelihood trackers),
cluster (each segment's fitted centre tracked as a point; goes with --occlusion none).

--config takes a TOML file whose [scan] table holds ScanTrackerConfig settings (see
occtrack.config.scan; the sensor's p_d, range_noise, clutter_per_scan and max_range, the
people's radius, ...), e.g.
  [scan]
  occlusion = "measurement-wise"
  max_range = 30.0
Flags given on the command line win over the file; an unknown table or setting stops the run.
Beneath the file and the flags, the recording says what it can: a file occtrack simulate
lidar wrote gives its sensor and its people, discs (body = "disc", radius its person_radius);
any other recording is a real laser at leg height, whose people are pairs of legs (body =
"legs": each leg tracked as a disc of leg_radius 0.1 m, the legs paired into people reported
at their midpoint, occtrack.tracker.people), and a bag gives its range_max. The other
defaults are the simulated sensor's (20 m range, 2 cm range noise, 5 clutter returns a scan,
P_D 0.98). A return at or beyond max_range counts as no return, with a warning giving the
count. Nothing is reported outside the field of view (the beams' span and range): a track
whose centre leaves it is dropped as a box leaving an image is.

The tracks file is written whole or not at all: to a temporary file beside it, renamed into
place when complete, so an interrupted run leaves the old file (or none); an existing file
is refused unless --force. -o - writes the tracks to standard output (the summary then goes
to standard error). One input gives the same file byte for byte."""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scans", metavar="SCANS",
                        help="lidar scan file (time,angle,range rows; occtrack simulate "
                             "lidar's scans.csv), or a ROS bag: a .bag file, a ROS 2 bag "
                             "folder, a .db3 or .mcap file")
    parser.add_argument("-o", "--output", metavar="TRACKS", required=True,
                        help="where to write the tracks file ('-': standard output)")
    parser.add_argument("--poses", metavar="FILE",
                        help="the sensor's pose a scan, time,x,y,heading rows (occtrack "
                             "simulate lidar writes one: sensor.csv); default: at the origin, "
                             "heading 0")
    parser.add_argument("--topic", metavar="TOPIC",
                        help="with a bag: its sensor_msgs/LaserScan topic (default: its only "
                             "one, or /scan among several)")
    parser.add_argument("--fixed-frame", metavar="FRAME",
                        help="with a bag: the world frame; the sensor's pose a scan comes from "
                             "the bag's /tf, /tf_static or odometry (default: tracks in the "
                             "scanner's frame)")
    parser.add_argument("--stamps", choices=BAG_STAMPS, default=None,
                        help="with a bag: a scan's time, the bag's record time or the "
                             "message's header stamp (default: record)")
    parser.add_argument("--ego-motion", choices=("none", "scan-matching"), default="none",
                        help="without poses: none (the sensor taken as still; the default) or "
                             "scan-matching (the sensor's motion estimated from the scans, "
                             "occtrack.models.scan_matching; the tracks then in the first "
                             "scan's frame)")
    parser.add_argument("--occlusion", choices=SCAN_OCCLUSION_NAMES, default=None,
                        help="occlusion model (default: measurement-wise, or the config "
                             "file's)")
    parser.add_argument("--likelihood", choices=SCAN_LIKELIHOOD_NAMES, default=None,
                        help="scan likelihood (default: derived, or the config file's)")
    parser.add_argument("--config", metavar="FILE",
                        help="TOML file with a [scan] table of scan tracker settings")
    parser.add_argument("--force", action="store_true", help="overwrite TRACKS")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def build_config(args: argparse.Namespace, defaults: dict | None = None):
    """The tracker settings (a ScanTrackerConfig) from the config file's [scan] table and the
    flags; `defaults` (a bag's max_range) beneath both."""
    from occtrack.config import load_toml
    from occtrack.config.scan import ScanTrackerConfig, scan_table

    values: dict = dict(defaults or {})
    source = "command line"
    if args.config:
        source = args.config
        values.update(scan_table(load_toml(args.config), source))
    if args.occlusion is not None:
        values["occlusion"] = args.occlusion
    if args.likelihood is not None:
        values["likelihood"] = args.likelihood
    if values.get("likelihood") == "cluster" and "occlusion" not in values:
        raise OcctrackError("likelihood cluster (points, no beams) goes with occlusion none; "
                            "pass --occlusion none", source)
    return ScanTrackerConfig.from_dict(values, source)


SIMULATED = {"person_radius": "radius", "max_range": "max_range", "p_d": "p_d",
             "range_noise": "range_noise", "clutter_per_scan": "clutter_per_scan"}
"""The settings `occtrack simulate lidar` writes in a scan file's comments, and the tracker
settings they give."""


def recording_defaults(scans, info) -> dict:
    """What the recording says of its sensor, beneath the --config file and the flags: a
    simulated scan file's sensor and its people, discs of person_radius (`occtrack simulate
    lidar` writes them in its comments); anything else is a real laser at leg height, whose
    people are pairs of legs (body "legs"), and a bag gives its range_max."""
    if info is not None:
        legs = {"body": "legs"}
        return {**legs, "max_range": info.range_max} if 0 < info.range_max <= 100_000 else legs
    if "person_radius" not in scans.settings:
        return {"body": "legs"}
    out: dict = {"body": "disc"}
    for key, name in SIMULATED.items():
        if key in scans.settings:
            try:
                out[name] = float(scans.settings[key])
            except ValueError:
                raise OcctrackError(f"the comment's {key}={scans.settings[key]} is not a "
                                    f"number", scans.path) from None
    return out


def matched_poses(args: argparse.Namespace, scans, poses):
    """The sensor's poses a scan estimated by scan matching (`--ego-motion scan-matching`),
    with a note of how many scans matched (the rest took the constant-velocity guess)."""
    import numpy as np

    from occtrack.models.scan_matching import ScanMatcher

    if poses is not None:
        raise OcctrackError("--ego-motion scan-matching estimates the poses that --poses or "
                            "--fixed-frame give; pass one of them")
    matcher = ScanMatcher()
    out, matched = [], 0
    for _, angles, ranges in scans:
        out.append(matcher.update(angles, ranges))
        matched += matcher.status == "matched"
    print(f"occtrack track-scans: note: scan matching matched {matched} of {len(scans)} scans; "
          f"the others took the constant-velocity guess", file=sys.stderr)
    return np.array(out, dtype=float).reshape(-1, 3)


def world_scans(scans, poses):
    """(time, world angles, ranges, sensor x, y) a scan; `poses` (S, 3) or None: the sensor at
    the origin, heading 0."""
    for i, (t, angle, ranges) in enumerate(scans):
        if poses is None:
            yield t, angle, ranges
        else:
            yield t, poses[i, 2] + angle, ranges, poses[i, :2]


def read_input(args: argparse.Namespace):
    """(the scans, poses or None, what a bag held or None): a scan file's, checked beam by
    beam, or a bag's (`occtrack.io.rosbag.BagScans`), with poses when --fixed-frame is given."""
    from occtrack.io.rosbag import is_bag, read_bag_scans
    from occtrack.io.scans import check_beam_order, read_scans

    if is_bag(args.scans):
        if args.poses is not None and args.fixed_frame is not None:
            raise OcctrackError("--poses and --fixed-frame both give the sensor's pose; pass "
                                "one of them")
        return read_bag_scans(args.scans, args.topic, args.fixed_frame,
                              args.stamps or "record")
    given = [f"--{name.replace('_', '-')}" for name in BAG_OPTIONS
             if getattr(args, name) is not None]
    if given:
        raise OcctrackError(f"{' and '.join(given)} go{'es' if len(given) == 1 else ''} with a "
                            f"ROS bag (.bag, a ROS 2 bag folder, .db3, .mcap), and SCANS is a "
                            f"scan file", args.scans)
    scans = read_scans(args.scans)
    check_beam_order(scans)
    return scans, None, None


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from occtrack.io.atomic import check_output
    from occtrack.io.scans import match_poses, read_poses, write_tracks
    from occtrack.progress import progress, summary
    from occtrack.tracker import ScanTracker

    check_output(args.output, args.force, (args.scans, args.config, args.poses))
    config = build_config(args)
    scans, poses, info = read_input(args)
    config = build_config(args, recording_defaults(scans, info))
    if info is not None:
        if args.topic is None and len(info.laser_topics) > 1:
            print(f"occtrack track-scans: note: {args.scans} has {len(info.laser_topics)} "
                  f"LaserScan topics ({', '.join(info.laser_topics)}); reading {info.topic}, "
                  f"ROS's conventional laser topic (--topic chooses another)", file=sys.stderr)
        if info.invalid:
            print(f"occtrack track-scans: warning: {args.scans}: {info.invalid} of "
                  f"{info.scans * info.beams} readings of {info.topic} are invalid (nan, -inf "
                  f"or outside [range_min, range_max], REP 117) and are left out",
                  file=sys.stderr)
    if args.poses is not None:
        times, poses = read_poses(args.poses)
        match_poses(scans, args.poses, times)
    if args.ego_motion == "scan-matching":
        poses = matched_poses(args, scans, poses)
    if len(scans) == 0:
        print(f"occtrack track-scans: warning: {args.scans} holds no scans, so the result has "
              f"no tracks", file=sys.stderr)
    far = np.isfinite(scans.range) & (scans.range >= config.max_range)
    if far.any():
        print(f"occtrack track-scans: warning: {args.scans}: {int(far.sum())} returns at or "
              f"beyond max_range ({config.max_range:g} m) count as no return; set max_range "
              f"in the --config file's [scan] table to the sensor's range", file=sys.stderr)
    beams = int(np.median(np.diff(scans.start))) if len(scans) else 1
    # The rate sets only the time step before the first scan (births are per scan), so a
    # file of one scan, which has no step to infer it from, takes the tracker's default.
    rate = 1.0 / float(np.median(np.diff(scans.time))) if len(scans) > 1 else 10.0
    origin = (0.0, 0.0) if poses is None or len(poses) == 0 else tuple(poses[0, :2])
    tracker = ScanTracker(config, beams=beams, rate=rate, origin=origin)
    start = time.perf_counter()
    result = tracker.run(progress(world_scans(scans, poses), total=len(scans),
                                  desc=f"tracking ({config.occlusion})", quiet=args.quiet))
    seconds = time.perf_counter() - start
    write_tracks(args.output, result, overwrite=args.force)
    if not args.quiet:
        print(summary(len(scans), len(np.unique(result.id)), seconds, what="scans"),
              file=sys.stderr if args.output == "-" else sys.stdout)
    return 0
