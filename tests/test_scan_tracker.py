"""The lidar scan tracker (issue 24, item 2): the scan measurement model's segments and
likelihood against `models.scan`'s per-beam terms, its update, the scan occlusion term, and
the tracker on small hand-built scenes."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from scipy.special import ndtr

from occtrack.config.scan import ScanTrackerConfig
from occtrack.errors import OcctrackError
from occtrack.experiments.scan_tracking import run_scene
from occtrack.models.beam import BeamModel
from occtrack.models.scan import beam_terms
from occtrack.models.scan_geometry import disc_range_gradient, disc_ranges
from occtrack.models.scan_segments import ScanMeasurement, _gaussian_hits, cut
from occtrack.occlusion.base import OcclusionContext
from occtrack.occlusion.scan import ScanMeasurementWise
from occtrack.tracker.scan import ScanTracker

BEAMS = 720
ANGLES = -np.pi + (np.arange(BEAMS) + 0.5) * 2 * np.pi / BEAMS
MODEL = BeamModel(p_d=0.98, sigma=0.02, clutter_rate=5.0 / BEAMS, max_range=20.0)
RADIUS = 0.25


def scan_of(centres, rng=None, p_d=1.0, sigma=0.0, opaque=False):
    """Ranges of discs at `centres` seen from the origin: the nearest return a beam (each
    disc returns with p_d; `opaque`: the nearest surface returns with p_d and hides the rest
    either way, the scene's object-wise sensor)."""
    rho = disc_ranges(np.zeros(2), ANGLES, np.asarray(centres, float), RADIUS)
    if opaque:
        rho = rho.min(axis=1, keepdims=True)
    if rng is not None:
        rho = np.where(rng.random(rho.shape) < p_d,
                       rho + sigma * rng.standard_normal(rho.shape), np.inf)
    z = rho.min(axis=1)
    return np.where(z < MODEL.max_range, z, np.inf)


def test_cut_splits_on_range_jumps_and_gaps_and_joins_across_the_wrap():
    angle = np.linspace(-np.pi, np.pi, 12, endpoint=False)
    r = np.array([2.0, 2.01, np.inf, 2.02, 5.0, 5.0, np.inf, np.inf, 3.0, np.inf, 2.0, 2.0])
    beam, start = cut(angle, r, 0.02, 0.3, 1)
    segments = [beam[a:b].tolist() for a, b in zip(start[:-1], start[1:], strict=True)]
    # 0-3 (one missing beam bridged) joins 10-11 across the wrap; 4-5; 8 alone
    assert sorted(map(sorted, segments)) == [[0, 1, 3, 10, 11], [4, 5], [8]]


def test_loglik_at_a_known_centre_is_the_sum_of_the_per_beam_factors():
    """With no centre uncertainty and the component on the segment's disc, log p(z_j | x_k)
    = sum of log g_b over the segment's hit beams + sum of log m_b over the component's other
    beams (models.scan.beam_terms), here with a nearer person hiding part of the far one."""
    model = ScanMeasurement(MODEL, RADIUS)
    far, near = np.array([4.0, 1.0]), np.array([2.0, 0.2])
    z = model.segments(ANGLES, scan_of([far, near]))
    j = int(np.argmin(np.linalg.norm(z.centre - far, axis=1)))
    centre = z.centre[j][None]
    got = model.raw_loglik(centre, np.zeros((1, 2, 2)), z, np.array([0]), np.array([j]))[0]
    rho = disc_ranges(np.zeros(2), ANGLES, centre, RADIUS)
    m, g = beam_terms(z.range, rho, MODEL)
    seg_beams = z.beam[z.start[j]:z.start[j + 1]]
    hits = seg_beams[z.fit_beam[z.start[j]:z.start[j + 1]]]
    others = np.setdiff1d(np.flatnonzero(np.isfinite(rho[:, 0])), seg_beams)
    assert len(hits) >= 5 and len(others) >= 3  # some of its beams hit the near person
    expected = np.log(g[hits, 0]).sum() + np.log(m[others, 0]).sum()
    assert got == pytest.approx(expected, rel=1e-9, abs=1e-6)
    # the beams the near person takes are "short" returns: m about 1, no information
    assert np.all(m[others, 0] > 0.99)


def test_loglik_with_an_uncertain_centre_is_the_linearised_gaussian():
    """At any linearisation point c, the Woodbury closed form is log N(z; rho(c) + H (m - c),
    H P H' + sigma^2 I) and the Kalman posterior of the centre, written out over the hit
    beams; log p(z_j | x_k) is that at the iterated EKF's last point, plus n log(P_D / kappa),
    plus the other beams' log factors where the posterior puts the disc."""
    model = ScanMeasurement(MODEL, RADIUS)
    rng = np.random.default_rng(3)
    z = model.segments(ANGLES, scan_of([[3.0, -1.0]], rng, 1.0, 0.02))
    j = np.array([0])
    m_k = z.centre[0] + np.array([0.04, -0.03])
    P = np.array([[0.01, 0.002], [0.002, 0.02]])
    seg_beams = z.beam[z.start[0]:z.start[1]]

    def dense(c):
        rho = disc_ranges(np.zeros(2), ANGLES[seg_beams], c[None], RADIUS)[:, 0]
        H = disc_range_gradient(np.zeros(2), ANGLES[seg_beams], c[None], RADIUS)[:, 0]
        # H = u + slope n with u and n orthonormal: |H| = sqrt(1 + slope^2), slope <= 5
        hit = np.isfinite(rho) & (np.linalg.norm(H, axis=1) <= np.hypot(1.0, 5.0))
        rho, H = rho[hit], H[hit]
        mean = rho + H @ (m_k - c)
        S = H @ P @ H.T + MODEL.sigma**2 * np.eye(len(rho))
        r = z.range[seg_beams][hit] - mean
        log_n = -0.5 * (r @ np.linalg.solve(S, r) + np.linalg.slogdet(2 * np.pi * S)[1])
        gain = P @ H.T @ np.linalg.inv(S)
        return log_n, m_k + gain @ r, P - gain @ H @ P, hit.sum()

    at = z.centre[0] + np.array([0.01, 0.02])
    stats = model.linearise(at[None], z, j)
    got = _gaussian_hits(m_k[None], P[None], at[None], *stats, MODEL.sigma**2)
    log_n, c_post, P_post, n = dense(at)
    assert stats[3][0] == n
    assert got[0][0] == pytest.approx(log_n, rel=1e-9)
    assert np.allclose(got[1][0], c_post, atol=1e-12) and np.allclose(got[2][0], P_post,
                                                                       atol=1e-12)
    last, stats, _, post, post_cov = model.pair_fit(m_k[None], P[None], z, j)
    log_n, c_post, P_post, n = dense(last[0])
    # the component's other beams (at its edges, which the segment's disc does not take),
    # where the hit beams put it, each weighed by the chance that it meets that disc at all
    rho_k = disc_ranges(np.zeros(2), ANGLES, c_post[None], RADIUS)
    grad = disc_range_gradient(np.zeros(2), ANGLES, c_post[None], RADIUS)[:, 0]
    u = np.c_[np.cos(ANGLES), np.sin(ANGLES)]
    nv = np.c_[-u[:, 1], u[:, 0]]
    d, lateral = nv @ c_post, np.sqrt(np.einsum("bi,ij,bj->b", nv, P_post, nv))
    reach = ndtr((RADIUS - d) / lateral) - ndtr((-RADIUS - d) / lateral)
    t_c = u @ c_post
    rho_k = np.where(np.isfinite(rho_k[:, 0]), rho_k[:, 0], t_c)  # closest approach
    var = np.einsum("bi,ij,bj->b", grad, P_post, grad)
    m, _ = beam_terms(z.range, rho_k[:, None], MODEL, var[:, None])
    ahead = (t_c > 0) & (reach > 1e-12)
    ahead[seg_beams] = False
    other = np.log(1.0 - reach[ahead] * (1.0 - m[ahead, 0])).sum()
    expected = log_n + n * np.log(MODEL.p_d / MODEL.kappa) + other
    got = model.raw_loglik(m_k[None], P[None], z, np.array([0]), j)[0]
    assert got == pytest.approx(expected, rel=1e-9, abs=1e-6)


def test_update_moves_an_uncertain_centre_onto_the_segment():
    model = ScanMeasurement(MODEL, RADIUS)
    truth = np.array([2.0, 3.0])
    z = model.segments(ANGLES, scan_of([truth]))
    means = np.zeros((1, 2, 3))
    means[0, :, 0] = model.to_filter(truth + [0.1, -0.08])
    means[0, :, 2] = RADIUS * model.unit
    covs = np.zeros((1, 2, 3, 3))
    for axis in range(2):
        covs[0, axis] = np.diag([(0.2 * model.unit) ** 2, 1e4, 1e-6])
    model.update_rows(means, covs, np.array([0]), z, None, np.array([0]))
    centre, _ = model.to_world(means)
    assert np.linalg.norm(centre[0] - truth) < 0.005
    assert np.all(np.sqrt(covs[0, :, 0, 0]) / model.unit < 0.03)


def test_scan_occlusion_hides_a_person_behind_another_only():
    model = ScanMeasurement(MODEL, RADIUS)
    near, far, clear = np.array([1.0, 0.0]), np.array([4.0, 0.0]), np.array([0.0, 4.0])
    z = model.segments(ANGLES, scan_of([near]))
    means = np.zeros((2, 2, 3))
    means[:, :, 0] = model.to_filter(np.stack([far, clear]))
    means[:, :, 2] = RADIUS * model.unit
    covs = np.zeros((2, 2, 3, 3))
    covs[:, :, 0, 0] = (0.05 * model.unit) ** 2
    ctx = OcclusionContext(means=means, covs=covs, weights=np.ones(2), owner=np.arange(2),
                           existence=np.ones(2), measurements=z, measurement_model=model)
    q = ScanMeasurementWise().terms(ctx).hidden
    assert q[0] > 0.99 and q[1] < 1e-6


def test_a_still_disc_seen_by_noise_free_scans_is_tracked_to_within_a_centimetre():
    truth = np.array([3.0, -2.0])
    tr = ScanTracker(ScanTrackerConfig(occlusion="none"))
    ranges = scan_of([truth])
    for i in range(10):
        out = tr.update(ranges, ANGLES, 0.1 * i)
    assert len(out) == 1
    assert np.linalg.norm(out.positions[0] - truth) < 0.01
    assert np.linalg.norm(out.velocities[0]) < 0.05
    assert out.existence[0] > 0.99 and not out.occluded[0]


def walk_behind(occlusion):
    """A person standing 1 m out (0, 1) and one walking along y = 4 at 1 m/s from x = -3 to
    3, wholly hidden for about 1.5 s as they pass behind (surfaces opaque: a missed beam on the
    near person still hides the walker): the walker's track id a scan (-1: none within
    0.5 m), whether it was reported hidden, and whether it was wholly covered."""
    rng = np.random.default_rng(7)
    tr = ScanTracker(ScanTrackerConfig(occlusion=occlusion))
    ids, hidden, covered = [], [], []
    for i in range(61):
        t = 0.1 * i
        walker = np.array([-3.0 + t, 4.0])
        ranges = scan_of([[0.0, 1.0], walker], rng, 0.98, 0.02, opaque=True)
        out = tr.update(ranges, ANGLES, t)
        d = np.linalg.norm(out.positions - walker, axis=1)
        k = int(np.argmin(d)) if len(d) else -1
        ok = k >= 0 and d[k] < 0.5
        ids.append(int(out.ids[k]) if ok else -1)
        hidden.append(bool(out.occluded[k]) if ok else False)
        alone = disc_ranges(np.zeros(2), ANGLES, walker[None], RADIUS)[:, 0]
        seen = np.isfinite(alone) & (alone < disc_ranges(np.zeros(2), ANGLES,
                                                          np.array([[0.0, 1.0]]), RADIUS)[:, 0])
        covered.append(not seen.any())
    return np.array(ids), np.array(hidden), np.array(covered)


def test_a_walker_keeps_its_id_behind_a_person_under_measurement_wise_occlusion_only():
    ids, hidden, covered = walk_behind("measurement-wise")
    spell = np.flatnonzero(covered)
    assert len(spell) >= 10  # a full occlusion of a second or more
    before = ids[spell[0] - 1]
    after = ids[spell[-1] + 1:spell[-1] + 6]  # the half second after
    assert before >= 0 and (after == before).all()
    assert (ids[spell] == before).all()  # reported all along
    assert hidden[spell].mean() > 0.8  # and said to be hidden
    ids, _, _ = walk_behind("none")
    before, after = ids[spell[0] - 1], ids[spell[-1] + 1]
    assert before >= 0 and after != before  # lost, and a new track after


def test_same_seed_same_tracks_byte_for_byte():
    """Two runs of one seed of the walkway give the same tracks to the byte, and the same
    scores."""
    from occtrack.config.lidar import LidarSceneConfig
    from occtrack.scenarios.lidar import simulate_scene

    def digest():
        scans = [(s.time, s.pose[2] + s.angle, s.range, s.pose[:2])
                 for s in simulate_scene(LidarSceneConfig(), 30, 0)]
        out = ScanTracker().run(scans)
        h = hashlib.sha256()
        for name in ("time", "id", "position", "velocity", "existence", "confidence",
                     "occluded"):
            h.update(np.ascontiguousarray(getattr(out, name)).tobytes())
        run = run_scene(0, "measurement-wise", scans=30)
        return h.hexdigest(), (run.gospa, run.localisation, run.missed, run.false, run.kept)

    first = digest()
    assert first == digest()


def test_report_min_confidence_reports_the_same_tracks_less_those_below_it():
    """Reporting by confidence hides tracks from the report, never from the filter: each
    scan's reported tracks are those of the default run whose confidence reaches the bound."""
    from occtrack.config.lidar import LidarSceneConfig
    from occtrack.scenarios.lidar import simulate_scene

    scans = [(s.time, s.pose[2] + s.angle, s.range, s.pose[:2])
             for s in simulate_scene(LidarSceneConfig(), 150, 2)]
    every = ScanTracker().run(scans)
    some = ScanTracker(ScanTrackerConfig(report_min_confidence=0.5)).run(scans)
    kept = every.confidence >= 0.5
    assert 0 < kept.sum() < len(every)  # the bound bites on this scene
    for name in ("time", "id", "position", "existence", "confidence", "occluded"):
        np.testing.assert_array_equal(getattr(some, name), getattr(every, name)[kept])


def test_scan_settings_are_checked():
    with pytest.raises(ValueError, match="occlusion"):
        ScanTrackerConfig(occlusion="object-wise")
    with pytest.raises(ValueError, match="radius"):
        ScanTrackerConfig(radius=0.0)
    with pytest.raises(OcctrackError, match="scan"):
        ScanTrackerConfig.from_dict({"radious": 1.0})
    assert ScanTrackerConfig.from_dict({"radius": 0.3}).radius == 0.3


def test_update_refuses_bad_scans():
    tr = ScanTracker()
    with pytest.raises(ValueError, match="increase"):
        tr.update(np.ones(3), np.array([0.0, 0.0, 1.0]), 0.0)
    tr.update(np.full(BEAMS, np.inf), ANGLES, 0.0)
    with pytest.raises(ValueError, match="not after"):
        tr.update(np.full(BEAMS, np.inf), ANGLES, 0.0)


def test_compiled_hidden_probability_matches_the_array_form():
    """occlusion.scan._hidden_at against the same product written with
    ScanMeasurement.component_beams and scipy's Phi, on random discs in a scan of three."""
    from occtrack.occlusion.scan import _hidden_at

    model = ScanMeasurement(MODEL, RADIUS)
    rng = np.random.default_rng(11)
    z = model.segments(ANGLES, scan_of([[1.0, 0.3], [-2.0, 1.0], [0.5, -3.0]], rng, 0.98,
                                       0.02))
    centre = rng.uniform(-5, 5, (300, 2))
    centre[:100] = [1.0, 0.3] + rng.normal(0, 1.0, (100, 2)) * [[3.0, 1.0]]
    k, b, rho, _, reach = model.component_beams(centre, np.zeros((300, 2, 2)), z)
    at = np.where(np.isfinite(z.range[b]), z.range[b], MODEL.max_range)
    with np.errstate(divide="ignore"):
        log_q = np.log1p(-reach * ndtr((at - rho) / MODEL.sigma))
    total = np.bincount(k, weights=log_q, minlength=300)
    expected = np.where(np.bincount(k, minlength=300) > 0, np.exp(total), 0.0)
    got = _hidden_at(centre, z.origin, z.angle, z.range, MODEL.max_range, MODEL.sigma, RADIUS)
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-12)
    assert (got > 0.5).sum() >= 5 and (got < 1e-6).sum() >= 50  # both kinds present
