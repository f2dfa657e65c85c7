"""The PMB box tracker: occlusion through a gap, invariants, repeatability, settings."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.mot import write_mot
from occtrack.metrics.gospa import iou
from occtrack.models.box import edges_from_ltwh
from occtrack.occlusion.base import OcclusionTerms
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry, combine
from occtrack.scenarios.pedestrians import Crowd, crossing_pair, crowd_scene
from occtrack.tracker import Tracker, TrackerConfig


def track_of(scene, result, person, frames):
    """The id matched (IoU >= 0.5) to truth id `person` at each of `frames` (0: none)."""
    ids = []
    for f in frames:
        t = (scene.truth.frame == f) & (scene.truth.id == person)
        r = result.frame == f
        overlap = iou(scene.truth.box[t], result.box[r])
        best = overlap.argmax() if overlap.size else -1
        ids.append(int(result.id[r][best]) if best >= 0 and overlap[0, best] >= 0.5 else 0)
    return ids


def gap_frames(scene, person=1, other=2):
    """Tracked frames (odd) where the person overlaps the other one and is not detected."""
    gap = []
    for f in range(1, scene.frames + 1, 2):
        t = scene.truth.frame == f
        a = scene.truth.box[t & (scene.truth.id == person)]
        b = scene.truth.box[t & (scene.truth.id == other)]
        d = scene.detections.box[scene.detections.frame == f]
        if iou(a, b).max() > 0 and not (iou(a, d) >= 0.5).any():
            gap.append(f)
    return gap


def existence_over_gap(scene, occlusion):
    """The track id of person 1 before the gap, its existence at each gap frame (0 once its
    Bernoulli is gone) and the id matched to the person after the gap."""
    gap = gap_frames(scene)
    tracker = Tracker(TrackerConfig(occlusion=occlusion))
    label, existence, after = None, [], None
    slices = scene.detections.frame_slices(scene.frames)
    for frame, rows in enumerate(slices, start=1):
        tracks = tracker.step(scene.detections.box[rows], scene.detections.score[rows])
        f = tracker.filter
        if frame == gap[0] - 10:
            label = track_of_tracks(scene, tracks, frame)
        if gap[0] <= frame <= gap[-1]:
            slot = np.flatnonzero(f.slot_used & (tracker._report_id == label)
                                  & (tracker._reported_serial == f.slot_serial))
            existence.append(float(f.existence()[slot[0]]) if len(slot) else 0.0)
        if frame == gap[-1] + 30:
            after = track_of_tracks(scene, tracks, frame)
    return label, np.array(existence), after


def track_of_tracks(scene, tracks, frame, person=1):
    truth = scene.truth.box[(scene.truth.frame == frame) & (scene.truth.id == person)]
    overlap = iou(truth, tracks.boxes)
    return int(tracks.ids[overlap.argmax()]) if overlap.size and overlap.max() >= 0.5 else 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hidden_pedestrian_keeps_its_label_with_occlusion(seed):
    """A person walks behind another for about a second (no detection). Either occlusion
    model keeps the person's Bernoulli alive through the gap and the same id after it;
    without occlusion its existence falls with every miss (the id may be recovered only
    because a weak Bernoulli is kept)."""
    scene = crossing_pair(seed)
    assert len(gap_frames(scene)) >= 8
    plain = existence_over_gap(scene, "none")[1]
    assert plain.min() < 0.1
    for occlusion in ("object-wise", "measurement-wise"):
        label, existence, after = existence_over_gap(scene, occlusion)
        assert label > 0 and after == label
        assert existence.mean() > plain.mean() + 0.1


@pytest.mark.filterwarnings("ignore:max_labels = 24")  # hard limits on purpose
def test_existence_in_unit_interval_and_labels_unique():
    scene = crowd_scene(Crowd(people=20, frames=160), seed=3)
    # every object above report_existence that took a detection is reported (no confidence rule)
    tracker = Tracker(TrackerConfig(occlusion="measurement-wise", capacity=512,
                                    max_labels=24, report_min_confidence=0.0))
    serial_of_id = {}
    for rows in scene.detections.frame_slices(scene.frames)[::2]:
        tracks = tracker.step(scene.detections.box[rows], scene.detections.score[rows])
        f = tracker.filter
        r = f.existence()
        assert (r >= 0).all() and (r <= 1).all()
        assert (f.mass[:f.n] >= 0).all() and f.n <= 512 and f.slot_used.sum() <= 24
        labelled = f.label[:f.n][f.label[:f.n] >= 0]
        assert np.bincount(labelled).max(initial=0) <= 16
        assert (f.det[:f.n] >= 0).all() and (f.det[:f.n] <= 1).all()
        assert len(np.unique(tracks.ids)) == len(tracks.ids)
        assert ((tracks.existence > 0.5) & (tracks.existence <= 1)).all()
        shown = np.flatnonzero(f.slot_used & (r > 0.5))
        assert set(tracks.ids) <= set(tracker._report_id[shown])
        detected = np.flatnonzero(f.slot_used & (r > 0.5) & (f.slot_detection >= 0))
        assert set(tracker._report_id[detected]) <= set(tracks.ids)
        for slot in shown:
            track_id, serial = int(tracker._report_id[slot]), int(f.slot_serial[slot])
            assert serial_of_id.setdefault(track_id, serial) == serial
    assert len(serial_of_id) >= 20


def test_run_is_byte_for_byte_repeatable(tmp_path):
    outputs = []
    for attempt in range(2):
        scene = crowd_scene(Crowd(people=15, frames=120), seed=7)
        result = Tracker(TrackerConfig(occlusion="object-wise")).run(scene.detections,
                                                                     scene.frames)
        path = tmp_path / f"run{attempt}.txt"
        write_mot(path, result.frame, result.id, result.box, result.existence)
        outputs.append(path.read_bytes())
    assert outputs[0] == outputs[1] and len(outputs[0]) > 1000


def test_missed_object_existence_follows_the_miss_term():
    """One object, well tracked; then its detection is gone and a much bigger box in front
    hides it. Existence must follow r' = sum w P_S miss / (1 - sum w P_S + sum w P_S miss),
    miss_k = 1 - d_k + d_k o_k q_k with d, o predicted and q from the box geometry."""
    config = TrackerConfig(occlusion="measurement-wise")
    tracker = Tracker(config)
    person = np.array([[900.0, 400.0, 40.0, 120.0]])
    for step in range(12):
        tracker.step(person + [[4.0 * step, 0, 0, 0]])
    f = tracker.filter
    mine = f.label[:f.n] == np.flatnonzero(f.slot_used)[0]
    mass, det, occ = f.mass[:f.n][mine], f.det[:f.n][mine], f.occ[:f.n][mine]
    mean, cov = f.motion.predict(f.mean[:f.n][mine], f.cov[:f.n][mine])
    det = f.detectability.predict(det, config.dt)
    occ = f.occludability.predict(occ, config.dt)
    mass = mass * np.exp(-config.death_rate * config.dt)
    wall = np.array([[800.0, 150.0, 300.0, 600.0]])
    q = combine(BoxOcclusionGeometry()(f.measurement.predicted_edges(mean),
                                       edges_from_ltwh(wall)))
    miss = 1 - det + det * occ * q
    expected = (mass * miss).sum() / (1 - mass.sum() + (mass * miss).sum())
    assert 0.3 < expected < 0.999
    tracker.step(wall)
    r = tracker.filter.existence()
    assert r.max() == pytest.approx(expected, rel=1e-6)


def test_a_detection_where_it_could_have_been_hidden_weighs_occludability():
    """Measurement-wise occlusion with occludability: a detection z_j seen where the other
    detections would hide an occludable measurement with probability h_j came from a source
    that was not occludable or escaped, so each hit term carries 1 - o_k h_j (clutter:
    1 - o h_j with the stationary o) and P(O = 1 | hit) = o (1 - h_j) / (1 - o h_j).
    One tracked object, then its detection beside a box in front that covers a quarter of it:
    the existence and the hit child's occludability must follow these sums exactly."""
    config = TrackerConfig(occlusion="measurement-wise")
    tracker = Tracker(config)
    person = np.array([[900.0, 400.0, 40.0, 120.0]])
    for step in range(12):
        tracker.step(person + [[4.0 * step, 0, 0, 0]])
    seen = np.array([[964.0, 400.0, 40.0, 120.0], [994.0, 150.0, 300.0, 600.0]])
    z = edges_from_ltwh(seen)
    h = combine(BoxOcclusionGeometry()(z[:1], z[1:]))[0]
    assert h == pytest.approx(0.5, abs=0.01)  # 10 of 40 px covered, gain 2, bottom far lower

    f = copy.deepcopy(tracker.filter)  # the prior of the next update, computed separately
    f._predict()
    f._add_births()
    n = f.n
    mass, det, occ, label = f.mass[:n], f.det[:n], f.occ[:n], f.label[:n]
    mine = label == np.flatnonzero(f.slot_used)[0]
    poisson = label < 0
    boxes = f.measurement.predicted_edges(f.mean[:n])
    q = combine(BoxOcclusionGeometry()(boxes, z))
    miss = 1 - det + det * occ * q
    hidden_z = np.array([h, 0.0])
    lik = np.exp(f.measurement.loglik(f.mean[:n], f.cov[:n], z, f.measurement.observed(z)))
    hit = mass[:, None] * det[:, None] * (1 - occ[:, None] * hidden_z) * lik
    W, H = config.image_size
    clutter = config.clutter_rate / (W * H * seen[:, 2] * seen[:, 3]) * (
        1 - config.occludability * hidden_z)
    new = clutter + hit[poisson].sum(axis=0)
    r, miss_sum = mass[mine].sum(), (mass * miss)[mine].sum()
    odds = hit[mine].sum(axis=0) / new  # the object against clutter or a new object
    total = 1 - r + miss_sum + odds.sum()
    expected_r = (miss_sum + odds.sum()) / total
    assert odds[0] / total > 0.9  # the object takes its detection
    share = hit[mine, 0] / hit[mine, 0].sum()
    o = occ[mine]
    expected_o = (share * o * (1 - h) / (1 - o * h)).sum()

    tracker.step(seen)
    g = tracker.filter
    slot = np.flatnonzero(g.slot_used & (g.existence() > 0.5))
    assert len(slot) == 1
    assert g.existence()[slot[0]] == pytest.approx(expected_r, rel=1e-6)
    comps = np.flatnonzero((g.label[:g.n] == slot[0]) & (g.det[:g.n] > 1 - 1e-12))
    # (each object keeps its 16 heaviest components, rescaled: the hit share moves a little)
    assert g.mass[comps].sum() == pytest.approx(odds[0] / total, rel=1e-4)
    hit_o = (g.mass[comps] * g.occ[comps]).sum() / g.mass[comps].sum()
    assert hit_o == pytest.approx(expected_o, rel=1e-6)
    assert hit_o < o.mean() - 0.1  # seen where it could have been hidden: less occludable


class Wall:
    """A fourth occlusion model, unknown to the filter: everything left of x = 960 is hidden."""

    name = "wall"

    def terms(self, ctx):
        boxes = ctx.measurement_model.predicted_edges(ctx.means)
        visible = (boxes[:, 0, 1] > 960).astype(float)
        return OcclusionTerms(visible, np.zeros(len(ctx.means)))


def test_a_new_occlusion_model_plugs_in_without_filter_changes():
    """A person walks left into the wall's shadow, where detections stop."""
    frames = [np.array([[1200.0 - 20 * k, 400.0, 40.0, 120.0]]) if k < 16 else np.zeros((0, 4))
              for k in range(40)]
    results = {}
    for name, model in (("none", None), ("wall", Wall())):
        config = TrackerConfig(occlusion="none", frame_step=1, fps=15,
                               report_min_confidence=0.0)  # every object the filter holds
        results[name] = Tracker(config, occlusion=model).run(frames)
    assert set(results["wall"].frame) == set(range(1, 41))
    assert results["wall"].id.tolist() == [1] * 40
    assert results["none"].frame.max() < 22


def test_frames_between_tracked_ones_carry_tracks_along():
    config = TrackerConfig(frame_step=3, fps=30)
    frames = [np.array([[300.0 + 10 * k, 400.0, 40.0, 120.0, 0.9]]) for k in range(30)]
    result = Tracker(config).run(frames)
    assert result.frames == 30
    left = {int(f): result.box[result.frame == f][0, 0] for f in result.frame}
    # frames 1, 4, ..., 28 are tracked; 29 and 30 are frame 28's tracks moved on
    assert left[30] - left[29] == pytest.approx(left[29] - left[28], abs=1e-9)
    assert left[29] - left[28] == pytest.approx(10.0, abs=1.5)


def _tall_person(extrapolated: bool) -> list:
    """A person taller than a 640 x 480 image, walking right at 3 px a frame, as a detector
    that does not clip reports them (YOLOX on MOT17-05): top and bottom beyond the image, the
    right edge from the border on past it; edges 4 px noisy. Each frame's (ids, boxes), and
    the detection."""
    rng = np.random.default_rng(0)
    config = TrackerConfig(image_size=(640, 480), fps=14.0, extrapolated_edges=extrapolated)
    tracker, out = Tracker(config), []
    for k in range(40):
        truth = np.array([400.0 + 3.0 * k, -100.0, 240.0, 680.0])
        low = truth[:2] + rng.normal(0.0, 4.0, 2)
        high = truth[:2] + truth[2:] + rng.normal(0.0, 4.0, 2)
        detection = np.r_[low, high - low][None]
        tracks = tracker.step(detection, np.array([0.8]))
        out.append((tracks.ids, tracks.boxes, detection))
    return out


def test_edges_a_detector_placed_beyond_the_image_are_measured():
    """Measured, the beyond-border edges hold the box: one id from the third frame on (its
    existence passes 1/2 with the third detection), reported with the detection's box
    exactly. Censored, only the left edge and part of the right one are measured and no
    track is held."""
    kept = _tall_person(True)
    assert all(len(ids) == 0 for ids, _, _ in kept[:2])
    for ids, boxes, detection in kept[2:]:
        assert ids.tolist() == [1]
        np.testing.assert_array_equal(boxes, detection)
    censored = _tall_person(False)
    assert sum(len(ids) for ids, _, _ in censored[10:]) <= 1


def test_step_rejects_bad_boxes():
    tracker = Tracker()
    with pytest.raises(ValueError, match="shape"):
        tracker.step(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="NaN"):
        tracker.step(np.array([[1.0, 2.0, np.nan, 4.0]]))
    with pytest.raises(ValueError, match="negative"):
        tracker.step(np.array([[1.0, 2.0, -3.0, 4.0]]))
    assert len(tracker.step(np.zeros((0, 4)))) == 0


def test_config_defaults_follow_the_paper():
    assert TrackerConfig(occlusion="none").stationary_detectability == 0.9
    c = TrackerConfig()
    assert c.stationary_detectability == 0.93
    assert (c.capacity, c.max_labels) == (0, 0)  # grow with the scene (the paper: 2048, 72)
    assert c.edge_noise * 175 == pytest.approx(12.0, abs=0.1)  # 12 px at MOT17-04's median
    assert (c.occludability, c.occludability_ratio, c.report_existence) == (0.8, 0.8, 0.5)
    assert c.dt == pytest.approx(1 / 30)  # every frame
    assert c.velocity_time == float("inf")  # constant velocity


def test_config_from_toml(tmp_path):
    path = tmp_path / "tracker.toml"
    path.write_text('occlusion = "object-wise"\nimage_size = [1280, 720]\ncapacity = 512\n'
                    'edge_noise = 0.05\nvelocity_time = 1\n')
    c = TrackerConfig.from_toml(path, frame_step=2)
    assert (c.occlusion, c.image_size, c.capacity, c.edge_noise, c.frame_step) == \
        ("object-wise", (1280.0, 720.0), 512, 0.05, 2)
    assert c.velocity_time == 1.0 and Tracker(c).filter.motion.F[1, 1] < 1


@pytest.mark.parametrize("text,message", [
    ("edge_sd = 3\n", "unknown setting 'edge_sd'"),
    ("capacity = 2.5\n", "capacity must be an integer"),
    ("image_size = [1, 2, 3]\n", "image_size must be a pair"),
    ('occlusion = "grid"\n', "occlusion must be one of"),
    ("report_existence = 1.5\n", "report_existence must be a probability"),
    ("edge_noise = 0\n", "edge_noise must be a positive number"),
    ('camera_motion = "orb"\n', "camera_motion must be one of"),
    ("confirm_hits = 6\n", "confirm_hits must be between 1 and confirm_window"),
    ("lbp_max_iterations = 100000000\n", "lbp_max_iterations must be between 1 and 100000"),
    ("capacity = 100000000\n", "capacity must be between 0 and 10000000"),
    ("capacity = 1e8\n", "capacity must be an integer, not 100000000.0"),
    ("frame_step = 2.5\n", "frame_step must be an integer, not 2.5"),
    ("frame_step = 0\n", "frame_step must be between 1 and 10000"),
    ("velocity_time = 0\n", "velocity_time must be a positive number of seconds"),
    ("edge_noise = \n", "not valid TOML"),
])
def test_config_errors_name_the_file(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(OcctrackError, match=message) as err:
        TrackerConfig.from_toml(path)
    assert str(err.value).startswith(f"{path}: ")


def test_run_streams_frames_and_refuses_a_path():
    """`run` reads a generator one frame at a time (never a list of all), and a file name
    is refused with a pointer to the reader, not iterated character by character."""
    seen = []

    def frames():
        for k in range(12):
            seen.append(k)
            yield np.array([[300.0 + 5 * k, 400.0, 40.0, 120.0, 0.9]])

    tracker = Tracker()
    step = tracker.step
    read_when_stepped = []

    def counting_step(*args, **kwargs):
        read_when_stepped.append(len(seen))
        return step(*args, **kwargs)

    tracker.step = counting_step
    result = tracker.run(frames())
    assert result.frames == 12 and read_when_stepped == list(range(1, 13))
    with pytest.raises(ValueError, match="read_detections"):
        Tracker().run("det.txt")
