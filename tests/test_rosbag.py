"""`occtrack.io.rosbag` and `occtrack track-scans BAG`: the laser scans of ROS 1 and ROS 2
bags, and the sensor's pose from their transforms (issue 41, item 1), on small bags written
here with rosbags' own writers, and on the leg-tracker benchmark's recording when it is there."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.io.rosbag import read_bag_scans

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install "
                                      "'occtrack[ros]')")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

SCAN = "sensor_msgs/msg/LaserScan"
TF = "tf2_msgs/msg/TFMessage"
ODOM = "nav_msgs/msg/Odometry"
T0 = 1_700_000_000 * 10**9  # record times, ns
F32 = np.float32


def store_for(ros2: bool):
    store = get_typestore(Stores.LATEST if ros2 else Stores.ROS1_NOETIC)
    if not ros2:  # Noetic's store lacks tf2_msgs
        store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", TF))
    return store


class Messages:
    """Messages of one typestore: (topic, msgtype, record ns, message) to write."""

    def __init__(self, ros2: bool = False):
        self.ros2, self.store, self.rows = ros2, store_for(ros2), []

    def t(self, name):
        return self.store.types[name]

    def header(self, ns, frame):
        stamp = self.t("builtin_interfaces/msg/Time")(sec=ns // 10**9, nanosec=ns % 10**9)
        extra = {} if self.ros2 else {"seq": 0}
        return self.t("std_msgs/msg/Header")(stamp=stamp, frame_id=frame, **extra)

    def scan(self, record, ranges, topic="/scan", angle_min=-0.5, inc=0.25, range_min=0.1,
             range_max=10.0, stamp=None, frame="laser"):
        ranges = np.asarray(ranges, dtype=F32)
        msg = self.t(SCAN)(
            header=self.header(record if stamp is None else stamp, frame), angle_min=angle_min,
            angle_max=angle_min + inc * (len(ranges) - 1), angle_increment=inc,
            time_increment=0.0, scan_time=0.1, range_min=range_min, range_max=range_max,
            ranges=ranges, intensities=np.zeros(0, F32))
        self.rows.append((topic, SCAN, record, msg))

    def _quaternion(self, yaw):
        return self.t("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                      w=math.cos(yaw / 2))

    def tf(self, record, links, topic="/tf"):
        """links: (parent, child, x, y, yaw) each, one TFMessage."""
        v3 = self.t("geometry_msgs/msg/Vector3")
        transforms = [self.t("geometry_msgs/msg/TransformStamped")(
            header=self.header(record, parent), child_frame_id=child,
            transform=self.t("geometry_msgs/msg/Transform")(
                translation=v3(x=x, y=y, z=0.3), rotation=self._quaternion(yaw)))
            for parent, child, x, y, yaw in links]
        self.rows.append((topic, TF, record, self.t(TF)(transforms=transforms)))

    def odom(self, record, parent, child, x, y, yaw, topic="/odom"):
        v3 = self.t("geometry_msgs/msg/Vector3")
        pose = self.t("geometry_msgs/msg/Pose")(
            position=self.t("geometry_msgs/msg/Point")(x=x, y=y, z=0.0),
            orientation=self._quaternion(yaw))
        twist = self.t("geometry_msgs/msg/Twist")(linear=v3(x=0.0, y=0.0, z=0.0),
                                                  angular=v3(x=0.0, y=0.0, z=0.0))
        msg = self.t(ODOM)(
            header=self.header(record, parent), child_frame_id=child,
            pose=self.t("geometry_msgs/msg/PoseWithCovariance")(pose=pose,
                                                                 covariance=np.zeros(36)),
            twist=self.t("geometry_msgs/msg/TwistWithCovariance")(twist=twist,
                                                                   covariance=np.zeros(36)))
        self.rows.append((topic, ODOM, record, msg))

    def write(self, path, storage=StoragePlugin.SQLITE3) -> Path:
        path = Path(path)
        writer = (Writer2(path, version=9, storage_plugin=storage) if self.ros2
                  else Writer1(path))
        serialize = self.store.serialize_cdr if self.ros2 else self.store.serialize_ros1
        with writer:
            connections = {}
            for topic, kind, record, msg in self.rows:
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, kind, typestore=self.store)
                writer.write(connections[topic], record, serialize(msg, kind))
        return path


RANGES = [[1.0, 2.5, np.inf, 3.25, 9.5],
          [np.nan, -np.inf, 0.05, 10.5, 10.0],  # 4 invalid readings; 10.0 = range_max is valid
          [4.0, 4.0, 4.0, np.inf, 0.1]]  # 0.1 = range_min is valid


def three_scans(ros2=False, **kwargs) -> Messages:
    messages = Messages(ros2)
    for k, ranges in enumerate(RANGES):
        messages.scan(T0 + k * 100_000_000 + 7, ranges, **kwargs)
    return messages


def expected_ranges() -> np.ndarray:
    """The valid readings (the four invalid ones of the second scan left out), flat."""
    r = np.array(RANGES, dtype=F32).astype(float)
    return np.r_[r[0], r[1, 4:], r[2]]


def test_a_ros1_bag_gives_its_scans_exactly(tmp_path):
    bag = three_scans().write(tmp_path / "rec.bag")
    scans, poses, info = read_bag_scans(bag)
    assert poses is None and len(scans) == 3 and scans.path == str(bag)
    assert scans.time.tolist() == [(T0 + k * 100_000_000 + 7) / 10**9 for k in range(3)]
    assert scans.start.tolist() == [0, 5, 6, 11]  # invalid readings are left out
    angle = float(F32(-0.5)) + np.arange(5) * float(F32(0.25))
    assert np.array_equal(scans.angle, np.r_[angle, angle[4:], angle])
    assert np.array_equal(scans.range, expected_ranges())
    assert (info.topic, info.frame_id, info.scans, info.beams) == ("/scan", "laser", 3, 5)
    assert (info.angle_min, info.angle_max, info.range_max) == (-0.5, 0.5, 10.0)
    assert info.invalid == 4 and info.laser_topics == ("/scan",)


def test_header_stamps_instead_of_record_times(tmp_path):
    messages = Messages()
    for k in range(3):
        messages.scan(T0 + k * 10**8, [1.0, 2.0], stamp=T0 - 130 * 10**9 + k * 10**8 + 5)
    bag = messages.write(tmp_path / "rec.bag")
    assert read_bag_scans(bag)[0].time.tolist() == [(T0 + k * 10**8) / 1e9 for k in range(3)]
    header = read_bag_scans(bag, stamps="header")[0].time
    assert header.tolist() == [(T0 - 130 * 10**9 + k * 10**8 + 5) / 10**9 for k in range(3)]

    messages.rows[2][3].header.stamp.sec -= 1  # header stamps going backwards
    bag = messages.write(tmp_path / "back.bag")
    with pytest.raises(OcctrackError, match=r"message 3 of /scan: its header time .* is "
                                            r"earlier than the message before"):
        read_bag_scans(bag, stamps="header")
    assert len(read_bag_scans(bag)[0]) == 3  # the record times are in order


def test_a_clockwise_scanner_has_its_beams_reversed(tmp_path):
    messages = Messages()
    messages.scan(T0, [1.0, 2.0, 3.0], angle_min=0.5, inc=-0.25)
    scans, _, info = read_bag_scans(messages.write(tmp_path / "rec.bag"))
    assert np.array_equal(scans.angle, float(F32(0.5)) - np.arange(3)[::-1] * 0.25)
    assert scans.range.tolist() == [3.0, 2.0, 1.0]
    assert (info.angle_min, info.angle_max) == (0.0, 0.5)


def test_topic_choice_and_its_errors(tmp_path):
    messages = three_scans()
    messages.scan(T0 + 5, [7.0, 8.0], topic="/front")
    bag = messages.write(tmp_path / "two.bag")
    scans, _, info = read_bag_scans(bag)  # among several, ROS's conventional /scan
    assert (info.topic, len(scans)) == ("/scan", 3)
    other = Messages()
    other.scan(T0, [7.0, 8.0], topic="/front")
    other.scan(T0 + 1, [9.0], topic="/rear")
    with pytest.raises(OcctrackError, match=r"two_others.bag: 2 LaserScan topics \(/front, "
                                            r"/rear\); pass --topic to choose one"):
        read_bag_scans(other.write(tmp_path / "two_others.bag"))
    scans, _, info = read_bag_scans(bag, topic="/front")
    assert scans.range.tolist() == [7.0, 8.0] and info.laser_topics == ("/front", "/scan")
    assert len(read_bag_scans(bag, topic="/scan")[0]) == 3
    with pytest.raises(OcctrackError, match=r"no LaserScan topic '/rear'; its LaserScan "
                                            r"topics: /front, /scan"):
        read_bag_scans(bag, topic="/rear")

    only_tf = Messages()
    only_tf.tf(T0, [("odom", "base_link", 0.0, 0.0, 0.0)])
    bag = only_tf.write(tmp_path / "tf.bag")
    with pytest.raises(OcctrackError) as err:
        read_bag_scans(bag)
    assert str(err.value) == (f"{bag}: no sensor_msgs/LaserScan topic in the bag (its topics: "
                              f"/tf)")


def test_scans_whose_beams_change_are_refused(tmp_path):
    messages = three_scans()
    messages.scan(T0 + 10**9, [1.0, 2.0, 3.0, 4.0])
    bag = messages.write(tmp_path / "rec.bag")
    with pytest.raises(OcctrackError) as err:
        read_bag_scans(bag)
    assert str(err.value).startswith(f"{bag}: message 4 of /scan has 4 beams from -0.5 rad by "
                                     f"0.25, the first 5 from -0.5 by 0.25: every scan must")


@pytest.mark.parametrize("storage", [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_a_ros2_bag_reads_as_the_ros1_bag(tmp_path, storage):
    ros1 = read_bag_scans(three_scans().write(tmp_path / "rec.bag"))
    folder = three_scans(ros2=True).write(tmp_path / "rec2", storage)
    suffix = ".db3" if storage == StoragePlugin.SQLITE3 else ".mcap"
    (file,) = folder.glob(f"*{suffix}")
    for path in (folder, file):
        scans, poses, info = read_bag_scans(path)
        assert poses is None and info == ros1[2] and scans.path == str(path)
        for name in ("time", "start", "angle", "range"):
            assert np.array_equal(getattr(scans, name), getattr(ros1[0], name))


def pose_of(*links):
    """The composition of 2-D transforms (x, y, yaw), by rotation matrices."""
    matrix = np.eye(3)
    for x, y, yaw in links:
        c, s = math.cos(yaw), math.sin(yaw)
        matrix = matrix @ np.array([[c, -s, x], [s, c, y], [0, 0, 1]])
    return np.array([matrix[0, 2], matrix[1, 2], math.atan2(matrix[1, 0], matrix[0, 0])])


def test_poses_follow_the_tf_chain_and_interpolate(tmp_path):
    messages = Messages()
    messages.tf(T0, [("map", "odom", 1.0, 2.0, math.pi / 2)], topic="/tf_static")
    messages.tf(T0, [("base_link", "laser", 0.5, 0.0, math.pi)], topic="/tf_static")
    messages.tf(T0 + 10**9, [("odom", "base_link", 0.0, 0.0, 3.0)])
    messages.tf(T0 + 2 * 10**9, [("odom", "base_link", 2.0, -1.0, -3.0)])
    for ns in (T0 + 5 * 10**8, T0 + 15 * 10**8, T0 + 3 * 10**9):  # before, midway, after
        messages.scan(ns, [1.0, 2.0], frame="/laser")
    bag = messages.write(tmp_path / "rec.bag")
    scans, poses, _ = read_bag_scans(bag, fixed_frame="map")
    midway = math.pi  # from 3.0 to -3.0 the shorter way round, through pi
    expected = [pose_of((1, 2, math.pi / 2), odom, (0.5, 0, math.pi))
                for odom in [(0, 0, 3.0), (1.0, -0.5, midway), (2.0, -1.0, -3.0)]]
    assert poses.shape == (3, 3)
    assert np.allclose(poses[:, :2], np.array(expected)[:, :2], atol=1e-12)
    turn = poses[:, 2] - np.array(expected)[:, 2]
    assert np.allclose(np.angle(np.exp(1j * turn)), 0, atol=1e-12)
    assert np.all((-math.pi <= poses[:, 2]) & (poses[:, 2] < math.pi))
    odom = read_bag_scans(bag, fixed_frame="odom")[1][1]
    assert np.allclose(odom, pose_of((1.0, -0.5, midway), (0.5, 0, math.pi)), atol=1e-12)
    laser = read_bag_scans(bag, fixed_frame="laser")[1]
    assert np.array_equal(laser, np.zeros((3, 3)))

    with pytest.raises(OcctrackError) as err:
        read_bag_scans(bag, fixed_frame="world")
    assert str(err.value) == (
        f"{bag}: no transform chain from the fixed frame 'world' to the scans' frame 'laser': "
        f"the bag's transforms (parent -> child): base_link -> laser, map -> odom, odom -> "
        f"base_link; laser leads up to map")


def test_poses_from_an_odometry_topic(tmp_path):
    messages = Messages(ros2=True)
    messages.tf(T0, [("base_link", "laser", 0.5, 0.25, 0.0)], topic="/tf_static")
    messages.odom(T0, "odom", "base_link", 0.0, 0.0, 0.0)
    messages.odom(T0 + 10**9, "odom", "base_link", 1.0, 3.0, 1.0)
    messages.scan(T0 + 25 * 10**7, [1.0, 2.0])
    folder = messages.write(tmp_path / "rec2")
    _, poses, _ = read_bag_scans(folder, fixed_frame="odom")
    assert np.allclose(poses[0], pose_of((0.25, 0.75, 0.25), (0.5, 0.25, 0.0)), atol=1e-12)

    plain = Messages(ros2=True)
    plain.scan(T0, [1.0])
    with pytest.raises(OcctrackError, match="the bag has no /tf, /tf_static"):
        read_bag_scans(plain.write(tmp_path / "plain"), fixed_frame="odom")


def test_what_is_not_a_bag_is_one_clear_error(tmp_path, monkeypatch):
    junk = tmp_path / "junk.bag"
    junk.write_text("not a bag\n")
    with pytest.raises(OcctrackError) as err:
        read_bag_scans(junk)
    assert str(err.value) == f"{junk}: not a readable ROS bag: File magic is invalid."
    with pytest.raises(OcctrackError, match=r"missing.bag: no such file"):
        read_bag_scans(tmp_path / "missing.bag")
    with pytest.raises(OcctrackError, match=r"is a folder without metadata.yaml"):
        read_bag_scans(tmp_path)
    text = tmp_path / "scans.csv"
    text.write_text("time,angle,range\n")
    with pytest.raises(OcctrackError, match=r"not a bag name"):
        read_bag_scans(text)
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(OcctrackError, match=r'install it with pip install "occtrack\[ros\]"'):
        read_bag_scans(three_scans().write(tmp_path / "rec.bag"))


# -- the command line -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def scene_bag(tmp_path_factory):
    """A simulated scene of people walking past a still scanner (occtrack simulate lidar's
    scans.csv) as a ROS 1 bag, with one invalid reading a scan."""
    from occtrack.config.lidar import LidarSceneConfig
    from occtrack.io.scans import read_scans
    from occtrack.scenarios.lidar.files import write_scene

    folder = tmp_path_factory.mktemp("scene")
    write_scene(folder / "scene", LidarSceneConfig(people=3), scans=40, seed=2)
    scans = read_scans(folder / "scene" / "scans.csv")
    messages = Messages()
    for k, (t, angle, ranges) in enumerate(scans):
        ranges = ranges.copy()
        ranges[k % len(ranges)] = np.nan
        messages.scan(T0 + round(t * 1e9), ranges, angle_min=angle[0],
                      inc=(angle[-1] - angle[0]) / (len(angle) - 1), range_min=0.0,
                      range_max=20.0)
    return messages.write(folder / "scene.bag"), folder / "scene" / "scans.csv"


def test_track_scans_on_a_bag(scene_bag, tmp_path, capsys):
    bag, _ = scene_bag
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    # a bag is a real laser at leg height (people on two legs) unless the config says the
    # people are discs, as the simulated scene's are
    discs = tmp_path / "discs.toml"
    discs.write_text('[scan]\nbody = "disc"\n')
    assert main(["track-scans", str(bag), "-o", str(first), "--quiet", "--config",
                 str(discs)]) == 0
    out, err = capsys.readouterr()
    assert out == "" and err == (f"occtrack track-scans: warning: {bag}: 40 of "
                                 f"{40 * 720} readings of /scan are invalid (nan, -inf or "
                                 f"outside [range_min, range_max], REP 117) and are left "
                                 f"out\n")
    assert main(["track-scans", str(bag), "-o", str(second), "--quiet", "--config",
                 str(discs)]) == 0
    lines = first.read_text().splitlines()
    assert lines[0] == "time,id,x,y,vx,vy,existence,confidence,occluded" and len(lines) > 40
    assert float(lines[1].split(",")[0]) >= T0 / 1e9
    assert first.read_bytes() == second.read_bytes()


def test_the_bag_range_max_is_the_tracker_max_range_unless_the_config_sets_it(tmp_path, capsys):
    messages = Messages()
    for k in range(3):
        messages.scan(T0 + k * 10**8, [1.0, 5.0, 9.0], range_max=10.0)
    bag = messages.write(tmp_path / "rec.bag")
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(bag), "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr().err == ""  # max_range 10 m: no return is beyond it
    config = tmp_path / "scan.toml"
    config.write_text("[scan]\nmax_range = 3.0\n")
    assert main(["track-scans", str(bag), "-o", str(out), "--quiet", "--force",
                 "--config", str(config)]) == 0
    assert "6 returns at or beyond max_range (3 m)" in capsys.readouterr().err


def test_among_several_laser_topics_the_command_reads_scan_and_says_so(tmp_path, capsys):
    messages = Messages()
    for k in range(3):
        messages.scan(T0 + k * 10**8, [1.0, 5.0, 9.0])
        messages.scan(T0 + k * 10**8 + 5, [2.0, 2.0], topic="/rear")
    bag = messages.write(tmp_path / "rec.bag")
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(bag), "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr().err == (
        f"occtrack track-scans: note: {bag} has 2 LaserScan topics (/rear, /scan); reading "
        f"/scan, ROS's conventional laser topic (--topic chooses another)\n")
    assert main(["track-scans", str(bag), "-o", str(out), "--quiet", "--force",
                 "--topic", "/rear"]) == 0
    assert capsys.readouterr().err == ""


def one_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("occtrack track-scans: error: ") and err.count("\n") == 1
    return err.strip()


def test_bag_options_need_a_bag(scene_bag, tmp_path, capsys):
    bag, csv = scene_bag
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(csv), "-o", str(out), "--topic", "/scan"]) == 1
    assert one_error(capsys) == (f"occtrack track-scans: error: {csv}: --topic goes with a ROS "
                                 f"bag (.bag, a ROS 2 bag folder, .db3, .mcap), and SCANS is a "
                                 f"scan file")
    assert main(["track-scans", str(csv), "-o", str(out), "--stamps", "header",
                 "--fixed-frame", "map"]) == 1
    assert "--fixed-frame and --stamps go with a ROS bag" in one_error(capsys)
    assert main(["track-scans", str(bag), "-o", str(out), "--poses", str(csv),
                 "--fixed-frame", "map"]) == 1
    assert "--poses and --fixed-frame both give the sensor's pose" in one_error(capsys)
    assert main(["track-scans", str(bag), "-o", str(out), "--topic", "/laser"]) == 1
    assert one_error(capsys).endswith("no LaserScan topic '/laser'; its LaserScan topics: /scan")
    assert main(["track-scans", str(bag), "-o", str(out), "--fixed-frame", "map"]) == 1
    assert "no transform chain from the fixed frame 'map'" in one_error(capsys)
    assert not out.exists()


# -- the benchmark's recording --------------------------------------------------------------------

def test_the_leg_tracker_recording(laser_recording):
    folder = laser_recording
    scans, poses, info = read_bag_scans(folder / "person_following_outdoor_1.bag")
    assert poses is None and len(scans) == info.scans == 7170 and info.beams == 245
    assert info.topic == "/scan_base2" and info.frame_id == "base_laser_link"
    assert info.angle_min == pytest.approx(-0.6013, abs=1e-4)
    assert info.angle_max == pytest.approx(0.8958, abs=1e-4)
    assert info.range_max == pytest.approx(5.6, abs=1e-6)
    with open(folder / "scans.csv") as fh:
        fh.readline()
        row = fh.readline().split(",")
    assert scans.time[0] == pytest.approx(float(row[0]), abs=1e-6)  # the record time
    csv = np.array(row[12].split(), dtype=F32)
    assert np.array_equal(scans[0][1], csv[~np.isnan(csv)].astype(float))
    assert np.all(np.diff(scans.time) > 0)
