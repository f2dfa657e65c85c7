"""The scan tracker's field of view and moving sensor (issue 41, item 4), and people from legs
(item 2): a track that leaves the beams' span or range is dropped by the filter's exit rule
and never reported there, the survival region goes with the sensor, and leg tracks pair into
people with identities of their own."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.config.scan import ScanTrackerConfig
from occtrack.models.beam import BeamModel
from occtrack.models.scan_geometry import disc_ranges
from occtrack.models.scan_segments import ScanMeasurement
from occtrack.tracker.people import LegPairing
from occtrack.tracker.scan import ScanTracker

RATE = 10.0


def wedge(beams=245, low=-0.75, high=0.75):
    return np.linspace(low, high, beams)


def ranges_of(origin, angles, centres, radius, max_range):
    """Noise-free nearest returns of discs at `centres` from `origin` along world `angles`."""
    if len(centres) == 0:
        return np.full(len(angles), np.inf)
    rho = disc_ranges(np.asarray(origin, float), angles, np.asarray(centres, float), radius)
    z = rho.min(axis=1)
    return np.where(z < max_range, z, np.inf)


def test_in_view_is_the_beams_span_and_range():
    model = ScanMeasurement(BeamModel(0.98, 0.02, 0.01, 6.0), 0.1)
    angles = wedge(low=-0.5, high=0.5)
    model.segments(angles, np.full(len(angles), np.inf), np.array([1.0, 2.0]))
    points = np.array([[1.0 + 3.0, 2.0],        # ahead: in
                       [1.0 + 7.0, 2.0],        # beyond the range
                       [1.0, 2.0 + 3.0],        # to the side, outside the span
                       [1.0 + 3 * np.cos(0.49), 2.0 + 3 * np.sin(0.49)],   # just inside
                       [1.0 + 3 * np.cos(0.51), 2.0 + 3 * np.sin(0.51)]])  # just outside
    assert model.sees(points).tolist() == [True, False, False, True, False]
    means = np.zeros((len(points), 2, 3))
    means[:, :, 0] = model.to_filter(points)
    assert model.in_view(means).tolist() == model.sees(points).tolist()
    # all round: only the range counts
    full = np.linspace(-np.pi, np.pi, 720, endpoint=False)
    model.segments(full, np.full(720, np.inf), np.array([1.0, 2.0]))
    assert model.sees(points).tolist() == [True, False, True, True, True]


def test_recentre_returns_the_shift_between_the_frames():
    model = ScanMeasurement(BeamModel(0.98, 0.02, 0.01, 6.0), 0.1)
    p = np.array([2.5, -1.0])
    before = model.to_filter(p)
    shift = model.recentre(np.array([3.0, 4.0]))
    np.testing.assert_allclose(before + shift, model.to_filter(p))
    np.testing.assert_allclose(model.to_filter(np.array([3.0, 4.0])), model.region_size / 2)


def walker_leaving(config):
    """A disc walking at 1 m/s across a still wedge of beams, from inside to well outside
    its span; the reported positions and ids a scan."""
    tracker = ScanTracker(config, beams=245, rate=RATE)
    angles = wedge()
    out = []
    for i in range(60):
        centre = np.array([3.0, -1.5 + i / RATE])  # crosses the span (y = 3 tan 0.75 = 2.8)
        z = ranges_of((0, 0), angles, [centre], config.disc_radius, config.max_range)
        tr = tracker.update(z, angles, i / RATE)
        out.append((centre, tr.ids.copy(), tr.positions.copy()))
    return out


def test_a_track_that_leaves_the_view_is_dropped_and_never_reported_outside_it():
    config = ScanTrackerConfig(max_range=6.0, radius=0.25, clutter_per_scan=1.0)
    out = walker_leaving(config)
    bearing_edge = 0.75
    seen = [ids for centre, ids, _ in out if abs(np.arctan2(centre[1], centre[0])) < 0.6]
    assert seen and all(len(ids) == 1 for ids in seen[3:])  # tracked while in view
    for _, _, positions in out:
        for p in positions:  # nothing reported where no beam looks
            assert abs(np.arctan2(p[1], p[0])) <= bearing_edge
    # gone within two scans of its centre leaving the span, not coasted on
    left = [i for i, (c, _, _) in enumerate(out) if np.arctan2(c[1], c[0]) > bearing_edge]
    assert all(len(out[i][1]) == 0 for i in left[2:])


def test_a_moving_sensor_keeps_its_tracks_wherever_it_goes():
    """A robot drives 100 m (turning half way) with a person walking beside it and a post it
    passes: the person keeps one identity all the way (the survival region goes with the
    sensor; before, it stayed about the first pose and every track out of it died), and the
    post is tracked while in view."""
    config = ScanTrackerConfig(max_range=8.0, radius=0.25, clutter_per_scan=1.0)
    tracker = ScanTracker(config, beams=360, rate=RATE)
    full = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    ids, errors = set(), []
    pose = np.zeros(3)
    for i in range(500):  # 50 s at 2 m/s: 100 m
        turn = 0.3 if 240 <= i < 260 else 0.0  # rad/s: a 0.6 rad bend half way
        pose = pose + np.array([0.2 * np.cos(pose[2]), 0.2 * np.sin(pose[2]), turn / RATE])
        heading = np.array([np.cos(pose[2]), np.sin(pose[2])])
        side = np.array([-heading[1], heading[0]])
        person = pose[:2] + 2.0 * heading + 1.5 * side
        post = np.array([60.0, 3.0])
        angles = full  # world angles: the sensor's heading added, kept sorted
        z = ranges_of(pose[:2], angles, [person, post], 0.25, config.max_range)
        tr = tracker.update(z, angles, i / RATE, origin=pose[:2])
        near = np.linalg.norm(tr.positions - person, axis=1) < 0.3 if len(tr) else []
        if i >= 5:
            assert np.sum(near) == 1, f"scan {i}: the person is not tracked"
            ids.add(int(tr.ids[np.argmax(near)]))
            errors.append(np.min(np.linalg.norm(tr.positions - person, axis=1)))
    assert len(ids) == 1
    assert np.median(errors) < 0.05


def test_leg_pairing_reports_a_person_at_the_midpoint_and_keeps_its_id():
    pairing = LegPairing(separation=0.8, gate=0.5, hold=1.0, pairs_only=False)

    def step(t, ids, pos):
        pos = np.asarray(pos, float).reshape(-1, 2)
        n = len(ids)
        return pairing.update(t, np.array(ids), pos, np.zeros((n, 2)), np.ones(n),
                              np.ones(n))

    people = step(0.0, [1, 2, 7], [[1.0, 0.1], [1.0, -0.1], [4.0, 0.0]])
    assert len(people) == 2
    np.testing.assert_allclose(people.positions[0], [1.0, 0.0])
    assert sorted(people.legs[0].tolist()) == [1, 2]
    person = int(people.ids[0])
    # leg 2's track breaks and leg 5 takes over: the same person
    people = step(0.1, [1, 5, 7], [[1.1, 0.1], [1.1, -0.1], [4.0, 0.0]])
    assert int(people.ids[0]) == person and sorted(people.legs[0].tolist()) == [1, 5]
    # both legs lost for under `hold`: a new leg near where it was takes it up
    people = step(0.2, [7], [[4.0, 0.0]])
    assert person not in people.ids.tolist()  # not reported without a leg
    people = step(0.7, [9, 7], [[1.2, 0.0], [4.0, 0.0]])
    assert person in people.ids.tolist()
    # legs that part beyond the stride are two people
    people = step(0.8, [9, 10, 7], [[1.2, 0.0], [1.2, 1.5], [4.0, 0.0]])
    assert len(people) == 3
    # gone for longer than hold: a leg there is somebody new
    step(0.9, [7], [[4.0, 0.0]])
    people = step(2.5, [11, 7], [[1.2, 0.0], [4.0, 0.0]])
    assert person not in people.ids.tolist()
    assert len(set(people.ids.tolist())) == len(people)


def test_leg_pairing_never_reuses_an_id_and_checks_its_settings():
    pairing = LegPairing(hold=1.0, pairs_only=False)
    last: dict[int, float] = {}  # person id -> when last reported
    rng = np.random.default_rng(0)
    for step in range(200):
        t = step * 0.25
        n = int(rng.integers(0, 6))
        ids = rng.choice(30, size=n, replace=False)
        people = pairing.update(t, ids, rng.random((n, 2)) * 3, np.zeros((n, 2)),
                                np.ones(n), np.ones(n))
        legs = [leg for held in pairing.members.values() for leg in held]
        assert len(set(legs)) == len(legs)  # a leg is one person's
        assert set(legs) == set(ids.tolist())  # every leg is someone's
        assert set(people.ids.tolist()) == {k for k, v in pairing.members.items() if v}

        shown = people.legs[people.legs >= 0]
        assert set(shown.tolist()) <= set(legs)
        # nobody is reported within half a stride of another
        d = np.linalg.norm(people.positions[:, None] - people.positions[None], axis=-1)
        assert (d[np.triu_indices(len(people), 1)] >= 0.4).all()
        assert len(np.unique(people.ids)) == len(people)
        for i in people.ids.tolist():  # an id away for longer than hold never comes back
            assert t - last.get(i, t) <= 1.0 + 0.25
            last[i] = t
    with pytest.raises(ValueError, match="separation"):
        LegPairing(separation=-1.0)


def test_a_person_on_two_legs_is_one_track_at_the_midpoint():
    """Two leg discs (radius 6 cm) 30 cm apart walking side by side, swinging alternately:
    body "legs" reports one person between them under one id; body "disc" with discs of the
    legs' size reports the two legs."""
    config = ScanTrackerConfig(max_range=6.0, body="legs", leg_radius=0.06,
                               clutter_per_scan=1.0)
    angles = wedge(beams=490)
    reported = {"legs": [], "disc": []}
    for body in reported:
        tracker = ScanTracker(config.replace(body=body, radius=0.06), beams=len(angles),
                              rate=RATE)
        for i in range(40):
            t = i / RATE
            mid = np.array([2.5 + 0.8 * t, 0.2])
            swing = 0.1 * np.sin(2 * np.pi * t)
            legs = [mid + [swing, 0.15], mid + [-swing, -0.15]]
            z = ranges_of((0, 0), angles, legs, 0.06, config.max_range)
            tr = tracker.update(z, angles, t)
            if i >= 10:
                reported[body].append((mid, tr.ids.copy(), tr.positions.copy()))
    for mid, ids, positions in reported["legs"]:
        assert len(ids) == 1
        assert np.linalg.norm(positions[0] - mid) < 0.1
    assert len({int(ids[0]) for _, ids, _ in reported["legs"]}) == 1
    assert all(len(ids) == 2 for _, ids, _ in reported["disc"])


def test_a_lone_leg_is_not_a_person_until_a_second_joins_it():
    pairing = LegPairing(separation=0.8, pairs_only=True)
    one = pairing.update(0.0, np.array([1]), np.array([[2.0, 0.0]]), np.zeros((1, 2)),
                         np.ones(1), np.ones(1))
    assert len(one) == 0 and pairing.members == {1: (1,)}
    two = pairing.update(0.1, np.array([1, 2]), np.array([[2.0, 0.0], [2.0, 0.3]]),
                         np.zeros((2, 2)), np.ones(2), np.ones(2))
    assert two.ids.tolist() == [1]
    # once paired, a person stays reported on one leg
    again = pairing.update(0.2, np.array([1]), np.array([[2.05, 0.0]]), np.zeros((1, 2)),
                           np.ones(1), np.ones(1))
    assert again.ids.tolist() == [1]
    np.testing.assert_allclose(again.positions[0], [2.05, 0.0])


def test_a_tentative_leg_keeps_or_refinds_a_person_but_never_starts_one():
    """A leg track not yet confirmed (a leg whose track broke and began again) may keep its
    person or take up a person who lost both legs; it never pairs with another leg into
    somebody new, never makes a lone leg a pair, and a person held only by such legs for
    longer than `hold` is no longer reported."""
    pairing = LegPairing(separation=0.8, gate=0.5, hold=1.0, pairs_only=True)

    def step(t, ids, pos, tentative):
        pos = np.asarray(pos, float).reshape(-1, 2)
        n = len(ids)
        return pairing.update(t, np.array(ids, np.int64), pos, np.zeros((n, 2)), np.ones(n),
                              np.ones(n), None, np.array(tentative, bool))

    person = step(0.0, [1, 2], [[2.0, 0.1], [2.0, -0.1]], [False, False]).ids.tolist()
    assert person == [1]
    # both legs' tracks break: new tentative tracks where they were keep the person
    people = step(0.1, [3, 4], [[2.0, 0.12], [2.0, -0.1]], [True, True])
    assert people.ids.tolist() == person
    # two tentative legs far away are nobody; a confirmed lone leg with a tentative one is
    # no pair
    people = step(0.2, [3, 4, 5, 6, 7, 8],
                  [[2.0, 0.12], [2.0, -0.1], [4.0, 1.0], [4.0, 1.2], [3.0, -1.0],
                   [3.0, -1.2]], [True, True, True, True, False, True])
    assert people.ids.tolist() == person
    assert {5, 6} not in [set(legs) for legs in pairing.members.values()]
    # held by tentative legs alone for longer than hold: not reported, though kept
    for t in (0.6, 1.0, 1.15):
        people = step(t, [3, 4], [[2.0, 0.12], [2.0, -0.1]], [True, True])
    assert people.ids.tolist() == []
    assert (3, 4) in [tuple(sorted(v)) for v in pairing.members.values()]
    # a confirmed leg again: reported again under the same id
    people = step(1.2, [3, 4], [[2.0, 0.12], [2.0, -0.1]], [False, True])
    assert people.ids.tolist() == person


def test_one_segment_two_legs_wide_is_a_pair():
    """A person standing with legs together is one segment wider than one leg can look: a
    confirmed leg on such a segment makes a person; a tentative one does not."""
    pairing = LegPairing(separation=0.8, pairs_only=True)

    def step(t, wide, tentative):
        return pairing.update(t, np.array([1]), np.array([[1.2, 0.2]]), np.zeros((1, 2)),
                              np.ones(1), np.ones(1), None, np.array([tentative]),
                              np.array([wide]))

    assert len(step(0.0, False, False)) == 0
    assert len(step(0.1, True, True)) == 0
    assert step(0.2, True, False).ids.tolist() == [1]
    assert step(0.3, False, False).ids.tolist() == [1]  # once a pair, on one leg too


def test_the_tracker_calls_a_segment_two_legs_wide_by_its_first_and_last_return():
    tracker = ScanTracker(ScanTrackerConfig(max_range=5.0, body="legs", leg_radius=0.1),
                          beams=245, rate=RATE)
    angles = wedge()
    step = angles[1] - angles[0]
    z = np.full(len(angles), np.inf)
    # at 2 m: 0.15 m (one leg), 0.3 m (two together), 0.6 m (neither), 5 beams' worth each
    for first, width in ((20, 0.15), (100, 0.3), (180, 0.6)):
        n = int(round(width / (2.0 * step))) + 1
        z[first:first + n] = 2.0
    tracker.update(z, angles, 0.0)
    segs = np.arange(len(tracker.segments))
    wide = tracker._two_legs_wide(np.r_[segs, -1])
    assert wide.tolist() == [False, True, False, False]
