"""The clutter map (`models.clutter_map`): clutter intensity by range as a hazard along the
beam, learned from the returns no object took; exact on a hand-counted scan, unbiased on
simulated uniform clutter within its Monte Carlo error, and in the tracker a far ring of
spurious returns stops making people there."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from occtrack.models.clutter_map import ClutterMap


def test_one_scan_by_hand():
    """Bins of 0.5 m to 2 m; a beam returning clutter at 1.3 m reached bins 0-1 whole and
    0.3 m of bin 2, a beam with no return all four: exposure 1, 1, 0.8, 0.5 beam-metres, one
    return in bin 2. The prior is kappa_0 over prior_beams * 0.5 m of exposure a bin."""
    k0, prior_beams = 0.01, 2.0
    m = ClutterMap(kappa=k0, max_range=2.0, bin_width=0.5, memory=1e9,
                   prior_beams=prior_beams)
    m.learn(np.array([1.3, np.inf]), np.array([True, False]), dt=0.1)
    np.testing.assert_allclose(m.exposure, [1.0, 1.0, 0.8, 0.5], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(m.count, [0, 0, 1, 0])
    prior = Fraction(prior_beams) * Fraction(1, 2)
    exposure = [Fraction(1), Fraction(1), Fraction(4, 5), Fraction(1, 2)]
    expect = [(c + Fraction(k0) * prior) / (e + prior)
              for c, e in zip([0, 0, 1, 0], exposure, strict=True)]
    np.testing.assert_allclose(m.density(), [float(x) for x in expect], rtol=1e-9)
    # the segment's log ratio is that of its bin
    assert m.log_ratio(np.array([1.25]))[0] == pytest.approx(
        math.log(float(expect[2]) / k0), rel=1e-12)


def test_a_return_an_object_took_adds_exposure_but_no_count_and_counts_fade():
    m = ClutterMap(kappa=0.02, max_range=4.0, bin_width=1.0, memory=2.0, prior_beams=1.0)
    m.learn(np.array([2.5, 3.5]), np.array([False, True]), dt=0.1)
    np.testing.assert_array_equal(m.count, [0, 0, 0, 1])
    np.testing.assert_allclose(m.exposure, [2, 2, 1.5, 0.5])
    m.learn(np.array([np.inf]), np.array([False]), dt=2.0)  # one memory later: e^-1
    np.testing.assert_allclose(m.count, np.array([0, 0, 0, 1]) * math.exp(-1))
    np.testing.assert_allclose(m.exposure, np.array([2, 2, 1.5, 0.5]) * math.exp(-1) + 1)


def test_uniform_clutter_is_learned_without_bias():
    """Poisson clutter of density kappa per beam metre on [0, R), the nearest return kept (the
    sensor's model, `models.scan`): every bin's estimate is kappa within 4 standard errors
    (the count in a bin is Poisson with mean kappa * exposure)."""
    rng = np.random.default_rng(3)
    kappa, R, beams, scans = 0.08, 6.0, 200, 400
    m = ClutterMap(kappa=0.001, max_range=R, bin_width=0.5, memory=1e9, prior_beams=1e-6)
    for _ in range(scans):
        n = rng.poisson(kappa * R, size=beams)
        z = np.full(beams, np.inf)
        for b in np.flatnonzero(n):
            z[b] = rng.uniform(0, R, size=n[b]).min()
        m.learn(z, np.isfinite(z), dt=0.1)
    se = np.sqrt(kappa / m.exposure)
    assert np.all(np.abs(m.density() - kappa) < 4 * se), (m.density(), se)


def test_settings_are_checked():
    with pytest.raises(ValueError, match="memory"):
        ClutterMap(kappa=0.1, max_range=5.0, memory=0.0)
    with pytest.raises(ValueError, match="kappa"):
        ClutterMap(kappa=float("nan"), max_range=5.0)


def ring_scene(clutter_map: bool, seed: int = 0, scans: int = 150):
    """A person (a disc of 0.25 m) walking across 2 m ahead, and a ring of spurious returns
    between 4.5 and 5 m on a fifth of the beams each scan (the ground a tilted laser
    strikes): how many people are reported a scan near the ring, and in how many scans the
    person is reported within 0.3 m."""
    from occtrack.config.scan import ScanTrackerConfig
    from occtrack.models.scan_geometry import disc_ranges
    from occtrack.tracker.scan import ScanTracker

    rng = np.random.default_rng(seed)
    angles = np.linspace(-0.75, 0.75, 245)
    config = ScanTrackerConfig(max_range=5.6, clutter_map=clutter_map)
    tracker = ScanTracker(config, beams=len(angles), rate=10.0)
    ring = found = 0
    for i in range(scans):
        t = i / 10.0
        person = np.array([2.0, -1.0 + 0.013 * i])
        z = disc_ranges(np.zeros(2), angles, person[None], 0.25)[:, 0]
        z = np.where(z > 0, z + rng.normal(0, 0.02, len(z)), np.inf)
        spurious = rng.random(len(z)) < 0.2
        z = np.where(spurious & ~np.isfinite(z), rng.uniform(4.5, 5.0, len(z)), z)
        tr = tracker.update(np.where(z < 5.6, z, np.inf), angles, t)
        d = np.hypot(*tr.positions.T)
        ring += int(np.count_nonzero(d > 4.0))
        found += bool((np.hypot(*(tr.positions - person).T) < 0.3).any())
    return ring / scans, found


def test_a_ring_of_spurious_returns_stops_making_people_there():
    """Off, the ring's returns are as likely a person as anywhere and people are reported
    there; with the map, after it has seen the ring for a few seconds, far fewer, and the
    person is found as often."""
    ring_off, found_off = ring_scene(False)
    ring_on, found_on = ring_scene(True)
    assert ring_off > 0.5
    assert ring_on < ring_off / 4
    assert found_on >= found_off - 3


def test_a_kept_person_explains_the_returns_a_leg_of_theirs_can_make():
    """With legs, a return within half a stride and a leg's radius of a person the pairing
    keeps (0.4 + 0.1 m: the outer edge of a leg a full stride from the other) is theirs, not
    clutter, whether or not a leg track took it; one further out is clutter."""
    from occtrack.config.scan import ScanTrackerConfig
    from occtrack.tracker.scan import ScanTracker

    config = ScanTrackerConfig(max_range=5.6, body="legs")
    reach = config.leg_separation / 2 + config.leg_radius
    angles = np.linspace(-0.5, 0.5, 101)
    tracker = ScanTracker(config, beams=len(angles), rate=10.0)
    tracker.update(np.full(len(angles), np.inf), angles, 0.0)
    half = config.leg_separation / 2 - 0.01
    tracker.pairing.update(0.0, np.array([1, 2]), np.array([[2.0, half], [2.0, -half]]),
                           np.zeros((2, 2)), np.full(2, 0.9), np.full(2, 0.9))
    np.testing.assert_allclose(tracker.pairing.kept_positions(), [[2.0, 0.0]])
    on = {}
    for d in (reach - 0.01, reach + 0.01):  # straight ahead, behind the person's midpoint
        ranges = np.full(len(angles), np.inf)
        ranges[50] = 2.0 + d
        on[d] = bool(tracker._on_objects(angles, ranges, np.zeros(2))[50])
    assert on == {reach - 0.01: True, reach + 0.01: False}
