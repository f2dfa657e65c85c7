"""`occtrack track-scans`: the lidar scan tracker on the scan files `occtrack simulate lidar`
writes, from the command line (issue 24, item 2)."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.config.lidar import LidarSceneConfig
from occtrack.config.scan import ScanTrackerConfig
from occtrack.io.scans import read_poses, read_scans
from occtrack.scenarios.lidar.files import write_scene
from occtrack.tracker import ScanTracker

HEADER = "time,id,x,y,vx,vy,existence,confidence,occluded"


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """60 scans of 4 people seen by a sensor that moves and turns, so that the poses matter."""
    folder = tmp_path_factory.mktemp("lidar") / "scene"
    write_scene(folder, LidarSceneConfig(people=4, sensor_vx=0.3, sensor_yaw_rate=0.05),
                scans=60, seed=1)
    return folder


def track_scans(scene, out, *args):
    return main(["track-scans", str(scene / "scans.csv"), "--poses", str(scene / "sensor.csv"),
                 "-o", str(out), "--quiet", *args])


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("occtrack track-scans: error: ") and err.count("\n") == 1
    assert "Traceback" not in err
    return err.strip()


def test_the_tracks_file_is_the_tracker_run_over_the_scans_and_poses(scene, tmp_path, capsys):
    out = tmp_path / "tracks.csv"
    assert track_scans(scene, out) == 0 and capsys.readouterr().out == ""
    lines = out.read_text().splitlines()
    assert lines[0] == HEADER and len(lines) > 100
    rows = [line.split(",") for line in lines[1:]]
    assert all(len(row) == 9 for row in rows)
    assert all(row[1] == str(int(row[1])) and row[8] in ("0", "1") for row in rows)
    assert all(float(row[7]) <= float(row[6]) <= 1 for row in rows)

    scans = read_scans(scene / "scans.csv")
    times, poses = read_poses(scene / "sensor.csv")
    assert np.ptp(poses[:, 0]) > 1 and np.ptp(poses[:, 2]) > 0.2  # the sensor moved, turned
    tracker = ScanTracker(ScanTrackerConfig(), beams=720, rate=10.0, origin=poses[0, :2])
    expected = []
    for (t, angle, ranges), pose in zip(scans, poses, strict=True):
        tracks = tracker.update(ranges, pose[2] + angle, t, pose[:2])
        for k in range(len(tracks)):
            (x, y), (vx, vy) = tracks.positions[k], tracks.velocities[k]
            expected.append(f"{t:.6f},{tracks.ids[k]},{x:.4f},{y:.4f},{vx:.4f},{vy:.4f},"
                            f"{tracks.existence[k]:.6f},{tracks.confidence[k]:.6f},"
                            f"{int(tracks.occluded[k])}")
    assert lines[1:] == expected


def test_the_same_scans_give_the_same_bytes_and_a_summary(scene, tmp_path, capsys):
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    assert track_scans(scene, first) == 0
    assert main(["track-scans", str(scene / "scans.csv"), "--poses", str(scene / "sensor.csv"),
                 "-o", str(second)]) == 0
    summary = capsys.readouterr().out.strip()
    assert summary.startswith("60 scans, ") and summary.endswith("scans per second")
    assert first.read_bytes() == second.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


def test_without_poses_the_sensor_is_at_the_origin(scene, tmp_path, capsys):
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(scene / "scans.csv"), "-o", "-", "--quiet"]) == 0
    stdout = capsys.readouterr().out
    assert track_scans(scene, out) == 0
    assert stdout.startswith(HEADER + "\n") and stdout != out.read_text()


def test_an_existing_output_is_refused_without_force(scene, tmp_path, capsys):
    out = tmp_path / "tracks.csv"
    out.write_text("keep me\n")
    assert track_scans(scene, out) == 1
    err = one_error_line(capsys)
    assert f"{out}: exists already; pass --force" in err and out.read_text() == "keep me\n"
    assert track_scans(scene, out, "--force") == 0
    assert out.read_text().startswith(HEADER + "\n")


def test_a_malformed_scan_line_names_the_file_and_line(tmp_path, capsys):
    scans = tmp_path / "scans.csv"
    scans.write_text("# a comment\ntime,angle,range\n0.0,0.1,3.0\n0.0,0.2,far\n")
    out = tmp_path / "tracks.csv"
    assert main(["track-scans", str(scans), "-o", str(out)]) == 1
    assert one_error_line(capsys) == (f"occtrack track-scans: error: {scans}:4: range is not "
                                      f"a number: 'far'")
    scans.write_text("time,angle,range\n0.0,0.1,3.0\n0.0,0.2,inf\n0.0,0.15,2.0\n")
    assert main(["track-scans", str(scans), "-o", str(out)]) == 1
    err = one_error_line(capsys)
    assert f"{scans}:4: angle 0.15 is not above the beam before it" in err
    assert not out.exists()


def test_poses_at_other_times_name_the_file_and_line(scene, tmp_path, capsys):
    lines = (scene / "sensor.csv").read_text().splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if line[0].isdigit())  # scan 1's pose
    poses = tmp_path / "sensor.csv"
    poses.write_text("".join(lines[:first + 3] + ["0.250000,0,0,0\n"] + lines[first + 4:]))
    out = tmp_path / "tracks.csv"
    args = ["track-scans", str(scene / "scans.csv"), "--poses", str(poses), "-o", str(out)]
    assert main(args) == 1
    assert one_error_line(capsys).startswith(
        f"occtrack track-scans: error: {poses}:{first + 4}: time 0.250000 is not the time of "
        f"scan 4 of {scene / 'scans.csv'} (0.300000)")
    poses.write_text("".join(lines[:first + 10]))
    assert main(args) == 1
    assert "no pose for scan 11" in one_error_line(capsys) and not out.exists()


def test_a_scan_table_in_the_config_file_sets_the_tracker(scene, tmp_path, capsys):
    config = tmp_path / "tracker.toml"
    config.write_text('[scan]\nocclusion = "none"\n')
    by_file, by_flag, flag_wins = (tmp_path / f"{n}.csv" for n in ("file", "flag", "wins"))
    default = tmp_path / "default.csv"
    assert track_scans(scene, by_file, "--config", str(config)) == 0
    assert track_scans(scene, by_flag, "--occlusion", "none") == 0
    assert track_scans(scene, flag_wins, "--config", str(config),
                       "--occlusion", "measurement-wise") == 0
    assert track_scans(scene, default) == 0
    assert by_file.read_bytes() == by_flag.read_bytes() != default.read_bytes()
    assert flag_wins.read_bytes() == default.read_bytes()

    config.write_text('[scan]\nocclusion = "none"\nbeam_count = 720\n')
    out = tmp_path / "r.csv"
    assert track_scans(scene, out, "--config", str(config)) == 1
    assert one_error_line(capsys).startswith(
        f"occtrack track-scans: error: {config}: unknown setting 'scan.beam_count'")
    config.write_text('occlusion = "none"\n')
    assert track_scans(scene, out, "--config", str(config)) == 1
    assert "unknown setting 'occlusion' outside a table" in one_error_line(capsys)
    config.write_text('[tracker]\nocclusion = "none"\n')
    assert track_scans(scene, out, "--config", str(config)) == 1
    assert f"{config}: unknown table [tracker]" in one_error_line(capsys)
    config.write_text("[scan]\nmax_range = -1.0\n")
    assert track_scans(scene, out, "--config", str(config)) == 1
    assert f"{config}: [scan] max_range must be a number in (0, 100000]" in one_error_line(
        capsys)
    assert track_scans(scene, out, "--likelihood", "cluster") == 1
    assert "pass --occlusion none" in one_error_line(capsys) and not out.exists()


def test_help_explains_the_command(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["track-scans", "--help"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    for words in (HEADER, "--poses", "sensor.csv", "occtrack simulate lidar", "[scan]",
                  "measurement-wise", "--force", "1    bad input"):
        assert words in text


def test_the_command_names_match_the_tracker_settings():
    from occtrack.cli.track_scans import SCAN_LIKELIHOOD_NAMES, SCAN_OCCLUSION_NAMES
    from occtrack.config import scan

    assert SCAN_OCCLUSION_NAMES == scan.SCAN_OCCLUSION_NAMES
    assert SCAN_LIKELIHOOD_NAMES == scan.SCAN_LIKELIHOOD_NAMES


def test_ego_motion_by_scan_matching_tracks_in_the_first_scans_frame(scene, tmp_path, capsys):
    out = tmp_path / "matched.csv"
    args = ["track-scans", str(scene / "scans.csv"), "-o", str(out), "--quiet",
            "--ego-motion", "scan-matching"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert err.startswith("occtrack track-scans: note: scan matching matched ")
    assert err.endswith(" of 60 scans; the others took the constant-velocity guess\n")
    assert out.read_text().startswith(HEADER + "\n")
    # poses given and estimated at once is refused in one line
    assert track_scans(scene, tmp_path / "both.csv", "--ego-motion", "scan-matching") == 1
    assert "--ego-motion scan-matching estimates the poses" in one_error_line(capsys)


def test_the_recording_says_what_its_sensor_and_people_are(tmp_path):
    """A simulated file's comments give its sensor and its disc people; any other recording
    is a real laser at leg height (people on two legs), a bag with its range_max."""
    from types import SimpleNamespace

    from occtrack.cli.track_scans import recording_defaults
    from occtrack.errors import OcctrackError

    simulated = SimpleNamespace(settings={"person_radius": "0.3", "max_range": "15",
                                          "p_d": "0.9", "seed": "4"}, path="s.csv")
    assert recording_defaults(simulated, None) == {"body": "disc", "radius": 0.3,
                                                   "max_range": 15.0, "p_d": 0.9}
    assert recording_defaults(SimpleNamespace(settings={}, path="own.csv"), None) == {
        "body": "legs"}
    bag = SimpleNamespace(range_max=5.6)
    assert recording_defaults(None, bag) == {"body": "legs", "max_range": 5.6}
    bad = SimpleNamespace(settings={"person_radius": "wide"}, path="s.csv")
    with pytest.raises(OcctrackError, match="person_radius=wide is not a number"):
        recording_defaults(bad, None)
