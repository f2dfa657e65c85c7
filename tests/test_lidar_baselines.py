"""The lidar scan tracker's baselines (issue 24): the hand-made beam factor, the point model
of cluster-then-track, their settings, and `occtrack reproduce lidar --json`."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from occtrack.cli import main
from occtrack.config.scan import ScanTrackerConfig
from occtrack.models.beam import BeamModel
from occtrack.models.point import PointMeasurement
from occtrack.models.scan_geometry import disc_ranges
from occtrack.models.scan_hand_made import BAND, PASSED, _other_beams_hand_made, hand_made_factor
from occtrack.models.scan_segments import ScanMeasurement
from occtrack.tracker.scan import ScanTracker

BEAMS = 720
ANGLES = -np.pi + (np.arange(BEAMS) + 0.5) * 2 * np.pi / BEAMS
MODEL = BeamModel(p_d=0.98, sigma=0.02, clutter_rate=5.0 / BEAMS, max_range=20.0)
RADIUS = 0.25


def test_the_hand_made_factor_takes_its_fixed_value_in_each_regime():
    rho = np.full(6, 5.0)
    s = MODEL.sigma
    z = np.array([np.inf, 25.0, 5.0 + 2 * BAND * s, 5.0 + 0.5 * BAND * s, 5.0, 1.0])
    f = hand_made_factor(z, rho, s, MODEL.max_range)
    # none and beyond: the fixed low factor; near and closer: 1, whatever P_D
    assert f.tolist() == [PASSED, PASSED, PASSED, 1.0, 1.0, 1.0]


def _through(centre):
    """The beams through the disc at `centre` (from the origin), and their near ranges."""
    u = np.c_[np.cos(ANGLES), np.sin(ANGLES)]
    d = u[:, 0] * centre[1] - u[:, 1] * centre[0]
    t = u @ np.asarray(centre)
    hit = (np.abs(d) < RADIUS) & (t > 0)
    return hit, t - np.sqrt(np.maximum(RADIUS**2 - d**2, 0.0))


@pytest.mark.parametrize("scene, expected", [("empty", PASSED), ("wall in front", 1.0),
                                             ("on the surface", 1.0)])
def test_the_compiled_hand_made_term_is_the_sum_of_the_factors_over_the_beams_through_the_disc(
        scene, expected):
    centre = np.array([5.0, 2.0])
    hit, rho = _through(centre)
    ranges = {"empty": np.full(BEAMS, np.inf), "wall in front": np.full(BEAMS, 2.0),
              "on the surface": np.where(hit, rho, np.inf)}[scene]
    out = _other_beams_hand_made(centre[None], np.array([7]), np.zeros(2), ANGLES, ranges,
                                 np.full(BEAMS, -1), RADIUS, MODEL.max_range, MODEL.sigma,
                                 PASSED, BAND)
    assert hit.sum() > 3
    assert out[0] == pytest.approx(hit.sum() * np.log(expected))


def test_the_point_models_likelihood_is_the_gaussian_of_the_centre_plus_its_noise():
    noise = 0.1
    model = PointMeasurement(MODEL, RADIUS, noise, 5.0)
    plain = ScanMeasurement(MODEL, RADIUS)
    rng = np.random.default_rng(1)
    K = 3
    means = np.zeros((K, 2, 3))
    means[:, :, 0] = model.to_filter(rng.uniform(-5, 5, (K, 2)))
    covs = np.zeros((K, 2, 3, 3))
    for axis in range(2):
        covs[:, axis] = np.diag([30.0**2, 50.0**2, 1e-6])
    zhat, S = model.innovation(means, covs)
    centre, P = plain.innovation(means, covs)
    assert np.allclose(zhat, centre) and np.allclose(S, P + noise**2 * np.eye(2))
    seg = plain.segments(ANGLES, disc_ranges(np.zeros(2), ANGLES,
                                             np.array([[4.0, 1.0], [-2.0, 3.0]]), RADIUS).min(1))
    assert len(seg) == 2
    k, j = np.array([0, 1, 2, 0]), np.array([0, 0, 1, 1])
    got = model.loglik_pairs(means, zhat, S, seg, None, k, j)
    want = [multivariate_normal(zhat[a], S[a]).logpdf(seg.centre[b])
            for a, b in zip(k, j, strict=True)]
    assert np.allclose(got, want)
    # clutter: the scan's spurious returns spread over the sensor's disc
    assert model.clutter_density(seg, None, None) == pytest.approx(
        np.full(2, 5.0 / (np.pi * MODEL.max_range**2)))
    # the update is the Kalman update, per axis, in the filter's units
    m2, P2 = means.copy(), covs.copy()
    model.update_rows(m2, P2, np.array([1]), seg, None, np.array([0]))
    z = model.to_filter(seg.centre[0])
    for axis in range(2):
        Pa = covs[1, axis]
        gain = Pa[:, 0] / (Pa[0, 0] + (noise * model.unit) ** 2)
        assert np.allclose(m2[1, axis], means[1, axis] + gain * (z[axis] - means[1, axis, 0]))
        assert np.allclose(P2[1, axis], Pa - np.outer(gain, Pa[0]))
    assert np.array_equal(m2[0], means[0]) and np.array_equal(m2[2], means[2])


def test_the_likelihood_setting_is_checked_and_picks_the_model():
    with pytest.raises(ValueError, match="likelihood must be one of"):
        ScanTrackerConfig(likelihood="hand made")
    with pytest.raises(ValueError, match="goes with occlusion 'none'"):
        ScanTrackerConfig(likelihood="cluster")
    kinds = {name: type(ScanTracker(ScanTrackerConfig(likelihood=name, occlusion="none"))
                        .measurement).__name__ for name in ("derived", "hand-made", "cluster")}
    assert kinds == {"derived": "ScanMeasurement", "hand-made": "HandMadeScanMeasurement",
                     "cluster": "PointMeasurement"}
    assert ScanTrackerConfig.from_dict({"likelihood": "hand-made"}).likelihood == "hand-made"


def test_a_spell_counts_when_its_person_is_there_on_both_sides_and_is_kept_by_one_track():
    from occtrack.experiments.scan_tracking import count_bridged
    from occtrack.scenarios.lidar.scene import Occlusions

    # scans 0..29 at 10 a second; person 1 hidden at scans 5-7 (kept by track 9), 12-24
    # (1.2 s, another track after), person 2 at 15-16 (entered at scan 15: left out),
    # person 3 at 20-21 (matched to no track going in: not kept), 25-28 (left at 28: out)
    index = {i: i for i in range(30)}
    spells = Occlusions(np.array([1, 1, 2, 3, 3]),
                        np.array([0.5, 1.2, 1.5, 2.0, 2.5]), np.array([0.7, 2.4, 1.6, 2.1, 2.8]))
    present = ({(i, 1) for i in range(30)} | {(i, 2) for i in range(15, 30)}
               | {(i, 3) for i in range(29)})
    assigned = {(4, 1): 9, (8, 1): 9, (11, 1): 9, (25, 1): 7, (17, 2): 5, (22, 3): 4,
                (24, 3): 4, (29, 3): 4}
    assert count_bridged(spells, assigned, present, index, 10.0, 2.0) == (3, 2, 1, 1, 0)
    # shorter spells only
    assert count_bridged(spells, assigned, present, index, 10.0, 1.0) == (2, 1, 1, 0, 0)


def test_reproduce_lidar_json_is_one_object_of_the_documented_shape(capsys):
    assert main(["reproduce", "lidar", "--json", "--seeds", "0", "--scans", "60",
                 "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"full_occlusions", "trackers"}
    assert isinstance(out["full_occlusions"], int) and out["full_occlusions"] > 0
    assert list(out["trackers"]) == ["derived", "hand-made", "none", "cluster"]
    for cell in out["trackers"].values():
        assert set(cell) == {"gospa", "bridged"}
        assert len(cell["gospa"]) == 1 and 0 < cell["gospa"][0] < 2
        assert 0 <= cell["bridged"] <= 1


def test_reproduce_lidar_draws_one_scan_and_never_overwrites(tmp_path, capsys):
    """--figure draws the scan where the derived tracker holds the most fully occluded people
    that the tracker without occlusion lost; an existing file is refused unless --force."""
    pytest.importorskip("matplotlib")
    from occtrack.experiments.scan_tracking import occlusion_picture

    picture = occlusion_picture(0, 150)
    assert picture.time >= 10.0 and set(picture.tracks) == {"measurement-wise", "none"}
    assert len(picture.people) == len(picture.occluded) and picture.returns.shape[1] == 2
    figure = tmp_path / "scan.png"
    args = ["reproduce", "lidar", "--seeds", "0", "--scans", "150", "--trackers", "none",
            "--quiet", "--figure", str(figure)]
    assert main(args) == 0
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert main(args) != 0  # the figure exists now
    assert "exists" in capsys.readouterr().err


def test_reproduce_lidar_animates_the_scans_around_the_picked_one_and_never_overwrites(
        tmp_path, capsys):
    """--animation writes a GIF of --animation-scans frames, a scan each, around the scan
    --figure draws; an existing file is refused before the run unless --force, a short run
    too."""
    pytest.importorskip("matplotlib")
    from PIL import Image

    gif = tmp_path / "scans.gif"

    def reproduce(scans, *more):
        return main(["reproduce", "lidar", "--seeds", "0", "--scans", str(scans), "--trackers",
                     "none", "--quiet", "--animation", str(gif), "--animation-scans", "4",
                     *more])

    assert reproduce(105) == 0
    assert "(4 frames) animated in" in capsys.readouterr().out
    with Image.open(gif) as image:
        assert image.format == "GIF" and image.n_frames == 4
        assert image.info["duration"] == 100  # ms: 10 frames a second, the scan rate
    written = gif.read_bytes()
    assert reproduce(105) != 0  # the animation exists now
    assert "exists" in capsys.readouterr().err and gif.read_bytes() == written
    assert reproduce(100, "--force") != 0  # no scan after the first 10 s to pick
    assert "more than 100 scans" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scans.gif"]  # no temporary left


def test_the_picked_window_is_arounds_without_holding_the_stream():
    """PickWindow, fed a stream with picks at some items, keeps what `around` cuts from the
    whole stream at the last pick (every stream of up to 9 items, every pick set, windows of 1
    to 5), makes only the items it may keep, and never holds more than 3 windows' worth."""
    import itertools

    from occtrack.experiments.scan_tracking import PickWindow, around

    for n in range(1, 10):
        for length in range(1, 6):
            for picks in itertools.chain.from_iterable(
                    itertools.combinations(range(n), k) for k in (1, 2, 3)):
                window, made = PickWindow(length), []
                for i in range(n):
                    window.add(lambda i=i, made=made: made.append(i) or i, i in picks)
                    assert len(window.kept) + len(window.recent) <= 3 * length
                kept, index = window.result()
                assert kept == around(list(range(n)), picks[-1], length)
                assert kept[index] == picks[-1]
                if length == 1:
                    assert made == list(picks)  # a figure makes only the picked scans


def test_an_animation_is_a_frame_per_scan_on_fixed_axes_holding_everyone(tmp_path):
    pytest.importorskip("matplotlib")
    from PIL import Image

    from occtrack.errors import OcctrackError
    from occtrack.experiments.scan_tracking import OcclusionPicture, around
    from occtrack.viz.lidar import animate_scan_tracks, window_limits

    assert around(list(range(10)), 5, 4) == [3, 4, 5, 6]
    assert around(list(range(10)), 0, 4) == [0, 1, 2, 3]
    assert around(list(range(10)), 9, 4) == [6, 7, 8, 9]
    assert around(list(range(3)), 1, 4) == [0, 1, 2]
    pictures = [OcclusionPicture(
        0.1 * k, np.zeros(2), np.array([[1.0 + k, 0.5], [-2.0, 3.0]]),
        np.array([[1.0 + k, 0.75], [-2.0 - k, 3.25]]), np.array([1, 2]), np.array([False, k > 1]),
        0.25, {"measurement-wise": (np.array([[1.0 + k, 0.7]]), np.array([7]), np.array([k > 1])),
               "none": (np.array([[-9.0, -4.0 + k]]), np.array([8]), np.array([False]))})
        for k in range(3)]
    (x0, x1), (y0, y1) = window_limits(pictures)
    assert x0 < -9.0 - 0.25 and x1 > 3.0 + 0.25 and y0 < -4.0 - 0.25 and y1 > 3.25 + 0.25
    path = animate_scan_tracks(tmp_path / "three.gif", pictures)
    with Image.open(path) as image:
        assert image.n_frames == 3
    with pytest.raises(OcctrackError, match="exists"):
        animate_scan_tracks(path, pictures[:2])
    animate_scan_tracks(path, pictures[:2], overwrite=True)
    with Image.open(path) as image:
        assert image.n_frames == 2
    with pytest.raises(OcctrackError, match=r"\.gif"):
        animate_scan_tracks(path.with_suffix(".png"), pictures)


def test_a_picture_without_matplotlib_names_the_extra_before_the_run(monkeypatch, tmp_path,
                                                                      capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib fails
    gif = tmp_path / "scans.gif"
    assert main(["reproduce", "lidar", "--seeds", "0", "--scans", "1800", "--quiet",
                 "--animation", str(gif)]) != 0
    err = capsys.readouterr().err
    assert "matplotlib" in err and 'pip install "occtrack[viz]"' in err
    assert not gif.exists()
