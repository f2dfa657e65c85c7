"""One frame of 3D boxes from above (`occtrack.viz.ground`, `occtrack bev`): a patch per box of
each kind, the tracks held while hidden drawn apart with the shadows that hide them, the field
of view from the calibration, pictures written whole and never over a file unasked, and the
command's one-line errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.tracker.ground import GroundTracks

pytest.importorskip("matplotlib", reason="the pictures need the viz extra")

# KITTI sequence 0000's P2 (calib/0000.txt) and image width (seqinfo/0000.ini)
P2 = np.array([[721.5377, 0.0, 609.5593, 44.85728], [0.0, 721.5377, 172.854, 0.2163791],
               [0.0, 0.0, 1.0, 0.002745884]])
WIDTH = 1242


def box(x, z, w=1.8, l=4.2, ry=math.pi / 2):
    """A KITTI box h w l x y z rotation_y on the ground 1.65 m below the camera (ry = pi/2:
    its length along z)."""
    return [1.5, w, l, x, 1.65, z, ry]


def synthetic_frame():
    """Three detections (a car ahead at 10 m, one to the right, a far one), two true boxes
    and four tracks: two on the near detections, one coasting in the open, one held hidden
    straight behind the car ahead."""
    detections = np.array([box(0.0, 10.0), box(6.0, 15.0), box(-8.0, 30.0)])
    scores = np.array([0.95, 0.6, 0.2])
    truth = np.array([box(0.1, 10.2), box(0.0, 22.0)])
    tracks = GroundTracks(
        ids=np.array([3, 5, 8, 11]),
        boxes3d=np.array([box(0.0, 10.0), box(6.0, 15.0), box(12.0, 8.0), box(0.0, 22.0)]),
        existence=np.ones(4), confidence=np.full(4, 0.9), velocities=np.zeros((4, 2)),
        detection_index=np.array([0, 1, -1, -1]), classes=np.zeros(4, dtype=int),
        occluded=np.array([False, False, False, True]))
    return detections, scores, tracks, truth


def kinds(ax) -> dict[str, int]:
    counts: dict[str, int] = {}
    for patch in ax.patches:
        counts[patch.get_gid()] = counts.get(patch.get_gid(), 0) + 1
    return counts


@pytest.fixture
def axis():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


def test_one_patch_per_box_of_each_kind(axis):
    from occtrack.viz.ground import draw_ground_frame

    detections, scores, tracks, truth = synthetic_frame()
    assert draw_ground_frame(axis, detections, scores, tracks, truth) is axis
    # the one shadow: the car ahead (a detection) hides track 11; the far detection and the
    # one to the right do not overlap its angles
    assert kinds(axis) == {"truth": 2, "detection": 3, "track": 2, "coasting": 1, "hidden": 1,
                           "shadow": 1}
    labels = [t.get_text() for t in axis.get_legend().get_texts()]
    assert labels[:2] == ["sensor", "camera's field of view (90\N{DEGREE SIGN})"]
    assert {"true box", "detection (fill: score)", "track (took a detection)",
            "track coasting", "track held while hidden", "shadow of a nearer box"} <= set(labels)
    assert sorted(t.get_text() for t in axis.texts) == ["11", "3", "5", "8"]


def test_hidden_tracks_are_drawn_apart(axis):
    from matplotlib.colors import to_hex

    from occtrack.viz.ground import HIDDEN, TRACK, draw_ground_frame

    detections, scores, tracks, truth = synthetic_frame()
    draw_ground_frame(axis, detections, scores, tracks, truth)
    by_kind = {p.get_gid(): p for p in axis.patches}
    hidden, took, coasting = by_kind["hidden"], by_kind["track"], by_kind["coasting"]
    assert to_hex(hidden.get_edgecolor()) == to_hex(HIDDEN) != to_hex(TRACK)
    assert to_hex(took.get_edgecolor()) == to_hex(coasting.get_edgecolor()) == to_hex(TRACK)
    assert hidden.get_linestyle() == coasting.get_linestyle() == "--"
    assert took.get_linestyle() == "-"
    # the hidden track's label in its colour
    label = next(t for t in axis.texts if t.get_text() == "11")
    assert to_hex(label.get_color()) == to_hex(HIDDEN)
    # the shadow starts at the car ahead and reaches past the hidden track, away from the
    # sensor
    shadow = by_kind["shadow"].get_xy()
    assert shadow[:, 1].min() == pytest.approx(10.0 - 2.1, abs=1e-9)
    assert shadow[:, 1].max() > 100


def test_detections_are_filled_by_score(axis):
    from occtrack.viz.ground import draw_ground_frame

    detections, scores, tracks, truth = synthetic_frame()
    draw_ground_frame(axis, detections, scores, shadows=False)
    fill = [p.get_facecolor()[3] for p in axis.patches if p.get_gid() == "detection"]
    assert fill[0] > fill[1] > fill[2] > 0
    assert kinds(axis) == {"detection": 3}  # no tracks, no truth, no shadow
    with pytest.raises(ValueError, match="3 detections but 2 scores"):
        draw_ground_frame(axis, detections, scores[:2])


def test_without_hidden_tracks_no_shadow_is_drawn(axis):
    from dataclasses import replace

    from occtrack.viz.ground import draw_ground_frame

    detections, scores, tracks, truth = synthetic_frame()
    draw_ground_frame(axis, detections, scores, replace(tracks, occluded=np.zeros(4, bool)))
    assert kinds(axis) == {"detection": 3, "track": 2, "coasting": 2}


def test_the_picture_is_written_whole_once_and_the_same_each_time(tmp_path):
    from occtrack.viz.ground import draw_ground_frame, field_of_view

    detections, scores, tracks, truth = synthetic_frame()
    fov = field_of_view(P2, WIDTH)
    first = draw_ground_frame(tmp_path / "a.png", detections, scores, tracks, truth, fov=fov,
                              title="synthetic")
    assert first == tmp_path / "a.png"
    assert first.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    draw_ground_frame(tmp_path / "b.png", detections, scores, tracks, truth, fov=fov,
                      title="synthetic")
    assert (tmp_path / "b.png").read_bytes() == first.read_bytes()
    with pytest.raises(OcctrackError, match="exists already; pass --force"):
        draw_ground_frame(first, detections, scores, tracks, truth)
    draw_ground_frame(first, detections, overwrite=True)
    assert first.read_bytes() != (tmp_path / "b.png").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "b.png"]  # no leftovers


def test_the_field_of_view_comes_from_p2_and_the_image_width():
    from occtrack.viz.ground import FIXED_FOV, field_of_view

    left, right = field_of_view(P2, WIDTH)
    # u = 0 and u = 1242 with the principal point at 609.6 px and a 721.5 px focal length
    assert math.degrees(left) == pytest.approx(-math.degrees(math.atan(609.56 / 721.54)),
                                               abs=0.05)
    assert math.degrees(right) == pytest.approx(math.degrees(math.atan(632.44 / 721.54)),
                                                abs=0.05)
    assert FIXED_FOV == pytest.approx((-math.pi / 4, math.pi / 4))


def test_only_nearer_boxes_across_the_angles_hide():
    from occtrack.tracker.ground import ground_corners
    from occtrack.viz.ground import hiding_boxes

    def footprints(*boxes):
        return ground_corners(np.array(boxes))[..., [0, 2]]

    hidden = footprints(box(0.0, 20.0))
    occluders = footprints(box(0.5, 10.0), box(0.0, 30.0), box(10.0, 10.0), box(-1.0, 5.0),
                           box(0.0, 20.0, ry=0.0))  # nearer; farther; aside; nearer; the same
    np.testing.assert_array_equal(hiding_boxes(hidden, occluders), [0, 3])
    assert len(hiding_boxes(hidden[:0], occluders)) == 0
    # behind the sensor: the angles wrap at +-pi
    behind = footprints(box(0.1, -20.0), box(-0.1, -10.0))
    np.testing.assert_array_equal(hiding_boxes(behind[:1], behind[1:]), [0])


# -- occtrack bev ---------------------------------------------------------------------------

def kitti_row(frame, x, z, score=2.0, kind="Car"):
    h, w, l, x, y, z, ry = box(x, z)
    return " ".join(str(c) for c in (frame, -1, kind, -1, -1, -1.57, 500, 150, 600, 220,
                                     h, w, l, x, y, z, ry, score))


@pytest.fixture
def det_file(tmp_path):
    """Three frames: a car ahead at 10 m in each, a second one behind it at 25 m seen in the
    first two frames (its lidar points blocked in the third)."""
    rows = []
    for f in range(3):
        rows.append(kitti_row(f, 0.0, 10.0))
        if f < 2:
            rows.append(kitti_row(f, 0.2, 25.0, score=1.0))
    path = tmp_path / "det.txt"
    path.write_text("\n".join(rows) + "\n")
    return path


def bev(*args):
    return main(["bev", *map(str, args)])


def one_error_line(capsys, start: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith(start), err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


def test_bev_draws_the_frame(det_file, tmp_path, capsys):
    out = tmp_path / "bev.png"
    assert bev(det_file, "--frame", 2, "--fps", 10, "-o", out) == 0
    captured = capsys.readouterr()
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "no poses (--poses FILE)" in captured.err and "90 degrees" in captured.err
    assert captured.out.startswith("drew frame 2: 1 detections, ")
    assert bev(det_file, "--frame", 0, "--fps", 10, "-o", tmp_path / "quiet.png",
               "--quiet") == 0
    assert capsys.readouterr().out == ""


def test_bev_classes_draws_the_picked_types_of_a_run_that_tracks_them_all(tmp_path, capsys):
    rows = [kitti_row(f, 0.0, 10.0) for f in range(3)]
    rows += [kitti_row(f, 5.0, 12.0, kind="Cyclist") for f in range(3)]
    det = tmp_path / "det.txt"
    det.write_text("\n".join(rows) + "\n")
    assert bev(det, "--frame", 2, "--fps", 10, "-o", tmp_path / "all.png") == 0
    assert capsys.readouterr().out.startswith("drew frame 2: 2 detections, 2 tracks")
    assert bev(det, "--frame", 2, "--fps", 10, "-o", tmp_path / "cars.png",
               "--classes", "Car") == 0
    assert capsys.readouterr().out.startswith("drew frame 2: 1 detections, 1 tracks")


def test_bev_a_frame_past_the_file_is_one_line(det_file, tmp_path, capsys):
    out = tmp_path / "bev.png"
    assert bev(det_file, "--frame", 3, "--fps", 10, "-o", out) == 1
    one_error_line(capsys, f"occtrack bev: error: {det_file}: --frame 3 is past the file's 3 "
                           f"frames (0..2)")
    assert not out.exists()
    with pytest.raises(SystemExit) as exit_:
        bev(det_file, "--frame", -1, "--fps", 10, "-o", out)
    assert exit_.value.code == 2 and "-1 must be at least 0" in capsys.readouterr().err


def test_bev_missing_files_are_one_line(det_file, tmp_path, capsys):
    out = tmp_path / "bev.png"
    missing = tmp_path / "nothing.txt"
    assert bev(missing, "--frame", 0, "--fps", 10, "-o", out) == 1
    one_error_line(capsys, f"occtrack bev: error: {missing}: no such file")
    assert bev(det_file, "--frame", 0, "--fps", 10, "--gt", missing, "-o", out) == 1
    one_error_line(capsys, f"occtrack bev: error: {missing}: no such file")
    assert bev(det_file, "--frame", 0, "--fps", 10, "--poses", missing, "-o", out) == 1
    one_error_line(capsys, f"occtrack bev: error: {missing}: no such file")
    assert not out.exists()


def test_bev_refuses_to_overwrite_and_other_mistakes(det_file, tmp_path, capsys):
    out = tmp_path / "bev.png"
    out.write_bytes(b"old")
    assert bev(det_file, "--frame", 0, "--fps", 10, "-o", out) == 1
    one_error_line(capsys, f"occtrack bev: error: {out}: exists already; pass --force")
    assert out.read_bytes() == b"old"
    assert bev(det_file, "--frame", 0, "--fps", 10, "-o", out, "--force", "--quiet") == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert "warning" in capsys.readouterr().err  # --quiet keeps the warnings
    assert bev(det_file, "--frame", 0, "--fps", 10, "-o", tmp_path / "bev.txt") == 1
    one_error_line(capsys, f"occtrack bev: error: {tmp_path / 'bev.txt'}: a picture's name "
                           f"ends in .png")
    assert bev(det_file, "--frame", 0, "-o", tmp_path / "x.png") == 1
    one_error_line(capsys, f"occtrack bev: error: {det_file}: frame rate unknown: pass --fps")
    mot = tmp_path / "det_mot.txt"
    mot.write_text("1,-1,10,10,30,90,0.9\n")
    assert bev(mot, "--frame", 0, "--fps", 10, "-o", tmp_path / "x.png") == 1
    one_error_line(capsys, f"occtrack bev: error: {mot}: not a KITTI tracking file")
    two_d = tmp_path / "det2d.txt"
    two_d.write_text("0 -1 Car -1 -1 -10 500 150 600 220 -1 -1 -1 -1000 -1000 -1000 -10 0.9\n")
    assert bev(two_d, "--frame", 0, "--fps", 10, "-o", tmp_path / "x.png") == 1
    one_error_line(capsys, f"occtrack bev: error: {two_d}:1: a detection without its 3D")
    assert not (tmp_path / "x.png").exists()


def test_the_docs_frame_holds_tracks_hidden_behind_nearer_people(kitti_root):
    """docs/kitti-3d.md's picture: KITTI 0017, frame 31, object-wise (the default) holds
    pedestrians hidden behind the nearer ones, where true people stand."""
    from occtrack.cli.bev import track_until
    from occtrack.io.kitti import DONTCARE, UNKNOWN, read_kitti
    from occtrack.io.kitti_geometry import read_poses
    from occtrack.tracker.ground import ground_config, ground_corners
    from occtrack.viz.ground import hiding_boxes

    det = read_kitti(kitti_root / "det_02" / "pointrcnn" / "0017.txt")
    det = det.select((det.type != DONTCARE) & (det.type != UNKNOWN))
    poses = read_poses(kitti_root / "poses" / "0017.txt", 32)
    tracks, rows, _ = track_until(det, 31, ground_config({"fps": 10.0}), poses)
    hidden = tracks.occluded & tracks.coasting
    assert hidden.any()
    labels = read_kitti(kitti_root / "label_02" / "0017.txt")
    labels = labels.select((labels.frame == 31) & (labels.type != DONTCARE))
    nearer = np.concatenate([det.box3d[rows], tracks.boxes3d[tracks.coasting & ~hidden]])
    for b in tracks.boxes3d[hidden]:
        footprint = ground_corners(b[None])[..., [0, 2]]
        assert len(hiding_boxes(footprint, ground_corners(nearer)[..., [0, 2]])) > 0
        assert np.hypot(*(labels.box3d[:, [3, 5]] - b[[3, 5]]).T).min() < 2.5
