"""3D boxes on the ground plane: the sensor's view as occlusion (nearer boxes hide the angles
behind them), the ground tracker on a moving sensor, and `occtrack track --3d` on KITTI files."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.config import TrackerConfig
from occtrack.io.kitti import read_kitti
from occtrack.occlusion.base import OcclusionContext
from occtrack.occlusion.sensor_view import (
    SensorViewGeometry,
    SensorViewMeasurementWise,
    SensorViewObjectWise,
    sensor_view_occlusion,
)
from occtrack.tracker.ground import (
    EVIDENCE_MEMORY,
    SCORE_EVIDENCE_WEIGHT,
    GroundTracker,
    check_boxes3d,
    detection_scores,
    forget_evidence,
    ground_config,
    ground_corners,
    lookahead_evidence,
)


def box(x, z, half=1.0):
    """An edge box (2, 2) of half-size `half` centred at (x, z)."""
    return np.array([[x - half, x + half], [z - half, z + half]])


# -- the sensor's view -------------------------------------------------------------------------

def test_a_nearer_box_on_the_same_bearing_hides_a_farther_one():
    g = SensorViewGeometry(sensor=np.zeros(2))
    far, near = box(0, 20), box(0, 10)
    assert g.visible(far[None], near[None])[0] == pytest.approx(0.0)  # wholly behind it
    assert g.visible(near[None], far[None])[0] == 1.0  # a farther box hides nothing
    beside = box(15, 10)
    assert g.visible(far[None], beside[None])[0] == 1.0  # another bearing


def test_the_hidden_share_is_the_angular_share_times_the_gain():
    g = SensorViewGeometry(gain=2.0, sensor=np.zeros(2))
    far = np.array([[-2.0, 2.0], [19.0, 21.0]])  # seen over about [-5.7, 5.7] degrees
    lo, hi, _, _ = g.view(far[None])
    # an occluder that covers a quarter of its angles, well in front
    half = 20.0 * math.tan((hi[0] - lo[0]) / 4)
    near = np.array([[-half, half], [9.0, 11.0]])
    a, b = g.view(far[None]), g.view(near[None])
    share = (b[1][0] - b[0][0]) / (a[1][0] - a[0][0])
    assert g.visible(far[None], near[None])[0] == pytest.approx(1.0 - min(1.0, 2.0 * share))


def test_boxes_behind_the_sensor_wrap_around_the_turn():
    g = SensorViewGeometry(sensor=np.zeros(2))
    far, near = box(-20, 0.0), box(-10, 0.0)  # straight behind: bearings near +-pi
    assert g.visible(far[None], near[None])[0] == pytest.approx(0.0)


def test_gated_pairs_give_the_dense_table_numbers():
    rng = np.random.default_rng(4)
    centres = rng.uniform(-60, 60, (120, 2))
    boxes = np.stack([box(x, z, rng.uniform(0.5, 3)) for x, z in centres])
    occluders = boxes[:50]
    g = SensorViewGeometry(sensor=np.zeros(2))
    weights = rng.uniform(0, 1, 50)
    skip = rng.integers(-1, 50, 120)
    sparse = g.visible(boxes, occluders, weights, skip)
    dense = g.visible(boxes, occluders, weights, skip, dense=True)
    assert 120 * 50 > 4096  # the gate is taken
    np.testing.assert_allclose(sparse, dense, rtol=0, atol=1e-12)
    assert (sparse < 1).sum() > 5  # some are hidden


class _Edges:
    def predicted_edges(self, means):
        return np.stack([means[:, :, 0] - means[:, :, 2], means[:, :, 0] + means[:, :, 2]],
                        axis=-1)


def _means(*centres):
    return np.array([[[x, 0, 1.0], [z, 0, 1.0]] for x, z in centres])


def test_object_wise_an_object_never_hides_itself_and_the_poisson_part_hides_nothing():
    model = SensorViewObjectWise(SensorViewGeometry(sensor=np.zeros(2)))
    means = _means((0, 10), (0, 20), (0, 30))
    owner = np.array([0, 1, -1])  # the farthest is the Poisson part's
    ctx = OcclusionContext(means, None, np.ones(3), owner, np.array([0.9, 0.9]),
                           np.zeros((0, 2, 2)), _Edges())
    terms = model.terms(ctx)
    assert terms.visible[0] == 1.0  # nothing in front of it
    assert terms.visible[1] == pytest.approx(0.1)  # behind object 0, existence .9
    assert terms.visible[2] == pytest.approx(0.01)  # behind both
    lone = OcclusionContext(means[:1], None, np.ones(1), np.array([0]), np.array([0.9]),
                            np.zeros((0, 2, 2)), _Edges())
    assert model.terms(lone).visible[0] == 1.0


def test_measurement_wise_the_seen_boxes_hide_the_components_and_each_other():
    model = SensorViewMeasurementWise(SensorViewGeometry(sensor=np.zeros(2)))
    means = _means((0, 20), (20, 20))
    z = np.stack([box(0, 10), box(0, 30)])
    ctx = OcclusionContext(means, None, np.ones(2), np.array([0, 1]), np.ones(2), z, _Edges())
    terms = model.terms(ctx)
    np.testing.assert_allclose(terms.hidden, [1.0, 0.0])
    np.testing.assert_allclose(terms.seen_hidden, [0.0, 1.0])  # the far one, behind the near
    np.testing.assert_array_equal(terms.visible, [1.0, 1.0])


def test_unknown_model_names_the_choices():
    with pytest.raises(ValueError, match="choose from none, object-wise, measurement-wise"):
        sensor_view_occlusion("both", SensorViewGeometry())


# -- the ground tracker ------------------------------------------------------------------------

def pose_at(x, z, yaw=0.0):
    """The camera at world (x, 0, z), turned by `yaw` about the vertical."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, 0, s, x], [0, 1, 0, 0], [-s, 0, c, z]])


def in_camera(world_xz, pose, shape=(1.5, 1.8, 4.2), world_yaw=0.0):
    """A KITTI box (7,) of a car at world (x, z) seen from `pose`."""
    R, t = pose[:, :3], pose[:, 3]
    p = R.T @ (np.array([world_xz[0], 1.6, world_xz[1]]) - t)
    v = R.T @ np.array([math.cos(world_yaw), 0, -math.sin(world_yaw)])
    return np.array([*shape, *p, math.atan2(-v[2], v[0])])


def test_ground_corners_follow_kitti_conventions():
    corners = ground_corners(np.array([[1.5, 2.0, 4.0, 1.0, 1.6, 10.0, 0.0]]))[0]
    np.testing.assert_allclose(np.sort(corners[:, 0]), [-1, -1, 3, 3])  # length along x
    np.testing.assert_allclose(np.sort(corners[:, 2]), [9, 9, 11, 11])
    np.testing.assert_allclose(corners[:, 1], 1.6)


@pytest.mark.parametrize("occlusion", ["none", "object-wise", "measurement-wise"])
def test_a_car_keeps_its_id_while_the_sensor_drives_100_m_and_turns(occlusion):
    """The frame re-centres on the sensor every frame: a parked car and one driving beside the
    sensor each keep one id over 100 m of the sensor's travel, with their boxes in place."""
    tracker = GroundTracker(TrackerConfig(fps=10.0, occlusion=occlusion))
    ids = {0: set(), 1: set()}
    for f in range(125):
        sensor = (0.0, 0.8 * f)  # 8 m/s: 100 m in 125 frames
        pose = pose_at(*sensor, yaw=0.2 * math.sin(f / 20))
        parked = (4.0, 60.0)
        beside = (-4.0, 0.8 * f + 15.0)
        truth = [parked, beside]
        boxes = np.array([in_camera(p, pose) for p in truth])
        visible = [abs(sensor[1] - parked[1]) < 70, True]
        tracks = tracker.update(boxes[visible], np.full(sum(visible), 0.9), pose=pose)
        for k, seen in enumerate(visible):
            if not seen:
                continue
            j = sum(visible[:k])
            mine = tracks.detection_index == j
            if f >= 5:
                assert mine.sum() == 1, (f, k)
                ids[k].add(int(tracks.ids[mine][0]))
                np.testing.assert_allclose(tracks.boxes3d[mine][0], boxes[j], atol=1e-9)
    assert len(ids[0]) == 1 and len(ids[1]) == 1


def _behind_a_parked_car(occlusion):
    """A car crossing at 30 m (6 m/s) behind a parked one at 12 m, the sensor driving towards
    them at 1 m/s: the crossing car is missed while the parked one hides it from the sensor
    (as the sensor's view has it at the true boxes). Per frame: hidden?, the crossing car's
    true box, the tracks."""
    tracker = GroundTracker(ground_config({"occlusion": occlusion}))
    g = SensorViewGeometry(sensor=np.zeros(2))
    out = []
    for f in range(60):
        pose = pose_at(0.0, 0.1 * f)
        parked, crossing = (0.0, 12.0), (-18.0 + 0.6 * f, 30.0)
        boxes = np.array([in_camera(parked, pose, world_yaw=math.pi / 2),
                          in_camera(crossing, pose)])
        corners = ground_corners(boxes)[:, :, [0, 2]]
        edges = np.stack([corners.min(axis=1), corners.max(axis=1)], axis=-1)
        hidden = g.visible(edges[1:], edges[:1])[0] < 0.5
        seen = boxes[:1] if hidden else boxes
        out.append((hidden, boxes[1], tracker.update(seen, np.full(len(seen), 0.95),
                                                     pose=pose)))
    return out


@pytest.mark.parametrize("occlusion", ["object-wise", "measurement-wise"])
def test_the_sensors_view_keeps_a_hidden_car_longer_than_none(occlusion):
    """Of the 16 hidden frames, none keeps the crossing car through 3 and the sensor's view
    (either model) through 7, reported as occluded, in place, at its velocity; then its
    coasting confidence (the chance its box is within IoU .5, which falls as the prediction
    spreads) goes under .5 and the car comes back under a second id."""
    runs = {name: _behind_a_parked_car(name) for name in ("none", occlusion)}
    hidden = np.array([h for h, _, _ in runs["none"]])
    assert 5 <= hidden.sum() <= 30 and not hidden[:10].any() and not hidden[-10:].any()
    kept = {}
    for name, frames in runs.items():
        ids, through = set(), 0
        for is_hidden, truth, tracks in frames:
            near = np.hypot(*(tracks.boxes3d[:, [3, 5]] - truth[[3, 5]]).T) < 1.5
            ids.update(tracks.ids[near].tolist())
            if is_hidden and near.any():
                through += 1
                assert tracks.coasting[near].all()
                assert tracks.occluded[near].all() == (name != "none")
        kept[name] = (through, len(ids))
    assert kept[occlusion][0] >= 7 > kept["none"][0] >= 1


def test_bad_boxes_are_refused_by_row():
    with pytest.raises(ValueError, match="row 1: h, w and l must be positive"):
        check_boxes3d([[1, 1, 1, 0, 0, 5, 0], [1, -2, 1, 0, 0, 5, 0]])
    with pytest.raises(ValueError, match="row 0 is not finite"):
        check_boxes3d([[1, 1, np.nan, 0, 0, 5, 0]])
    with pytest.raises(ValueError, match=r"\(M, 7\)"):
        check_boxes3d(np.zeros((2, 4)))
    with pytest.raises(ValueError, match="pose must be a finite 3 x 4"):
        GroundTracker().update(np.zeros((0, 7)), pose=np.eye(3))


def test_logits_become_probabilities_and_probabilities_stay():
    np.testing.assert_array_equal(detection_scores(np.array([0.2, 1.0])), [0.2, 1.0])
    np.testing.assert_allclose(detection_scores(np.array([-2.0, 0.0, 3.0])),
                               1 / (1 + np.exp([2.0, 0.0, -3.0])))


# -- occtrack track --3d -----------------------------------------------------------------------

LAYOUT_P2 = np.array([[721.5, 0, 609.6, 44.9], [0, 721.5, 172.9, 0.2], [0, 0, 1, 0.003]])
"""The P2 that `_layout` writes."""


def _layout(tmp_path, rows, frames, calib=True, poses=None):
    for sub in ("det_02/pr", "label_02", "seqinfo", "calib", "poses"):
        (tmp_path / sub).mkdir(parents=True, exist_ok=True)
    det = tmp_path / "det_02" / "pr" / "0000.txt"
    det.write_text("".join(r + "\n" for r in rows))
    (tmp_path / "seqinfo" / "0000.ini").write_text(
        f"[Sequence]\nname=0000\nframeRate=10\nseqLength={frames}\nimWidth=1242\n"
        f"imHeight=375\n")
    if calib:
        p2 = " ".join(f"{v:g}" for v in LAYOUT_P2.ravel())
        (tmp_path / "calib" / "0000.txt").write_text(
            f"P0: {p2}\nP1: {p2}\nP2: {p2}\nP3: {p2}\nR0_rect: 1 0 0 0 1 0 0 0 1\n"
            f"Tr_velo_to_cam: 0 -1 0 0 0 0 -1 0 1 0 0 0\n"
            f"Tr_imu_to_velo: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    lines = poses if poses is not None else frames
    (tmp_path / "poses" / "0000.txt").write_text(
        "1 0 0 0 0 1 0 0 0 0 1 0\n" * lines)
    return det


def _rows(frames, skip=()):
    out = []
    for f in range(frames):
        if f in skip:
            continue
        z = 20.0 - 0.5 * f
        out.append(f"{f} -1 Car -1 -1 0 500 150 600 220 1.5 1.7 4.0 1.0 1.6 {z} 0.1 4.0")
    return out


def test_track_3d_writes_kitti_3d_rows_and_projects_the_coasting_ones(tmp_path, capsys):
    det = _layout(tmp_path, _rows(12, skip=(9,)), 12)
    out = tmp_path / "out.txt"
    assert main(["track", str(det), "-o", str(out), "--3d", "--quiet"]) == 0
    result = read_kitti(out)
    assert len(np.unique(result.id)) == 1
    assert set(range(3, 12)) <= set(result.frame.tolist())
    coasting = result.frame == 9
    assert coasting.sum() == 1
    # the coasting box lies where the car drove, and its 2D box is its projection
    np.testing.assert_allclose(result.box3d[coasting][0, 5], 20.0 - 4.5, atol=0.3)
    assert not np.allclose(result.box[coasting][0], [500, 150, 600, 220])
    detected = ~coasting & (result.frame >= 3)
    np.testing.assert_allclose(result.box[detected], [[500, 150, 600, 220]] * detected.sum())
    again = tmp_path / "again.txt"
    main(["track", str(det), "-o", str(again), "--3d", "--quiet"])
    assert again.read_bytes() == out.read_bytes()  # same input, same bytes


def _one_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_track_3d_without_a_calibration_names_the_file(tmp_path, capsys):
    det = _layout(tmp_path, _rows(5), 5, calib=False)
    assert main(["track", str(det), "-o", str(tmp_path / "o.txt"), "--3d"]) != 0
    err = _one_error(capsys)
    assert "0000.txt" in err and "--calib FILE" in err


def test_track_3d_with_a_short_pose_file_names_it(tmp_path, capsys):
    det = _layout(tmp_path, _rows(5), 5, poses=3)
    assert main(["track", str(det), "-o", str(tmp_path / "o.txt"), "--3d"]) != 0
    err = _one_error(capsys)
    assert "poses" in err and "3 poses" in err


def test_track_3d_refuses_rows_without_3d_columns_by_line(tmp_path, capsys):
    rows = _rows(3) + ["3 -1 Car -1 -1 -10 500 150 600 220 -1 -1 -1 -1000 -1000 -1000 -10 0.9"]
    det = _layout(tmp_path, rows, 5)
    assert main(["track", str(det), "-o", str(tmp_path / "o.txt"), "--3d"]) != 0
    err = _one_error(capsys)
    assert f"{det}:4" in err and "3D columns" in err


def test_poses_without_3d_are_refused(tmp_path, capsys):
    det = _layout(tmp_path, _rows(3), 3)
    assert main(["track", str(det), "-o", str(tmp_path / "o.txt"), "--poses",
                 str(tmp_path / "poses" / "0000.txt")]) != 0
    assert "--poses, --calib and --lookahead go with --3d" in _one_error(capsys)


def test_track_3d_lookahead_zero_writes_each_frames_filtered_confidence(tmp_path, capsys):
    """`--lookahead 0` writes what `track_kitti(..., lookahead=0)` gives (the online
    tracker's reports); a negative lookahead, or one without --3d, is one clear error."""
    from occtrack.io.kitti_geometry import read_calib
    from occtrack.tracker.ground import track_kitti

    rows = [r.rsplit(" ", 1)[0] + f" {(-1.0, 0.5, 3.0)[i % 3]}" for i, r in enumerate(_rows(9))]
    det = _layout(tmp_path, rows, 9)
    out = tmp_path / "o.txt"
    assert main(["track", str(det), "-o", str(out), "--3d", "--quiet", "--lookahead", "0"]) == 0
    online = track_kitti(read_kitti(det), 9, None, None, read_calib(tmp_path / "calib" /
                                                                    "0000.txt"), (1242, 375),
                         lookahead=0.0)
    written = read_kitti(out)
    np.testing.assert_array_equal(written.frame, online.frame)
    np.testing.assert_allclose(written.score, online.score, atol=5e-5)  # (4 decimals)
    with pytest.raises(SystemExit) as exit_:
        main(["track", str(det), "-o", str(out), "--3d", "--lookahead=-1"])
    assert exit_.value.code == 2
    assert "-1 must be a finite number of seconds, 0 or more" in capsys.readouterr().err
    assert main(["track", str(det), "-o", str(out), "--force", "--lookahead", "0.2"]) != 0
    assert "--poses, --calib and --lookahead go with --3d" in _one_error(capsys)


# -- what an object's scores say ---------------------------------------------------------------

def test_the_score_log_likelihood_ratio_is_the_smoothed_shares():
    from occtrack.models.score_model import ScoreLearner

    learner = ScoreLearner()
    learner.objects[:] = np.arange(10.0)
    learner.clutter[:] = 9.0 - np.arange(10.0)
    shares_o = (np.arange(10.0) + 1) / (45 + 10)
    shares_c = (10.0 - np.arange(10.0)) / (45 + 10)
    np.testing.assert_allclose(learner.log_likelihood_ratio(np.array([0.05, 0.55, 1.0])),
                               np.log(shares_o / shares_c)[[0, 5, 9]], rtol=1e-12)


def test_a_track_of_clutter_like_scores_loses_its_confidence_and_a_real_one_keeps_it():
    """With score densities where a .15 score is 9 times likelier from clutter and a .95 one
    9 times likelier from an object, two parked cars detected every frame: the low-scoring
    one's evidence falls by log 9 a detection (less what is forgotten) and it goes from the
    report; the high-scoring one is reported throughout, its confidence the filter's times
    where log 9 a frame settles against the forgetting."""
    tracker = GroundTracker(ground_config({"occlusion": "none"}))
    learner = tracker._evidence_scores  # unit log-odds bins from logit(.05): .15 in 1, .95 in 5
    assert learner.bin_of(np.array([0.15, 0.95])).tolist() == [1, 5]
    learner.objects[:], learner.clutter[:] = 1e9, 1e9
    learner.objects[1], learner.clutter[1] = 1e9, 9e9
    learner.objects[5], learner.clutter[5] = 9e9, 1e9
    plain = GroundTracker(ground_config({"occlusion": "none"}), score_evidence=False)
    boxes = np.array([in_camera((-5.0, 20.0), np.eye(3, 4)), in_camera((5.0, 20.0), np.eye(3, 4))])
    scores = np.array([0.15, 0.95])
    for _ in range(30):
        weighed = tracker.update(boxes, scores)
        alone = plain.update(boxes, scores)
    assert len(alone) == 2
    assert weighed.detection_index.tolist() == [1]
    ratio = weighed.confidence[0] / alone.confidence[alone.detection_index == 1][0]
    # w log 9 a frame (w = SCORE_EVIDENCE_WEIGHT) against the forgetting (forget_evidence)
    # settles where o = forget(o) + w log 9, within 1e-4 after the frames reported here
    settled = 0.0
    for _ in range(100):
        settled = forget_evidence(settled, 0.1) + SCORE_EVIDENCE_WEIGHT * math.log(9)
    assert ratio == pytest.approx(1 / (1 + math.exp(-settled)), abs=1e-4)
    assert ratio > 0.99


def _chain_posterior(odds0, llr, elapsed, memory):
    """P(real at the first frame | its filtered odds and the later frames' ratios) by summing
    over every path of the two-state chain (2^(k + 1) of them)."""
    import itertools

    total = {True: 0.0, False: 0.0}
    for path in itertools.product((True, False), repeat=len(llr) + 1):
        weight = 1 / (1 + math.exp(-odds0)) if path[0] else 1 / (1 + math.exp(odds0))
        for k, (ratio, dt) in enumerate(zip(llr, elapsed, strict=True)):
            keep = math.exp(-2 * dt / memory)
            weight *= (1 + keep) / 2 if path[k] == path[k + 1] else (1 - keep) / 2
            weight *= math.exp(ratio) if path[k + 1] else 1.0
        total[path[0]] += weight
    return total[True] / (total[True] + total[False])


@pytest.mark.parametrize("seed", range(5))
def test_lookahead_evidence_is_the_chains_backward_message_by_enumeration(seed):
    """Filtered odds plus the backward message give P(real now | the later frames too),
    summed over every path of the chain; with no forgetting the later ratios simply add."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 6))
    odds0, llr = rng.normal(0, 2), rng.normal(0, 2, k)
    elapsed = rng.choice([0.1, 0.2, 1.5], k)
    b = lookahead_evidence(llr, elapsed, memory=3.0)
    assert 1 / (1 + math.exp(-odds0 - b)) == pytest.approx(
        _chain_posterior(odds0, llr, elapsed, 3.0), rel=1e-12)
    assert lookahead_evidence(llr, elapsed, memory=math.inf) == pytest.approx(llr.sum())
    assert lookahead_evidence([], []) == 0.0


def test_a_frame_looked_ahead_is_weighed_by_the_objects_later_scores():
    """`_looked_ahead`: each object's confidence times P(real | later) / P(real | so far),
    the later frames found by id (a frame that does not hold it is skipped, its time still
    counted); an object no later frame holds keeps its filtered confidence."""
    from occtrack.tracker.ground import GroundTracks, _looked_ahead

    def frame(ids, confidence, evidence, llr):
        n = len(ids)
        return GroundTracks(np.array(ids), np.zeros((n, 7)), np.ones(n), np.array(confidence),
                            np.zeros((n, 2)), np.zeros(n, int), np.zeros(n, int),
                            np.zeros(n, bool), np.array(evidence), np.array(llr))

    now = frame([4, 7], [0.3, 0.6], [-1.0, 2.0], [0.5, 0.5])
    later = [(6, frame([4], [0.5], [0.2], [1.2])), (7, frame([4], [0.6], [0.9], [-0.4]))]
    got = _looked_ahead(now, 5, later, dt=0.1)
    smoothed = _chain_posterior(-1.0, [1.2, -0.4], [0.1, 0.1], EVIDENCE_MEMORY)
    assert got[0] == pytest.approx(0.3 * smoothed * (1 + math.exp(1.0)), rel=1e-12)
    assert got[1] == 0.6
    gap = [(8, frame([4], [0.5], [0.2], [1.2]))]
    assert _looked_ahead(now, 5, gap, dt=0.1)[0] == pytest.approx(
        0.3 * _chain_posterior(-1.0, [1.2], [0.3], EVIDENCE_MEMORY) * (1 + math.exp(1.0)),
        rel=1e-12)


def test_track_kitti_without_lookahead_writes_the_online_trackers_reports(tmp_path):
    """lookahead 0: each frame's rows are what `GroundTracker.update` reports then (the
    floor applied to the filtered confidence); with the default lookahead the last frame,
    which has no later frames, is the same."""
    from occtrack.io.kitti_geometry import read_calib
    from occtrack.tracker.ground import track_kitti

    rows = _rows(14)
    rows = [r.rsplit(" ", 1)[0] + f" {(-1.0, 0.5, 3.0)[i % 3]}" for i, r in enumerate(rows)]
    det = read_kitti(_layout(tmp_path, rows, 14))
    calibration = read_calib(tmp_path / "calib" / "0000.txt")
    online = track_kitti(det, 14, None, None, calibration, (1242, 375), lookahead=0.0)
    tracker = GroundTracker()
    scores = detection_scores(det.score)
    for f in range(14):
        sel = det.frame == f
        tracks = tracker.update(det.box3d[sel], scores[sel], det.type[sel])
        np.testing.assert_array_equal(online.id[online.frame == f], tracks.ids)
        np.testing.assert_array_equal(online.score[online.frame == f], tracks.confidence)
    ahead = track_kitti(det, 14, None, None, calibration, (1242, 375))
    assert len(ahead) and np.array_equal(ahead.score[ahead.frame == 13],
                                         online.score[online.frame == 13])
    with pytest.raises(ValueError, match="lookahead must be"):
        track_kitti(det, 14, None, None, calibration, (1242, 375), lookahead=-1.0)


def test_forgotten_evidence_relaxes_towards_even_odds_exactly():
    """P - 1/2 shrinks by exp(-2 t / memory): at t = memory ln 2 / 2 it halves, so P = 3/4
    (log-odds ln 3) becomes 5/8 (ln 5/3); even odds stay even, the sign is symmetric, and
    odds that round P to 1 stay finite."""
    half = EVIDENCE_MEMORY * math.log(2) / 2
    assert forget_evidence(math.log(3), half) == pytest.approx(math.log(5 / 3), rel=1e-12)
    assert forget_evidence(-math.log(3), half) == pytest.approx(-math.log(5 / 3), rel=1e-12)
    assert forget_evidence(0.0, 100.0) == 0.0
    assert forget_evidence(2.5, 0.0) == 2.5
    big = forget_evidence(1000.0, 0.1)
    assert big == pytest.approx(2 * math.atanh(math.exp(-0.2 / EVIDENCE_MEMORY)), rel=1e-12)


def test_forgotten_evidence_is_the_two_state_chain_by_monte_carlo():
    """Chains that flip either way at the rate 1 / memory, started real with probability
    P0 = .9: the share real after t agrees with forget_evidence's P within 4 standard
    errors."""
    rng = np.random.default_rng(11)
    n, memory, t, p0 = 200_000, 10.0, 3.0, 0.9
    real = rng.random(n) < p0
    flips = rng.poisson(t / memory, n)  # flips in [0, t] of a Poisson clock at rate 1 / memory
    share = np.mean(real ^ (flips % 2 == 1))
    expected = 1 / (1 + math.exp(-forget_evidence(math.log(p0 / (1 - p0)), t, memory)))
    assert abs(share - expected) < 4 * math.sqrt(expected * (1 - expected) / n)


def test_a_car_that_began_with_clutter_like_scores_is_lifted_by_good_ones():
    """Ten clutter-like scores (9 times likelier from clutter), then top ones (9 times
    likelier from an object): the confidence is the filter's times the forward recursion of
    the two-state chain, o <- forget_evidence(o, dt) + llr, and the car is back above even
    odds after the good scores outweigh the forgotten bad ones."""
    config = ground_config({"occlusion": "none", "report_min_confidence": 0.0})
    tracker = GroundTracker(config)
    learner = tracker._evidence_scores
    learner.objects[:], learner.clutter[:] = 1e9, 1e9
    learner.objects[1], learner.clutter[1] = 1e9, 9e9
    learner.objects[5], learner.clutter[5] = 9e9, 1e9
    plain = GroundTracker(config, score_evidence=False)
    box = np.array([in_camera((0.0, 20.0), np.eye(3, 4))])
    odds, seen, ratios = 0.0, False, []
    for k in range(30):
        score = np.array([0.15 if k < 10 else 0.95])
        weighed, alone = tracker.update(box, score), plain.update(box, score)
        if len(alone):
            odds = (forget_evidence(odds, 0.1) if seen else 0.0) + SCORE_EVIDENCE_WEIGHT * (
                -math.log(9) if k < 10 else math.log(9))
            seen = True
            ratios.append((weighed.confidence[0] / alone.confidence[0],
                           1 / (1 + math.exp(-odds))))
    got, want = np.array(ratios).T
    np.testing.assert_allclose(got, want, rtol=1e-6)
    assert want[-1] > 0.99 and min(want) < 0.01


def test_log_odds_bins_are_a_unit_of_log_odds_wide_from_the_floor():
    from occtrack.models.score_model import ScoreLearner

    learner = ScoreLearner(score_floor=0.05, log_odds=True)
    start = math.log(0.05 / 0.95)
    logits = np.array([start - 3, start + 0.01, start + 0.99, start + 1.01, start + 9.5, 40.0])
    scores = 1 / (1 + np.exp(-logits))
    assert learner.bin_of(scores).tolist() == [0, 0, 0, 1, 9, 9]
    plain = ScoreLearner(score_floor=0.05)
    assert plain.bin_of(scores[3:5]).tolist() == [1, 9]  # the probability bins: .1 wide


def test_ground_defaults_keep_a_hidden_objects_velocity():
    assert ground_config().coast_velocity_time == math.inf
    assert ground_config({"coast_velocity_time": 0.5}).coast_velocity_time == 0.5
    assert GroundTracker().config.fps == 10.0


def test_what_the_ground_tracker_remembers_is_bounded_by_the_scene():
    """A car passes every 3 s for 5 minutes (100 objects): the shapes and the scores'
    evidence kept per id stay those of the last SHAPE_MEMORY seconds' objects, not of all."""
    from occtrack.tracker.ground import SHAPE_MEMORY

    tracker = GroundTracker(ground_config({"occlusion": "none"}))
    seen, most = set(), 0
    for f in range(3000):
        t = (f % 30) / 10.0  # a new car each 3 s, driving past at 10 m/s
        car = (-15.0 + 10.0 * t, 20.0)
        tracks = tracker.update(in_camera(car, np.eye(3, 4))[None], [0.95])
        seen.update(tracks.ids.tolist())
        most = max(most, len(tracker._shape), len(tracker._evidence), len(tracker._size))
    assert len(seen) >= 75
    assert most <= SHAPE_MEMORY / 3.0 + 2


def test_one_object_reported_under_two_classes_is_one_track_with_a_count():
    """A cyclist that the detector also reports, lower scored, as a pedestrian at the same
    place: one track, of the cyclist's class, on the cyclist's row; each walker box counted."""
    tracker = GroundTracker(ground_config({"occlusion": "none"}))
    for f in range(10):
        z = 15.0 + 0.5 * f
        walker = [1.7, 0.6, 0.8, 0.1, 1.6, z + 0.1, 0.0]
        cyclist = [1.7, 0.6, 1.8, 0.0, 1.6, z, 0.0]
        tracks = tracker.update(np.array([walker, cyclist]), [0.8, 0.99], [3, 5])
    assert tracker.duplicates_dropped == 10
    assert len(tracks) == 1 and tracks.classes.tolist() == [5]
    assert tracks.detection_index.tolist() == [1]  # the given row, not the kept one's
    np.testing.assert_allclose(tracks.boxes3d[0], cyclist)
    both = GroundTracker(ground_config({"occlusion": "none"}), duplicate_overlap=None)
    for f in range(10):
        z = 15.0 + 0.5 * f
        tracks = both.update(np.array([[1.7, 0.6, 0.8, 0.1, 1.6, z + 0.1, 0.0],
                                       [1.7, 0.6, 1.8, 0.0, 1.6, z, 0.0]]), [0.8, 0.99], [3, 5])
    assert sorted(tracks.classes.tolist()) == [3, 5] and both.duplicates_dropped == 0
    with pytest.raises(ValueError, match="duplicate_overlap"):
        GroundTracker(duplicate_overlap=1.5)


def test_track_3d_says_how_many_duplicates_it_dropped(tmp_path, capsys):
    rows = []
    for f in range(6):
        z = 20.0 - 0.5 * f
        rows.append(f"{f} -1 Car -1 -1 0 500 150 600 220 1.5 1.7 4.0 1.0 1.6 {z} 0.1 4.0")
        rows.append(f"{f} -1 Cyclist -1 -1 0 505 150 600 220 1.5 1.0 1.8 1.2 1.6 {z} 0.1 -1")
    det = _layout(tmp_path, rows, 6)
    out = tmp_path / "out.txt"
    assert main(["track", str(det), "-o", str(out), "--3d"]) == 0
    err = capsys.readouterr().err
    assert "6 boxes dropped as the duplicate of a higher-scored box" in err and str(det) in err
    assert set(read_kitti(out).type.tolist()) == {0}  # the cars only


def test_track_3d_classes_writes_the_picked_types_and_still_sees_the_others(tmp_path, capsys):
    """--classes Pedestrian: the cyclist is tracked (not written), so the walker box that
    duplicates it is dropped and no pedestrian track follows the cyclist."""
    rows = []
    for f in range(8):
        z = 12.0 + 0.3 * f
        rows.append(f"{f} -1 Cyclist -1 -1 0 500 150 600 300 1.7 0.6 1.8 0.0 1.6 {z} 0.0 5.0")
        rows.append(f"{f} -1 Pedestrian -1 -1 0 505 150 600 300 1.7 0.6 0.8 0.1 1.6 {z} 0 2.0")
        rows.append(f"{f} -1 Pedestrian -1 -1 0 800 150 850 300 1.7 0.6 0.8 4.0 1.6 15 0 5.0")
    det = _layout(tmp_path, rows, 8)
    out = tmp_path / "out.txt"
    assert main(["track", str(det), "-o", str(out), "--3d", "--classes", "Pedestrian"]) == 0
    err = capsys.readouterr().err
    assert "8 rows of types not picked (--classes) tracked, their tracks not written" in err
    assert "8 boxes dropped as the duplicate" in err
    result = read_kitti(out)
    assert set(result.type.tolist()) == {3} and len(np.unique(result.id)) == 1
    np.testing.assert_allclose(result.box3d[:, 3], 4.0)  # the walker standing apart


def _row(frame: int, kind: str, box2d, box3d, score: float = 4.0) -> str:
    """One KITTI detection line: its 2D box x1 y1 x2 y2 and 3D box h w l x y z rotation_y."""
    numbers = " ".join(f"{v:.4f}" for v in (*box2d, *box3d))
    return f"{frame} -1 {kind} -1 -1 0 {numbers} {score}"


def test_a_walker_is_drawn_as_the_cylinder_in_its_box_unless_its_2d_box_is_its_own(tmp_path):
    """A person fills the elliptic cylinder inscribed in the 3D box, not its corners: a
    walker whose 2D box is only its 3D box's corners projected (as PointRCNN writes it) is
    written with the cylinder's box; a walker with a 2D box of the detector's own, and a car,
    keep theirs."""
    from occtrack.io.kitti_geometry import project_boxes, project_cylinders

    p2 = LAYOUT_P2
    rows, own = [], [300.0, 120.0, 330.0, 220.0]
    for f in range(6):
        walker = np.array([1.7, 0.6, 0.8, -2.0, 1.6, 12.0 + 0.1 * f, 0.8])
        corners = project_boxes(walker[None], p2, (1241, 374))[0]
        other = walker + [0, 0, 0, -4.0, 0, 0, 0]
        car = np.array([1.5, 1.7, 4.0, 4.0, 1.6, 20.0 - 0.5 * f, 0.1])
        rows += [_row(f, "Pedestrian", corners, walker), _row(f, "Pedestrian", own, other),
                 _row(f, "Car", [700, 150, 800, 220], car)]
    det = _layout(tmp_path, rows, 6)
    out = tmp_path / "out.txt"
    assert main(["track", str(det), "-o", str(out), "--3d", "--quiet"]) == 0
    result = read_kitti(out)
    last = result.frame == 5
    assert last.sum() == 3
    for box, box3d, kind in zip(result.box[last], result.box3d[last], result.type[last],
                                strict=True):
        if kind == 0:
            np.testing.assert_allclose(box, [700, 150, 800, 220])
        elif box3d[3] < -4:
            np.testing.assert_allclose(box, own)
        else:
            cylinder = project_cylinders(box3d[None], p2)[0]
            np.testing.assert_allclose(box, cylinder, atol=0.006)  # (2 decimals)
            corners = project_boxes(box3d[None], p2, (1242, 375))[0]
            assert box[2] - box[0] < 0.9 * (corners[2] - corners[0])  # turned 0.8 rad


def test_an_objects_size_is_its_detections_mean_weighted_by_one_over_range_squared():
    """Sizes read at 10 m and 40 m weigh 16 to 1 (a lidar's points fall off as 1 / r^2); a box
    nearer than SIZE_NEAR weighs as if it were that far; each object keeps its own sums."""
    from occtrack.tracker.ground import SIZE_NEAR

    tracker = GroundTracker()
    near = np.array([[1.5, 1.6, 4.0, 6.0, 1.6, 8.0, 0.0]])  # range 10 m
    far = np.array([[1.7, 2.0, 4.8, 0.0, 1.6, 40.0, 0.0]])
    tracker._add_sizes(np.array([7]), near)
    np.testing.assert_allclose(tracker.mean_sizes(np.array([7])), near[:, :3])
    tracker._add_sizes(np.array([7]), far)
    both = tracker.mean_sizes(np.array([7]))
    np.testing.assert_allclose(both, (16 * near[:, :3] + far[:, :3]) / 17, rtol=1e-12)
    close = np.array([[1.6, 1.8, 4.4, 0.0, 1.6, 1.0, 0.0]])  # 1 m: weighs as SIZE_NEAR
    tracker._add_sizes(np.array([8, 7]), np.concatenate([close, close]))
    again = tracker.mean_sizes(np.array([8, 7]))
    np.testing.assert_allclose(again[0], close[0, :3])
    w = np.array([1 / 100, 1 / 1600, 1 / SIZE_NEAR**2])
    np.testing.assert_allclose(again[1], (w[0] * near[0, :3] + w[1] * far[0, :3]
                                          + w[2] * close[0, :3]) / w.sum(), rtol=1e-12)


def test_a_car_whose_2d_box_is_its_3d_box_projected_is_drawn_at_its_mean_size(tmp_path):
    """A parked car whose detected length alternates 3.6 / 4.4 m at one range: the 3D box
    written has the running mean length, and where the detector's 2D box is only its 3D box's
    corners projected (as PointRCNN's is) the written 2D box is the written 3D box's
    projection; the 2D box a detector found in the image is kept."""
    from occtrack.io.kitti_geometry import project_boxes

    p2 = LAYOUT_P2
    rows, lengths = [], []
    for f in range(8):
        length = 3.6 if f % 2 == 0 else 4.4
        lengths.append(length)
        car = np.array([1.5, 1.7, length, -3.0, 1.6, 15.0, 0.5])
        drawn = project_boxes(car[None], p2, (1241, 374))[0]
        other = car + [0, 0, 0, 7.0, 0, 0, 0]
        rows += [_row(f, "Car", drawn, car), _row(f, "Car", [700, 150, 800, 220], other)]
    det = _layout(tmp_path, rows, 8)
    out = tmp_path / "out.txt"
    assert main(["track", str(det), "-o", str(out), "--3d", "--quiet"]) == 0
    result = read_kitti(out)
    assert len(np.unique(result.id)) == 2 and set(result.frame.tolist()) == set(range(8))
    for frame, box, box3d in zip(result.frame, result.box, result.box3d, strict=True):
        if box3d[3] > 0:
            np.testing.assert_allclose(box, [700, 150, 800, 220])
            continue
        assert box3d[2] == pytest.approx(np.mean(lengths[:frame + 1]), abs=0.01)
        np.testing.assert_allclose(box, project_boxes(box3d[None], p2, (1242, 375))[0],
                                   atol=0.02)


def test_the_evidence_weight_scales_each_frames_ratio():
    """With weight w the evidence of one frame is w times the learner's log-likelihood ratio
    (the first frame's odds start even, nothing to forget); a negative weight is refused."""
    box = np.array([in_camera((0.0, 20.0), np.eye(3, 4))])
    seen = {}
    for weight in (1.0, 0.25):
        tracker = GroundTracker(ground_config({"occlusion": "none",
                                               "report_min_confidence": 0.0}),
                                evidence_weight=weight)
        learner = tracker._evidence_scores
        learner.objects[:], learner.clutter[:] = 1e9, 1e9
        learner.objects[1], learner.clutter[1] = 1e9, 9e9  # (even totals: .95 is 9 to 1)
        learner.objects[5], learner.clutter[5] = 9e9, 1e9
        for _ in range(3):
            tracks = tracker.update(box, np.array([0.95]))
        seen[weight] = tracks.score_llr[0]
    assert seen[1.0] == pytest.approx(math.log(9), rel=1e-6)
    assert seen[0.25] == pytest.approx(0.25 * math.log(9), rel=1e-6)
    with pytest.raises(ValueError, match="evidence_weight must be"):
        GroundTracker(evidence_weight=-1.0)
