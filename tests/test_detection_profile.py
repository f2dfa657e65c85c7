"""The detection profile: P_D per class and range band, learnt from the tracker's own objects,
and what it does in the filter (a car missed where the detector never misses goes sooner)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.models.detection_profile import DetectionProfile
from occtrack.tracker.ground import GroundTracker, ground_config
from test_ground import in_camera


def test_the_profile_is_the_prior_until_objects_teach_it_and_then_their_weighted_share():
    profile = DetectionProfile(0.9, bands=(10.0, 20.0, 40.0), prior_weight=20.0, memory=60.0)
    ranges = np.array([5.0, 10.0, 15.0, 39.9, 40.0, 90.0])
    assert profile.band_of(ranges).tolist() == [0, 1, 1, 2, 3, 3]  # (an edge opens its band)
    np.testing.assert_allclose(profile.probability(np.zeros(6, int), ranges), 0.9)
    # band 1 of class 0: a hit of weight 1 and a miss of weight 1/2
    profile.update(np.array([0, 0]), np.array([12.0, 18.0]), np.array([True, False]),
                   np.array([1.0, 0.5]), dt=0.0)
    got = profile.probability(np.array([0, 0, 3]), np.array([15.0, 30.0, 15.0]))
    assert got[0] == pytest.approx((1.0 + 20 * 0.9) / (1.5 + 20), rel=1e-12)
    assert got[1] == got[2] == 0.9  # another band, another class: the prior
    # a memory's ln 2 later the old counts weigh half, and a new hit comes in whole
    profile.update(np.array([0]), np.array([11.0]), np.array([True]), np.array([1.0]),
                   dt=60.0 * math.log(2))
    got = profile.probability(np.array([0]), np.array([15.0]))[0]
    assert got == pytest.approx((0.5 + 1.0 + 18.0) / (0.75 + 1.0 + 20.0), rel=1e-12)


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="prior P_D"):
        DetectionProfile(1.5)
    with pytest.raises(ValueError, match="positive"):
        DetectionProfile(0.9, prior_weight=0.0)


def _vanishing_car(profile_pd: float | None) -> tuple[int, float]:
    """A car at 15 m detected for 4 s, then gone: the frames it is still reported, and its
    existence after the first miss. profile_pd: the learnt P_D of cars at that range (None:
    the filter's one configured P_D)."""
    tracker = GroundTracker(ground_config({"occlusion": "none"}))
    if profile_pd is None:
        tracker.tracker.filter.detection_profile = None
    else:
        tracker.detection_profile.update(np.zeros(1, int), np.array([15.0]), np.array([True]),
                                         np.array([1.0]), 0.0)
        band = tracker.detection_profile.band_of(np.array([15.0]))[0]
        tracker.detection_profile._hits[0][band] = 1e9 * profile_pd
        tracker.detection_profile._trials[0][band] = 1e9
        tracker.detection_profile.memory = 1e12  # (hold it for the test)
    box = np.array([in_camera((2.0, 15.0), np.eye(3, 4))])
    for _ in range(40):
        tracker.update(box, [0.99], [0])
    shown, first = 0, None
    for _ in range(20):
        tracks = tracker.update(np.zeros((0, 7)), [], [])
        if first is None:  # (read from the filter: it may already be under the report)
            r = tracker.tracker.filter.object_moments()[0]
            first = float(r[tracker.tracker.filter.slot_used].max())
        shown += len(tracks)
    return shown, first


def test_a_car_missed_where_the_detector_never_misses_goes_sooner():
    """With the profile at .995 for cars at 15 m the chain of the car's detectability relaxes
    towards .995, not the configured .93: one miss takes its existence lower (r' = r (1 - P_D)
    / (1 - r P_D)), and it leaves the report in fewer frames than with the configured P_D."""
    sure, r_sure = _vanishing_car(0.995)
    plain, r_plain = _vanishing_car(None)
    assert r_sure < r_plain - 0.05
    assert sure < plain
