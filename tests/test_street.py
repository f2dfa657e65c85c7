"""The demo's street (occtrack.scenarios.street) and its scores (occtrack.experiments.demo):
the detector gives back, under `occtrack calibrate`'s own measurement, the MOT17 values it was
built from; full occlusions and identities kept through them are counted as documented."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.config.street import StreetDetector, StreetMotion
from occtrack.experiments.demo import Spell, full_occlusions, kept
from occtrack.io.mot import MotTable
from occtrack.models.calibration import Labelled, calibrate
from occtrack.scenarios.street import Street, StreetScene, cover_by_nearer, street_scene


@pytest.fixture(scope="module")
def street() -> StreetScene:
    return street_scene(Street(people=16, frames=900), seed=3)


def test_calibrate_gives_back_the_detector(street):
    """What `occtrack calibrate` measures on the street is what the street was given."""
    cal = calibrate([Labelled("street", street.truth, street.detections, street.image_size,
                              street.fps, street.frames)], seed=0)
    det = StreetDetector()
    for (lo, _hi, est), want in zip(cal.by_visibility, det.detect_by_visibility, strict=True):
        if est.n > 300:
            assert abs(est.value - want) < 0.06, (lo, est, want)
    assert cal.false_per_frame.value == pytest.approx(det.false_per_frame, rel=0.3)
    assert cal.edge_noise.value == pytest.approx(np.mean(det.edge_std), rel=0.25)


def test_calibrate_gives_back_the_detectors_memory():
    """The memory of detection of visible, tracked people on the demo's own street (seed 0,
    docs/occlusion-models.md): its 95 % interval holds the memory the street was given
    (MOT17's, 0.485); misses of people in view come in runs of about two frames, as on MOT17."""
    scene = street_scene(Street(), seed=0)
    cal = calibrate([Labelled("street", scene.truth, scene.detections, scene.image_size,
                              scene.fps, scene.frames)], seed=0)
    memory = cal.memory_visible
    assert memory.low <= StreetDetector().memory <= memory.high, memory


def test_same_seed_same_street():
    a, b = (street_scene(Street(people=6, frames=120), seed=7) for _ in range(2))
    assert np.array_equal(a.truth.box, b.truth.box)
    assert np.array_equal(a.detections.box, b.detections.box)
    c = street_scene(Street(people=6, frames=120), seed=8)
    assert not np.array_equal(a.detections.box, c.detections.box)


def test_people_stop_and_stand():
    """Some stand throughout, walkers stop: the share of still frames is far from none."""
    s = street_scene(Street(people=20, frames=600, motion=StreetMotion()), seed=1)
    t = s.truth
    still = moving = 0
    for person in np.unique(t.id):
        rows = np.flatnonzero(t.id == person)
        x = t.box[rows, 0]
        step = np.abs(np.diff(x))
        still += int((step == 0).sum())
        moving += int((step > 0).sum())
    assert 0.1 < still / (still + moving) < 0.8


def test_cover_by_nearer():
    far = [100.0, 100.0, 40.0, 100.0]  # bottom at 200
    near = [120.0, 110.0, 40.0, 100.0]  # bottom at 210: nearer, covers half of far's width
    cover = cover_by_nearer(np.array([far, near]))
    assert cover[0] == pytest.approx(0.5 * 0.9) and cover[1] == 0.0


def _scene(hidden_frames: range, frames: int = 60, inside: float = 1.0) -> StreetScene:
    f = np.arange(1, frames + 1)
    cover = np.where(np.isin(f, hidden_frames), 0.9, 0.0)
    table = MotTable(frame=f, id=np.ones(frames, np.int64),
                     box=np.tile([500.0, 500.0, 40.0, 100.0], (frames, 1)),
                     score=np.ones(frames), cls=np.ones(frames, np.int64),
                     visibility=1 - cover)
    empty = MotTable(frame=np.zeros(0, np.int64), id=np.zeros(0, np.int64),
                     box=np.zeros((0, 4)), score=np.zeros(0), cls=np.zeros(0, np.int64),
                     visibility=np.zeros(0))
    return StreetScene(table, empty, frames, (1920.0, 1080.0), 30.0,
                       np.full(frames, inside), cover)


def test_full_occlusions_are_long_hidden_spells_seen_on_both_sides():
    assert full_occlusions(_scene(range(11, 31))) == [Spell(1, 11, 30)]
    assert full_occlusions(_scene(range(11, 20))) == []  # 9 frames: shorter than 0.5 s
    assert full_occlusions(_scene(range(1, 31))) == []  # not seen before
    assert full_occlusions(_scene(range(11, 31), inside=0.8)) == []  # partly out of the image


def test_kept_needs_the_same_track_before_and_after():
    spell = Spell(1, 11, 30)
    same = {(8, 1): 5, (35, 1): 5}
    other = {(10, 1): 5, (31, 1): 6}
    late = {(10, 1): 5, (31 + 30, 1): 5}  # found again after more than a second
    assert kept([spell], same, 30.0) == [True]
    assert kept([spell], other, 30.0) == [False]
    assert kept([spell], late, 30.0) == [False]
