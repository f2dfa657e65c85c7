"""The laser scans of a ROS 1 or ROS 2 bag as a scan file's arrays (`occtrack.io.scans.Scans`),
and the sensor's pose a scan from the bag's transforms (issue 41, item 1).

A bag is a ROS 1 `.bag` file, a ROS 2 bag folder (holding metadata.yaml), or one of a ROS 2
bag's `.db3` / `.mcap` files (the folder around it is read when it holds metadata.yaml). The
`rosbags` package reads them all, pure Python, with the message definitions the bag carries
(the optional `ros` extra: `pip install "occtrack[ros]"`).

The topic: the one LaserScan topic of the bag or, among several, `/scan`, the name ROS's
laser drivers and its navigation, mapping and leg-tracking nodes take by default (a robot's
main laser); with several and no `/scan`, the caller must choose.

One sensor_msgs/msg/LaserScan message is one scan: beam k at angle_min + k angle_increment,
its range as sent (float32, widened exactly to float64), the beams in increasing angle (a
scanner turning clockwise, angle_increment < 0, has its beams reversed). REP 117 readings:
`+inf` is no return and stays inf; `nan` (an invalid reading), `-inf` (too close) and a range
outside [range_min, range_max] say nothing about the beam, so the beam is left out of its scan
(the tracker's beam model then takes it as no evidence either way, and the segments close over
it) and counted (`BagScans.invalid`). Read as "no return" instead, an invalid reading is
evidence that nothing stands on the beam: on the leg-tracker benchmark's recording, where an
eighth of the readings are invalid, mostly at the edges of legs, that cut legs into pieces
and ended tracks (178 identity switches of the followed person against 219). Every message of
the topic must have the beams of the first.

A scan's time is, by default, the bag's record time (the recorder's clock when the message
arrived), not its header stamp: annotations of recorded bags, such as the leg-tracker
benchmark's, use the record times and assign each position to the last scan recorded before
it, and a header stamp may come from another machine's clock (on that benchmark's bags it
is some 130 s off). `stamps="header"` takes header.stamp instead. Either clock must not go
backwards from one scan to the next.

Poses (`fixed_frame`): the scanner's frame (the scans' header.frame_id) in `fixed_frame` a
scan, as x, y, heading, from the chain of 2-D transforms (x, y and the yaw of the rotation;
roll and pitch dropped) of the bag's tf2_msgs/msg/TFMessage messages (/tf, /tf_static) and
of nav_msgs/msg/Odometry messages (header.frame_id the parent, child_frame_id the child, used
where no tf message gives that child). Each link is interpolated linearly in time between its
two samples around the scan (the yaw along the shorter way round), and held at its first or
last sample outside them; its time is a message's record time, or its header stamp with
stamps="header", the clock of the scans.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.scans import Scans

LASER_SCAN = "sensor_msgs/msg/LaserScan"
DEFAULT_TOPIC = "/scan"  # ROS's conventional name for a robot's laser
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage")
ODOMETRY = "nav_msgs/msg/Odometry"
STAMPS = ("record", "header")
BAG_SUFFIXES = (".bag", ".db3", ".mcap")
EXPECTED = ("a ROS bag (a ROS 1 .bag file, a ROS 2 bag folder holding metadata.yaml, or its "
            ".db3 or .mcap file)")


@dataclass(frozen=True)
class BagScans:
    """What `read_bag_scans` read: the topic and the scanner's frame, `scans` messages of
    `beams` beams from `angle_min` to `angle_max` (rad, the beams' angles in increasing
    order), the sensor's `range_max` (m, the largest the messages give), the `invalid`
    readings turned into no return, and every LaserScan topic of the bag."""

    topic: str
    frame_id: str
    scans: int
    beams: int
    angle_min: float
    angle_max: float
    range_max: float
    invalid: int
    laser_topics: tuple[str, ...]


def is_bag(path: str | os.PathLike) -> bool:
    """Whether `path` names a bag rather than a scan file: a .bag, .db3 or .mcap name, or a
    folder (a ROS 2 bag; `read_bag_scans` says so if it holds no metadata.yaml)."""
    return Path(path).suffix.lower() in BAG_SUFFIXES or Path(path).is_dir()


def _bag_path(path: str) -> Path:
    """The path to give rosbags, or an OcctrackError saying why `path` is not a bag."""
    p = Path(path)
    if not p.exists():
        raise OcctrackError("no such file", path)
    if p.is_dir():
        if not (p / "metadata.yaml").is_file():
            raise OcctrackError(f"is a folder without metadata.yaml, expected {EXPECTED}", path)
        return p
    suffix = p.suffix.lower()
    if suffix not in BAG_SUFFIXES:
        raise OcctrackError(f"not a bag name, expected {EXPECTED}", path)
    if suffix != ".bag" and (p.parent / "metadata.yaml").is_file():
        return p.parent  # the whole ROS 2 bag: all its files, and its compression
    return p


def _seconds(ns: int) -> float:
    return ns / 1_000_000_000  # int / int: correctly rounded


def _stamp(header) -> float:
    return _seconds(int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec))


def _frame(name: str) -> str:
    return name.lstrip("/")  # ROS 1's tf wrote "/odom" where tf2 writes "odom"


def _yaw(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def read_bag_scans(path: str | os.PathLike, topic: str | None = None,
                   fixed_frame: str | None = None,
                   stamps: str = "record") -> tuple[Scans, np.ndarray | None, BagScans]:
    """The LaserScan messages of `topic` (default: the bag's one LaserScan topic, or
    `DEFAULT_TOPIC` among several) as Scans,
    the sensor's pose a scan in `fixed_frame` ((S, 3) x, y, heading; None without a fixed
    frame), and what was read (see the module docstring). Any problem with the bag, the
    topic, the scans or the transforms is one OcctrackError naming the bag."""
    if stamps not in STAMPS:
        raise ValueError(f"stamps must be one of {', '.join(STAMPS)}, not {stamps!r}")
    name = str(path)
    bag = _bag_path(name)
    try:
        from rosbags.highlevel import AnyReader, AnyReaderError
        from rosbags.rosbag1 import ReaderError as ReaderError1
        from rosbags.rosbag2 import ReaderError as ReaderError2
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise OcctrackError('reading a ROS bag needs the rosbags package, from the optional '
                            '\'ros\' extra: install it with pip install "occtrack[ros]"',
                            name) from None
    try:
        # A ROS 2 bag written without message definitions is read with the latest ROS 2
        # types; a ROS 1 bag always carries its own.
        with AnyReader([bag], default_typestore=get_typestore(Stores.LATEST)) as reader:
            return _read(reader, name, topic, fixed_frame, stamps)
    except (AnyReaderError, ReaderError1, ReaderError2) as err:
        raise OcctrackError(f"not a readable ROS bag: {' '.join(str(err).split())}",
                            name) from None


def _pick_topic(reader, name: str, topic: str | None) -> tuple[str, tuple[str, ...]]:
    lasers = tuple(sorted(t for t, info in reader.topics.items() if info.msgtype == LASER_SCAN))
    if topic is not None:
        if topic not in lasers:
            have = ", ".join(lasers) if lasers else "none"
            raise OcctrackError(f"no LaserScan topic {topic!r}; its LaserScan topics: {have}",
                                name)
        return topic, lasers
    if not lasers:
        found = ", ".join(sorted(reader.topics)) or "none"
        raise OcctrackError(f"no sensor_msgs/LaserScan topic in the bag (its topics: {found})",
                            name)
    if len(lasers) > 1 and DEFAULT_TOPIC in lasers:
        return DEFAULT_TOPIC, lasers
    if len(lasers) > 1:
        raise OcctrackError(f"{len(lasers)} LaserScan topics ({', '.join(lasers)}); pass "
                            f"--topic to choose one", name)
    return lasers[0], lasers


def _read(reader, name: str, topic: str | None, fixed_frame: str | None,
          stamps: str) -> tuple[Scans, np.ndarray | None, BagScans]:
    topic, lasers = _pick_topic(reader, name, topic)
    times: list[float] = []
    rows: list[np.ndarray] = []
    invalid = 0
    first = None
    range_max = -math.inf
    connections = [c for c in reader.connections if c.topic == topic]
    for k, (connection, record, raw) in enumerate(reader.messages(connections)):
        msg = reader.deserialize(raw, connection.msgtype)
        beams = (len(msg.ranges), msg.angle_min, msg.angle_increment)
        if first is None:
            first = msg
            if beams[0] > 1 and not (np.isfinite(beams[2]) and beams[2] != 0):
                raise OcctrackError(f"message 1 of {topic}: angle_increment is {beams[2]}; "
                                    f"a scan's beams must be at different angles", name)
        elif beams != (len(first.ranges), first.angle_min, first.angle_increment):
            raise OcctrackError(
                f"message {k + 1} of {topic} has {beams[0]} beams from {beams[1]:.6g} rad by "
                f"{beams[2]:.6g}, the first {len(first.ranges)} from {first.angle_min:.6g} by "
                f"{first.angle_increment:.6g}: every scan must have the beams of the first",
                name)
        t = _seconds(record) if stamps == "record" else _stamp(msg.header)
        if times and t < times[-1]:
            raise OcctrackError(f"message {k + 1} of {topic}: its {stamps} time {t:.6f} is "
                                f"earlier than the message before ({times[-1]:.6f}); scans "
                                f"must be in time order", name)
        r = np.asarray(msg.ranges, dtype=np.float64)
        bad = np.isnan(r) | (r == -np.inf) | (np.isfinite(r) & ((r < msg.range_min)
                                                                 | (r > msg.range_max)))
        invalid += int(bad.sum())
        rows.append(np.where(bad, np.nan, r))
        times.append(t)
        range_max = max(range_max, float(msg.range_max))
    if first is None:
        info = BagScans(topic, "", 0, 0, math.nan, math.nan, math.nan, 0, lasers)
        empty = np.zeros(0)
        return (Scans(empty, np.zeros(1, np.int64), empty, empty, {"topic": topic}, name),
                None if fixed_frame is None else np.zeros((0, 3)), info)
    n = len(first.ranges)
    angle = float(first.angle_min) + np.arange(n) * float(first.angle_increment)
    ranges = np.array(rows).reshape(len(rows), n)
    if n > 1 and first.angle_increment < 0:  # a clockwise scanner: beams in increasing angle
        angle, ranges = angle[::-1], ranges[:, ::-1]
    frame = _frame(first.header.frame_id)
    time = np.array(times)
    valid = ~np.isnan(ranges)  # an invalid reading is left out: it says nothing of its beam
    start = np.r_[0, np.cumsum(valid.sum(axis=1))].astype(np.int64)
    scans = Scans(time, start, np.broadcast_to(angle, ranges.shape)[valid], ranges[valid],
                  {"topic": topic, "frame_id": frame, "stamps": stamps}, name)
    info = BagScans(topic, frame, len(rows), n, float(angle.min()) if n else math.nan,
                    float(angle.max()) if n else math.nan, range_max, invalid, lasers)
    poses = None
    if fixed_frame is not None:
        poses = _poses(reader, name, _frame(fixed_frame), frame, time, stamps)
    return scans, poses, info


# -- poses ----------------------------------------------------------------------------------------

def _links(reader, name: str, stamps: str) -> tuple[dict[str, str], dict[str, list[tuple]]]:
    """child frame -> parent frame, and child -> its (time, x, y, yaw) samples, from the tf
    messages and then the odometry topics (for children no tf message gives)."""
    parent: dict[str, str] = {}
    samples: dict[str, list[tuple]] = {}
    for kinds in (TF_TYPES, (ODOMETRY,)):
        connections = [c for c in reader.connections if c.msgtype in kinds]
        given = set(parent)
        for connection, record, raw in (reader.messages(connections) if connections else ()):
            msg = reader.deserialize(raw, connection.msgtype)
            if connection.msgtype == ODOMETRY:
                pose = msg.pose.pose
                links = [(msg.header, msg.child_frame_id, pose.position, pose.orientation)]
            else:
                links = [(tf.header, tf.child_frame_id, tf.transform.translation,
                          tf.transform.rotation) for tf in msg.transforms]
            for header, child_id, xyz, q in links:
                child, up = _frame(child_id), _frame(header.frame_id)
                if child in given:
                    continue
                if parent.setdefault(child, up) != up:
                    raise OcctrackError(f"frame {child!r} has two parents in the bag's "
                                        f"transforms, {parent[child]!r} and {up!r}",
                                        name)
                t = _seconds(record) if stamps == "record" else _stamp(header)
                samples.setdefault(child, []).append((t, xyz.x, xyz.y, _yaw(q)))
    return parent, samples


def _link_pose(samples: list[tuple], time: np.ndarray) -> np.ndarray:
    """A link's (x, y, yaw) at `time`, linear between its samples, held beyond them."""
    s = np.array(sorted(samples, key=lambda sample: sample[0]))
    yaw = np.unwrap(s[:, 3])
    return np.c_[np.interp(time, s[:, 0], s[:, 1]), np.interp(time, s[:, 0], s[:, 2]),
                 np.interp(time, s[:, 0], yaw)]


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """2-D poses (.., 3) x, y, heading: b (given in a's frame) in a's parent's frame."""
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1],
                     a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     a[..., 2] + b[..., 2]], axis=-1)


def _poses(reader, name: str, fixed: str, frame: str, time: np.ndarray,
           stamps: str) -> np.ndarray:
    parent, samples = _links(reader, name, stamps)
    chain = [frame]
    while chain[-1] != fixed and chain[-1] in parent and len(chain) <= len(parent):
        chain.append(parent[chain[-1]])
    if chain[-1] != fixed:
        if parent:
            links = sorted(f"{p} -> {c}" for c, p in parent.items())
            have = (f"the bag's transforms (parent -> child): {', '.join(links[:20])}"
                    + (f" and {len(links) - 20} more" if len(links) > 20 else "")
                    + (f"; {frame} leads up to {chain[-1]}" if len(chain) > 1 else ""))
        else:
            have = "the bag has no /tf, /tf_static (tf2_msgs/TFMessage) or nav_msgs/Odometry"
        raise OcctrackError(f"no transform chain from the fixed frame {fixed!r} to the scans' "
                            f"frame {frame!r}: {have}", name)
    pose = np.zeros((len(time), 3))
    for child in reversed(chain[:-1]):  # from the fixed frame down to the scanner
        pose = compose(pose, _link_pose(samples[child], time))
    pose[:, 2] = (pose[:, 2] + np.pi) % (2 * np.pi) - np.pi
    return pose
