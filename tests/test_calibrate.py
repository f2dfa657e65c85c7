"""`occtrack calibrate`: the detector model recovered from simulated detections whose true
parameters are known (`occtrack.scenarios.detector`), and the TOML it writes.

The scene: 36 people in their own cells of a 1920 x 1080 image (so non-maximum suppression
never joins two of them), heights log-uniform in 40-300 px, visibility drawn afresh every 25
frames, 600 frames. The simulated detector's truth, from its parameters:
- a person is detected when the logit b + w_v (v - 1) - w_h max(0, log(h_ref / h)) + d + e
  clears logit(0.5), with d + e ~ N(0, person_std^2 + noise_std^2) marginally, so P_D of a row
  is Phi(mu / sqrt(person_std^2 + noise_std^2));
- false boxes come at false_positive_rate per frame with logit-normal scores, so the false
  detections per frame with a score in [a, b) are that rate times the normal mass of
  [logit a, logit b) above logit(0.5);
- the left / right edges move by edge_noise_x of the width, top / bottom by edge_noise_y of
  the height.
Over 100 seeds of this scene (scene and detector) the 95 % intervals covered the truth 90-100 %
of the time, quantity by quantity (mean 96 %); here a few fixed seeds are checked: every
headline quantity inside its interval, and nearly every bin.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import logit
from scipy.stats import norm

from occtrack._compat import tomllib
from occtrack.cli import main
from occtrack.config import TrackerConfig
from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.models.calibration import (
    BOOTSTRAP,
    EDGES,
    HEIGHT_BINS,
    SCORE_BINS,
    VISIBILITY_BINS,
    Z95,
    Calibration,
    Estimate,
    Labelled,
    _bins,
    _bootstrap_weights,
    _edge_noise,
    _inflation,
    _percentile,
    _recently_detected,
    _score_centres,
    _size_area,
    _wilson,
    calibrate,
    match,
    poisson_power_fit,
    proportion,
    rate,
    report_lines,
    to_toml,
)
from occtrack.scenarios.detector import DetectorConfig, simulate_detections

FRAMES = 600
SIZE = (1920.0, 1080.0)
CONFIG = DetectorConfig()


def scene(seed: int, frames: int = FRAMES, cols: int = 12, rows: int = 3,
          segment: int = 25) -> MotTable:
    rng = np.random.default_rng(seed)
    n = cols * rows
    h = np.exp(rng.uniform(np.log(40.0), np.log(300.0), n))
    w = 0.41 * h
    cx = (np.arange(n) % cols + 0.5) * 160.0
    bottom = (np.arange(n) // cols + 1) * 360.0 - 20.0
    frame = np.repeat(np.arange(1, frames + 1), n)
    ids = np.tile(np.arange(1, n + 1), frames)
    vis = rng.uniform(0.0, 1.0, (frames // segment + 1, n))[(frame - 1) // segment, ids - 1]
    k = ids - 1
    box = np.stack([cx[k] - w[k] / 2, bottom[k] - h[k], w[k], h[k]], axis=1)
    m = len(frame)
    return MotTable(frame, ids, box, np.ones(m), np.ones(m, dtype=np.int64), vis)


def true_detection(gt: MotTable, cfg: DetectorConfig = CONFIG) -> np.ndarray:
    mu = (cfg.bias + cfg.visibility_weight * (gt.visibility - 1)
          - cfg.height_weight * np.log(cfg.height_ref / gt.box[:, 3]).clip(0))
    return norm.cdf((mu - logit(cfg.score_threshold)) / math.hypot(cfg.person_std,
                                                                   cfg.noise_std))


def true_false_rates(cfg: DetectorConfig = CONFIG) -> np.ndarray:
    lo = logit(np.maximum(np.array(SCORE_BINS[:-1]), cfg.score_threshold))
    with np.errstate(divide="ignore"):
        hi = logit(np.array(SCORE_BINS[1:]))
    mass = (norm.cdf((hi - cfg.false_positive_logit) / cfg.false_positive_logit_std)
            - norm.cdf((lo - cfg.false_positive_logit) / cfg.false_positive_logit_std))
    return cfg.false_positive_rate * np.where(np.array(SCORE_BINS[1:]) > cfg.score_threshold,
                                              mass, 0.0)


@pytest.fixture(scope="module", params=[0, 1, 2])
def simulated(request):
    seed = request.param
    gt = scene(seed)
    det = simulate_detections(gt, seed, CONFIG, image_size=SIZE, num_frames=FRAMES)
    return gt, det, calibrate([Labelled("SYN", gt, det, SIZE, 30.0, FRAMES)], seed=seed)


def test_headline_parameters_are_recovered_within_their_intervals(simulated):
    gt, _, cal = simulated
    pd = true_detection(gt)
    assert cal.detection_overall.covers(pd.mean())
    assert cal.detectability.covers(pd[gt.visibility >= 0.75].mean())
    assert cal.false_per_frame.covers(true_false_rates().sum())
    for edge, truth in (("left", CONFIG.edge_noise_x), ("right", CONFIG.edge_noise_x),
                        ("top", CONFIG.edge_noise_y), ("bottom", CONFIG.edge_noise_y)):
        estimate = cal.edge_std_own[edge]
        assert estimate.covers(truth), (edge, estimate)
        assert estimate.high - estimate.low < 0.2 * truth  # and the interval says something
        assert cal.edge_bias[edge].covers(0.0)
    # the tracker's unit is the box height: top and bottom are edge_noise_y there
    assert cal.edge_std["top"].covers(CONFIG.edge_noise_y)
    assert cal.detection_overall.high - cal.detection_overall.low < 0.15
    # clutter falls with the score as simulated (no power law, so no true c and p): the
    # fitted power is positive, each point estimate inside its interval
    for e in (cal.clutter_rate, cal.clutter_score_power):
        assert 0.0 < e.low < e.value < e.high < math.inf, e


def test_detection_and_clutter_curves_are_recovered_bin_by_bin(simulated):
    gt, _, cal = simulated
    pd = true_detection(gt)
    vb, hb = _bins(gt.visibility, VISIBILITY_BINS), _bins(gt.box[:, 3], HEIGHT_BINS)
    checks = [e.covers(pd[vb == i].mean()) for i, (_, _, e) in enumerate(cal.by_visibility)]
    checks += [e.covers(pd[hb == j].mean()) for j, (_, _, e) in enumerate(cal.by_height)
               if e.n]
    rates = true_false_rates()
    checks += [e.covers(rates[k]) for k, (_, hi, e, _) in enumerate(cal.by_score)
               if hi > CONFIG.score_threshold]
    assert len(checks) >= 11
    assert sum(checks) >= len(checks) - 1, checks  # 95 % intervals: about 1 in 20 misses
    # detection falls with occlusion, and clutter with the score, as simulated
    values = [e.value for _, _, e in cal.by_visibility]
    assert values == sorted(values)
    assert cal.by_score[1][2].value > cal.by_score[2][2].value


def test_power_law_fit_is_exact_on_its_own_model():
    """False counts exactly c s^-p times their exposure: the fit returns c and p, whatever
    the exposure's scale (a total exposure below one included)."""
    centres = np.array([0.3, 0.7, 0.95, 0.995, 0.9995])
    hits = np.array([50.0, 100.0, 400.0, 800.0, 20000.0])
    for frames, area in ((1000.0, 2.0), (1.0, 0.5)):
        for c, p in ((0.02, 2.5), (0.5, 0.7)):
            exposure = frames * area * hits / hits.sum()
            counts = exposure * c * centres ** -p
            got_c, got_p = poisson_power_fit(counts, hits, frames, area, centres)
            assert got_c[0] == pytest.approx(c, rel=1e-6)
            assert got_p[0] == pytest.approx(p, rel=1e-6)
    frames, area = 1000.0, 2.0
    # no false detection at all: no clutter
    got_c, _ = poisson_power_fit(np.zeros(5), hits, frames, area, centres)
    assert got_c[0] == 0.0
    # hits in one bin only: no slope can be told, the flat rate with p = 0
    single = np.array([0.0, 0.0, 400.0, 0.0, 0.0])
    got_c, got_p = poisson_power_fit(np.array([0.0, 0.0, 6.0, 0.0, 0.0]), single, frames, area,
                                     centres)
    assert got_c[0] == pytest.approx(6.0 / (frames * area), rel=1e-12) and got_p[0] == 0.0
    # one false detection, in the bin with a single hit: all of it is there (share 1/21351)
    one_hit = np.array([0.0, 1.0, 400.0, 800.0, 20000.0])
    got_c, got_p = poisson_power_fit(np.array([0.0, 1.0, 0, 0, 0]), one_hit, frames, area,
                                     centres)
    assert got_c[0] > 0 and 0 <= got_p[0] < np.inf
    # false counts in a bin without hits are left out of the fit
    with_extra = poisson_power_fit(np.array([7.0, 1.0, 0, 0, 0]), one_hit, frames, area,
                                   centres)
    assert with_extra[0][0] == got_c[0] and with_extra[1][0] == got_p[0]


def test_command_writes_a_tracker_config(tmp_path, capsys):
    gt = scene(3, frames=200)
    det = simulate_detections(gt, 3, CONFIG, image_size=SIZE, num_frames=200)
    gt_file, det_file = tmp_path / "gt.txt", tmp_path / "det.txt"
    gt_file.write_text("".join(
        f"{f},{i},{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{b[3]:.2f},1,1,{v:.3f}\n"
        for f, i, b, v in zip(gt.frame, gt.id, gt.box, gt.visibility, strict=True)))
    det_file.write_text("".join(f"{f},-1,{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{b[3]:.2f},{s}\n"
                                for f, b, s in zip(det.frame, det.box, det.score,
                                                   strict=True)))
    out = tmp_path / "detector.toml"
    args = ["calibrate", str(gt_file), str(det_file), "--image-size", "1920x1080",
            "--fps", "30", "-o", str(out)]
    assert main(args) == 0
    report = capsys.readouterr().out
    assert "by visibility" in report and "edge_noise" in report
    data = tomllib.loads(out.read_text())
    assert set(data) <= {"detectability", "detectability_ratio", "clutter_rate",
                         "clutter_score_power", "edge_noise"}
    assert {"detectability", "edge_noise", "clutter_rate"} <= set(data)
    config = TrackerConfig.from_toml(out)  # what `occtrack track --config` does
    assert config.edge_noise == data["edge_noise"]
    assert 0.01 < data["edge_noise"] < 0.1 and 0.5 < data["detectability"] < 1
    text = out.read_text()
    assert "95 % interval" in text and "# The measurements:" in text

    assert main(args) == 1  # exists: --force to overwrite
    assert "--force" in capsys.readouterr().err
    result = tmp_path / "result.txt"
    assert main(["track", str(det_file), "--image-size", "1920x1080", "--fps", "30",
                 "--config", str(out), "-o", str(result)]) == 0
    assert result.stat().st_size > 0
    capsys.readouterr()
    assert main(["calibrate", str(gt_file), "-o", str(tmp_path / "x.toml")]) == 1
    assert "in pairs" in capsys.readouterr().err
    assert main(["calibrate", str(gt_file), str(det_file)]) == 1
    assert "--image-size" in capsys.readouterr().err


def test_mot17_04_real_detections(mot17_04, tmp_path, capsys):
    """On the real detections the command runs, and the intervals hold their estimates."""
    out = tmp_path / "detector.toml"
    assert main(["calibrate", str(mot17_04 / "gt" / "gt.txt"),
                 str(mot17_04 / "det" / "det.txt"), "-o", str(out), "--quiet"]) == 0
    data = tomllib.loads(out.read_text())
    TrackerConfig.from_toml(out)
    assert 0.005 < data["edge_noise"] < 0.1
    assert data["clutter_rate"] > 0 and data["clutter_score_power"] >= 0


def _detected(gt: MotTable, keep: np.ndarray) -> MotTable:
    """The true boxes of `gt` where `keep` (frames, people), as detections (score 0.9)."""
    rows = np.flatnonzero(keep.ravel())
    return MotTable(gt.frame[rows], np.full(len(rows), -1), gt.box[rows],
                    np.full(len(rows), 0.9), np.full(len(rows), -1), np.full(len(rows), -1.0))


def _static_people(people: int, frames: int, keep: np.ndarray) -> tuple[MotTable, MotTable]:
    """People standing apart in full view, detected exactly where `keep` (frames, people)."""
    gt = scene(0, frames=frames, cols=people, rows=1)
    gt = MotTable(gt.frame, gt.id, gt.box, gt.score, gt.cls, np.ones(len(gt.frame)))
    return gt, _detected(gt, keep)


def test_tracked_detectability_is_p_d_when_misses_are_independent():
    """Misses drawn independently: having been detected lately says nothing, so P(hit | hit
    within the horizon) is P_D itself, and `occlusion = none` gets it."""
    frames, people, p = 300, 12, 0.7
    keep = np.random.default_rng(5).random((frames, people)) < p
    gt, det = _static_people(people, frames, keep)
    cal = calibrate([Labelled("IID", gt, det, SIZE, 30.0, frames)])
    assert cal.detection_tracked.covers(p) and cal.detection_overall.covers(p)
    assert cal.settings(occlusion=False)["detectability"] == cal.detection_tracked.value


def test_tracked_detectability_leaves_out_people_lost_long_ago():
    """Each person seen for 60 frames, then hidden for 60: half the rows are misses, but the
    tracker (horizon 0.67 s = 20 frames at 30 fps) holds a person from the second hit of a
    run (the first follows 60 misses, or nothing) to the 20th miss after it: 59 of those 79
    rows a cycle are hits."""
    frames, people = 480, 6
    keep = np.tile((np.arange(frames) // 60 % 2 == 0)[:, None], (1, people))
    gt, det = _static_people(people, frames, keep)
    cal = calibrate([Labelled("RUNS", gt, det, SIZE, 30.0, frames)])
    assert cal.detection_overall.value == pytest.approx(0.5)
    assert cal.detection_tracked.value == pytest.approx(59 / 79)
    assert cal.settings(occlusion=True)["detectability"] == pytest.approx(0.5)


# -- exact values: the report of a fixed scene, the matching, the settings -----------------------

REPORT = """\
sequences: A, B; 240 frames, 2520 pedestrian boxes, 1210 detections: 940 hits, 165 false, 105 on distractors (set aside); match IoU >= 0.5

detection probability, all pedestrians: 0.373 [0.280, 0.476]
  visible (visibility >= 0.75): 0.452 [0.320, 0.592]
  tracked (detected within the last 0.67 s): 0.626 [0.544, 0.701]
  memory per frame P(hit|hit) - P(hit|miss), visible and tracked: 0.817 [0.755, 0.887]; half-second ratio 0.926 [0.805, 0.976]
  memory per frame, tracked: 0.817 [0.770, 0.866]; half-second ratio 0.935 [0.861, 0.971]
  by visibility:
    0-0.25      0.000 [0.000, 0.020]      n     310  effective      186
    0.25-0.5    0.074 [0.009, 0.407]      n     215  effective        8
    0.5-0.75    0.509 [0.214, 0.798]      n     385  effective        7
    0.75-1      0.452 [0.320, 0.592]      n    1610  effective       48
  by box height (px):
    0-50        0.058 [0.002, 0.621]      n     240  effective        3
    50-100      0.402 [0.188, 0.662]      n     840  effective       13
    100-200     0.346 [0.191, 0.543]      n     840  effective       25
    200-400     0.495 [0.379, 0.612]      n     600  effective       67
    >= 400      -                         n       0  effective        0
  by visibility (rows) and height (columns), value (n):
                            0-50          50-100         100-200         200-400          >= 400
    0-0.25                     -     0.000 (120)     0.000 (145)      0.000 (45)               -
    0.25-0.5          0.000 (70)      0.000 (20)      0.000 (75)      0.320 (50)               -
    0.5-0.75          0.140 (50)     0.624 (170)      0.653 (95)      0.300 (70)               -
    0.75-1           0.058 (120)     0.438 (530)     0.436 (525)     0.598 (435)               -

false detections per frame: 0.688 [0.401, 1.100]
  by score (false per frame; hits in the bin):
    0-0.5       0.0000 [0.0000, 0.0239]       n      0  hits       0
    0.5-0.9     0.4625 [0.3277, 0.6342]       n    111  hits     678
    0.9-0.99    0.0583 [0.0115, 0.1739]       n     14  hits     204
    0.99-0.999  0.1667 [0.0352, 0.4822]       n     40  hits      58
    0.999-1     0.0000 [0.0000, 0.0239]       n      0  hits       0
  tracker's clutter term: clutter_rate 0.1935 [0.0188, 0.2886] and clutter_score_power 0.00 [0.00, 4.35]
  (false boxes spread over 3.55 in log width x log height: the 1st-99th percentile ranges of the detections)

box-edge noise, matched people with visibility >= 0.5, edges off the border: std in true box heights (own axis size), bias, robust std
    left    std 0.020 [0.020, 0.021]    (0.050 [0.048, 0.051])  bias 0.000 [-0.001, 0.001]     robust 0.020   n 924
    top     std 0.040 [0.037, 0.042]    (0.040 [0.037, 0.042])  bias 0.001 [-0.000, 0.003]     robust 0.041   n 924
    right   std 0.021 [0.020, 0.022]    (0.051 [0.048, 0.053])  bias 0.001 [-0.001, 0.003]     robust 0.021   n 924
    bottom  std 0.040 [0.038, 0.041]    (0.040 [0.038, 0.041])  bias -0.001 [-0.003, 0.001]    robust 0.040   n 924
  pooled about each edge's bias: edge_noise 0.0316 [0.0309, 0.0321]
note: B: no visibility column; every person counted as visible
"""  # noqa: E501


@pytest.fixture(scope="module")
def two_sequences():
    """Sequence A has classes (person 3 a distractor, person 5 not to be considered, person 8
    of class 3, neither) at 30 fps; B is the same without class or visibility columns at 25
    fps."""
    gt = scene(7, frames=120, cols=6, rows=2)
    det = simulate_detections(gt, 7, CONFIG, image_size=SIZE, num_frames=120)
    cls, score = gt.cls.copy(), gt.score.copy()
    cls[gt.id == 3], score[gt.id == 5], cls[gt.id == 8] = 7, 0, 3
    a = MotTable(gt.frame, gt.id, gt.box, score, cls, gt.visibility)
    m = len(gt.frame)
    b = MotTable(gt.frame, gt.id, gt.box, np.ones(m), np.full(m, -1), np.full(m, -1.0))
    return calibrate([Labelled("A", a, det, SIZE, 30.0, 120),
                      Labelled("B", b, det, SIZE, 25.0, 120)], seed=3)


def _numbers(cal):
    """Every number of a calibration: (values and bounds, counts and effective counts)."""
    small, counts = [], []

    def add(x):
        if isinstance(x, Estimate):
            small.extend([x.value, x.low, x.high])
            counts.extend([float(x.n), x.effective])
        else:
            small.append(float(x))

    for f in dataclasses.fields(cal):
        v = getattr(cal, f.name)
        if f.name in ("sequences", "notes"):
            continue
        if isinstance(v, dict):
            for x in v.values():
                add(x)
        elif isinstance(v, list):
            for row in v:
                for x in row:
                    add(x)
        elif isinstance(v, Estimate):
            add(v)
    return np.array(small), np.array(counts)


def test_report_of_a_fixed_scene_is_exact(two_sequences):
    """The printed report (3-4 digits) and a fingerprint of every number at full precision,
    as this code computes them on a fixed scene and seed; any change to the estimates, their
    intervals or the text shows here. The counts are those of the scene: 12 people x 120
    frames x 2 sequences = 2880 rows, 2520 of them pedestrians (person 5 is not considered in
    A, persons 3 and 8 are not pedestrians there)."""
    cal = two_sequences
    assert "\n".join(report_lines(cal)) + "\n" == REPORT
    assert (cal.frames, cal.targets, cal.hits + cal.false + cal.set_aside) == (240, 2520,
                                                                              cal.detections)
    for values, (size, finite, fingerprint) in zip(
            _numbers(cal), ((208, 189, 23008.703344651658), (114, 95, 223992.67767104018)),
            strict=True):
        ok = np.isfinite(values)
        assert (len(values), int(ok.sum())) == (size, finite)
        weights = np.sqrt(np.arange(1, size + 1))[ok]
        assert float(np.sum(values[ok] * weights)) == pytest.approx(fingerprint, rel=1e-11)


def test_toml_holds_the_settings_their_intervals_and_the_report(two_sequences):
    cal = two_sequences
    text = to_toml(cal, occlusion=False, command="occtrack calibrate x")
    head, tail = text.split("# The measurements:\n")
    assert head == TOML_HEAD
    assert tail == "".join(f"#   {line}\n" if line else "#\n" for line in report_lines(cal))
    settings = tomllib.loads(text)
    want = cal.settings(occlusion=False)
    assert list(settings) == list(want)  # four digits
    assert all(settings[k] == float(f"{want[k]:.4g}") for k in want)
    occluded = to_toml(cal)
    assert "# P_D of visible people (visibility >= 0.75), for occlusion models; estimate " \
           "0.4522, 95 % interval [0.3197, 0.5918]\ndetectability = 0.4522\n" in occluded
    assert occluded.startswith("# occtrack detector calibration (occtrack calibrate)\n# Only")


TOML_HEAD = """\
# occtrack detector calibration (occtrack calibrate)
# occtrack calibrate x
# Only TrackerConfig fields below; load with: occtrack track --config FILE.
# Each setting: its 95 % interval and meaning in the comment above it.

# P_D of tracked pedestrians (detected within the last 0.67 s), for occlusion = none; estimate 0.6258, 95 % interval [0.5437, 0.7012]
detectability = 0.6258

# half-second ratio of the detectability chain, tracked people; estimate 0.9354, 95 % interval [0.861, 0.9708]
detectability_ratio = 0.9354

# kappa W H w h at score 1: false boxes per frame per unit of log w x log h, over the hits' score density; estimate 0.1935, 95 % interval [0.01877, 0.2886]
clutter_rate = 0.1935

# clutter term ~ score ** -power; estimate 0.0, 95 % interval [0.0, 4.35]
clutter_score_power = 0.0

# std of a box edge, in box heights; estimate 0.03158, 95 % interval [0.03095, 0.03211]
edge_noise = 0.03158

"""  # noqa: E501


def _table(frame, ids, boxes, score=None, cls=None, vis=None) -> MotTable:
    n = len(frame)
    return MotTable(np.asarray(frame), np.asarray(ids), np.asarray(boxes, dtype=float),
                    np.ones(n) if score is None else np.asarray(score, dtype=float),
                    np.full(n, -1) if cls is None else np.asarray(cls),
                    np.full(n, -1.0) if vis is None else np.asarray(vis, dtype=float))


def test_match_by_class_consider_flag_and_iou():
    """Frame 1: a pedestrian, a pedestrian not to be considered, a distractor (7), a car (3,
    not considered, as in MOT17) and a box of class 0 (neither); a detection on each, one
    false. Frame 2: one pedestrian, one detection at IoU exactly 0.5 (matches). Frame 3: one
    pedestrian, a detection at IoU 0.49 (false). Frame 5 (after the last ground truth): a
    false detection."""
    box = [[0, 0, 10, 20], [100, 0, 10, 20], [200, 0, 10, 20], [300, 0, 10, 20],
           [400, 0, 10, 20]]
    gt = _table([1, 1, 1, 1, 1, 2, 3], [1, 2, 3, 4, 5, 1, 1],
                box + [[0, 0, 10, 20], [0, 0, 10, 20]], score=[1, 0, 1, 0, 1, 1, 1],
                cls=[1, 1, 7, 3, 0, 1, 1])
    # IoU of [0, 0, 10, 20] with [0, 0, 10, 10] is 0.5; with [0, 0, 10, 9.8] it is 0.49
    det = _table([1, 1, 1, 1, 1, 1, 2, 3, 5],
                 [-1] * 9, box + [[600, 0, 10, 20], [0, 0, 10, 10], [0, 0, 10, 9.8],
                                  [0, 0, 10, 20]])
    m = match(gt, det, 5)
    assert m.target.dtype == bool and m.gt_match.dtype == np.int64
    assert m.det_kind.dtype == np.int64
    assert m.target.tolist() == [True, False, False, False, False, True, True]
    assert m.gt_match.tolist() == [0, -1, -1, -1, -1, 6, -1]
    assert m.det_kind.tolist() == [1, -1, -1, 0, 0, 0, 1, 0, 0]


def test_match_without_a_class_column_takes_every_row_as_a_pedestrian():
    gt = _table([1, 2, 2], [1, 1, 2], [[0, 0, 10, 20], [0, 0, 10, 20], [50, 0, 10, 20]])
    det = _table([2, 2, 3], [-1] * 3, [[50, 0, 10, 20], [1, 0, 10, 20], [0, 0, 10, 20]])
    m = match(gt, det, 3)
    assert m.target.tolist() == [True, True, True]
    assert m.gt_match.tolist() == [-1, 1, 0]
    assert m.det_kind.tolist() == [1, 1, 0]
    # one row, with a class: a distractor is not a target
    one = match(_table([1], [1], [[0, 0, 10, 20]], cls=[7]), _table([1], [-1], [[0, 0, 10, 20]]), 1)
    assert one.target.tolist() == [False] and one.det_kind.tolist() == [-1]
    # no rows at all
    empty = match(_table([], [], np.zeros((0, 4))), det, 3)
    assert empty.target.shape == (0,) and empty.det_kind.tolist() == [0, 0, 0]


def _estimate(value, low=None, high=None):
    return Estimate(value, value if low is None else low, value if high is None else high, 10,
                    10.0)


def _calibration(**changes) -> Calibration:
    base = dict(sequences=["S"], frames=10, targets=5, detections=4, hits=3, false=1,
                set_aside=0, detection_overall=_estimate(0.6), detectability=_estimate(0.8),
                detection_tracked=_estimate(0.7), horizon=0.5,
                memory_visible=_estimate(0.2), ratio_visible=_estimate(0.3),
                memory_tracked=_estimate(0.9), ratio_tracked=_estimate(0.6),
                by_visibility=[], by_height=[], joint=[], false_per_frame=_estimate(0.1),
                by_score=[], size_area=1.0, clutter_rate=_estimate(0.05),
                clutter_score_power=_estimate(2.0),
                edge_bias=dict.fromkeys(EDGES, _estimate(0.0)),
                edge_std=dict.fromkeys(EDGES, _estimate(0.04)),
                edge_std_own=dict.fromkeys(EDGES, _estimate(0.05)),
                edge_robust=dict.fromkeys(EDGES, 0.04), edge_noise=_estimate(0.04))
    base.update(changes)
    return Calibration(**base)


def test_settings_clip_and_leave_out_what_was_not_measured():
    cal = _calibration()
    assert cal.settings() == cal.settings(occlusion=True) == {
        "detectability": 0.8, "detectability_ratio": 0.6, "clutter_rate": 0.05,
        "clutter_score_power": 2.0, "edge_noise": 0.04}
    assert cal.settings(occlusion=False)["detectability"] == 0.7
    assert cal.settings(occlusion=False)["detectability_ratio"] == 0.6
    nan = Estimate(float("nan"), float("nan"), float("nan"))
    cal = _calibration(detectability=_estimate(1.0), ratio_tracked=_estimate(1.5),
                       clutter_score_power=_estimate(-0.4), edge_noise=_estimate(0.0))
    assert cal.settings() == {"detectability": 0.999, "detectability_ratio": 1.0,
                              "clutter_rate": 0.05, "clutter_score_power": 0.0}
    cal = _calibration(detectability=_estimate(0.0), ratio_tracked=_estimate(-0.2),
                       clutter_rate=_estimate(0.0), edge_noise=nan)
    assert cal.settings() == {"detectability": 0.01, "detectability_ratio": 0.0}
    cal = _calibration(detectability=nan, ratio_tracked=nan, clutter_rate=nan,
                       clutter_score_power=_estimate(0.3))
    assert cal.settings() == {"edge_noise": 0.04}
    assert _calibration(clutter_score_power=_estimate(0.3)).settings()[
        "clutter_score_power"] == 0.3


def test_toml_says_what_it_clipped_and_left_out():
    nan = Estimate(float("nan"), float("nan"), float("nan"))
    cal = _calibration(detectability=_estimate(1.0, 0.98, 1.0), ratio_tracked=nan,
                       clutter_rate=_estimate(0.0), edge_noise=_estimate(0.04, 0.0, 0.0625))
    text = to_toml(cal)
    assert ("# P_D of visible people (visibility >= 0.75), for occlusion models; estimate 1, "
            "95 % interval [0.98, 1]\n# (clipped to [0.01, 0.999]: a certain detection leaves "
            "no room for a miss)\ndetectability = 0.999\n\n") in text
    assert ("# std of a box edge, in box heights; estimate 0.04, 95 % interval [0.0, 0.0625]"
            "\nedge_noise = 0.04\n\n# not set (no estimate in these data; the defaults hold): "
            "detectability_ratio, clutter_rate, clutter_score_power\n\n") in text
    assert "# occtrack calibrate" not in text.split("\n")[1]
    assert "# (clipped" not in to_toml(_calibration())


def test_estimate_covers_its_bounds_and_prints_three_digits():
    e = Estimate(0.5, 0.25, 0.75)
    assert e.covers(0.25) and e.covers(0.75) and not e.covers(0.2499999) and not e.covers(0.7500001)
    assert e.text() == "0.500 [0.250, 0.750]" and e.text(1) == "0.5 [0.2, 0.8]"
    assert Estimate(float("nan"), 0.0, 1.0).text() == "-"


def test_calibrate_names_what_is_missing():
    with pytest.raises(OcctrackError) as err:
        calibrate([])
    assert str(err.value) == ("calibration needs at least one pair of ground truth and "
                              "detections")
    gt = _table([1], [1], [[0, 0, 10, 20]], cls=[7], vis=[1.0])
    with pytest.raises(OcctrackError) as err:
        calibrate([Labelled("X", gt, gt, SIZE, 30.0, 1)])
    assert str(err.value) == ("the ground truth holds no pedestrian to calibrate against "
                              "(class 1 with a consider flag of 1)")


@pytest.mark.filterwarnings("error::RuntimeWarning")  # (no numpy warning either)
def test_one_person_always_detected_gives_no_interval_and_sets_only_the_detectability():
    """One person (one cluster, one block of frames): nothing to resample, so every interval
    is as wide as it can be; detected in every frame, exactly where the truth is: no memory
    (never a miss), no clutter, no edge noise, a size area at its floor of 0.1 x 0.1."""
    box = np.tile([[100.0, 100.0, 40.0, 100.0]], (30, 1))
    gt = _table(np.arange(1, 31), np.ones(30, int), box, cls=np.ones(30, int), vis=np.ones(30))
    cal = calibrate([Labelled("ONE", gt, gt, SIZE, 30.0, 30)])
    assert (cal.targets, cal.hits, cal.false, cal.set_aside) == (30, 30, 0, 0)
    # tracked: every frame but the first follows a detection
    for e, n in ((cal.detection_overall, 30), (cal.detectability, 30),
                 (cal.detection_tracked, 29)):
        assert (e.value, e.low, e.high, e.n) == (1.0, 0.0, 1.0, n)
    assert math.isnan(cal.memory_visible.value) and cal.memory_visible.n == 29
    assert math.isnan(cal.ratio_visible.value)
    for e in (cal.memory_visible, cal.ratio_visible):
        assert math.isnan(e.low) and math.isnan(e.high)
    assert (cal.false_per_frame.value, cal.false_per_frame.low) == (0.0, 0.0)
    assert cal.false_per_frame.high == math.inf
    assert cal.clutter_rate.value == 0.0 and math.isnan(cal.clutter_score_power.value)
    assert cal.size_area == pytest.approx(0.01, rel=1e-12)
    assert cal.edge_noise.value == 0.0 and cal.edge_noise.n == 120
    assert all(cal.edge_robust[name] == 0.0 for name in EDGES)
    assert cal.settings() == {"detectability": 0.999}
    lines = report_lines(cal)
    assert lines[5] == ("  memory per frame P(hit|hit) - P(hit|miss), visible and tracked: -; "
                        "half-second ratio -")
    assert lines[-1] == "  pooled about each edge's bias: edge_noise 0.0000 [0.0000, inf]"


def _two_people(frames, box1, box2, hit1, hit2, err1=None):
    """Two people standing still in full view; person 1's detections have right-edge errors
    `err1` (px), person 2's are exact."""
    f = np.arange(1, frames + 1)
    gt = _table(np.r_[f, f], np.r_[np.ones(frames, int), np.full(frames, 2)],
                np.r_[np.tile(box1, (frames, 1)), np.tile(box2, (frames, 1))],
                cls=np.ones(2 * frames, int), vis=np.ones(2 * frames))
    d1 = np.tile(np.asarray(box1, float), (frames, 1))
    if err1 is not None:
        d1[:, 2] += err1
    boxes = np.r_[d1[hit1], np.tile(box2, (int(hit2.sum()), 1))]
    det = _table(np.r_[f[hit1], f[hit2]], [-1] * len(boxes), boxes,
                 score=np.full(len(boxes), 0.9))
    return calibrate([Labelled("TWO", gt, det, SIZE, 30.0, frames)], seed=1)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_edges_with_fewer_than_two_rows_have_no_estimate():
    """Person 1 touches the left, top and bottom borders (only its right edge counts) and is
    detected twice, with right-edge errors +4 and -6 px; person 2 touches the right border and
    is detected once. So the right edge has two rows: bias -1 px, std 10 / sqrt(2) px (over
    the box height 1080, or the width 200); the others one row each: no estimate."""
    frames = 5
    hit1, hit2 = np.arange(frames) < 2, np.arange(frames) == 0
    cal = _two_people(frames, [0.0, 0.0, 200.0, 1080.0], [1800.0, 400.0, 120.0, 200.0],
                      hit1, hit2, err1=np.array([4.0, -6.0, 0.0, 0.0, 0.0]))
    right = cal.edge_std["right"]
    assert right.n == 2 and right.value == pytest.approx(10 / math.sqrt(2) / 1080, rel=1e-12)
    assert cal.edge_std_own["right"].value == pytest.approx(10 / math.sqrt(2) / 200, rel=1e-12)
    assert cal.edge_bias["right"].value == pytest.approx(-1 / 1080, rel=1e-12)
    assert cal.edge_robust["right"] == pytest.approx(1.4826 * 5 / 1080, rel=1e-12)
    for name in ("left", "top", "bottom"):
        for table in (cal.edge_std, cal.edge_std_own, cal.edge_bias):
            e = table[name]
            assert e.n == 1 and all(math.isnan(v) for v in (e.value, e.low, e.high)), name
        assert math.isnan(cal.edge_robust[name])
    # detected once each: no edge has two rows, nothing to pool
    once = _two_people(frames, [0.0, 0.0, 200.0, 1080.0], [1800.0, 400.0, 120.0, 200.0],
                       np.arange(frames) == 1, hit2)
    assert once.edge_noise.n == 0 and math.isnan(once.edge_noise.value)
    assert math.isnan(once.edge_noise.low) and math.isnan(once.edge_noise.high)
    assert "edge_noise" not in once.settings()
    # pooled about the bias: the two right-edge rows only
    assert cal.edge_noise.n == 2
    assert cal.edge_noise.value == pytest.approx(10 / math.sqrt(2) / 1080, rel=1e-12)
    assert cal.edge_noise.low == 0.0


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_memory_leaves_out_a_person_never_detected():
    """One person always detected, one never: the tracker never holds the second, so none of
    its pairs count (n 39, person 1's), and with no pair after a miss there is no memory to
    give. The bootstrap draws that take one person twice have no pairs after a miss: their
    0 / 0 is dropped quietly, not warned about."""
    frames = 40
    cal = _two_people(frames, [100.0, 100.0, 80.0, 200.0], [900.0, 400.0, 80.0, 200.0],
                      np.ones(frames, bool), np.zeros(frames, bool))
    assert cal.memory_visible.n == 39 and math.isnan(cal.memory_visible.value)
    assert "detectability_ratio" not in cal.settings()


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_memory_counts_a_run_of_misses_only_within_the_horizon():
    """Person 1 is always detected; person 2 in frames 1-5 only. The horizon (0.67 s at 30
    fps: 20 frames) keeps person 2's pairs up to frame 25: after a hit 39 + 5 pairs with
    39 + 4 hits, after a miss 19 pairs (frames 7-25) with none. lambda = 43/44 - 0."""
    frames = 40
    f = np.arange(1, frames + 1)
    cal = _two_people(frames, [100.0, 100.0, 80.0, 200.0], [900.0, 400.0, 80.0, 200.0],
                      np.ones(frames, bool), f <= 5)
    assert cal.memory_visible.n == 39 + 24
    assert cal.memory_visible.value == pytest.approx(43 / 44, rel=1e-12)
    assert cal.ratio_visible.value == pytest.approx(1 - (43 / 44) ** 15, rel=1e-12)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_memory_of_detection_by_hand_with_two_people():
    """Person 1 is detected every other frame, person 2 in runs of 10 frames, over 40 frames.
    After a hit: 20 + 20 pairs, 0 + 18 hits; after a miss: 19 + 19 pairs, 19 + 1 hits. So
    lambda = 18/40 - 20/38 = -29/380 < 0: no memory, half-second ratio 1. Two people are too few
    for an interval: it spans what lambda and the ratio can be."""
    frames = 40
    f = np.arange(1, frames + 1)
    cal = _two_people(frames, [100.0, 100.0, 80.0, 200.0], [900.0, 400.0, 80.0, 200.0],
                      f % 2 == 1, (f - 1) // 10 % 2 == 0)
    memory, ratio = cal.memory_visible, cal.ratio_visible
    assert memory.value == pytest.approx(-29 / 380, rel=1e-12) and memory.n == 78
    assert (memory.low, memory.high) == (-1.0, 1.0)
    assert ratio.value == 1.0 and ratio.high == 1.0 and ratio.n == 78
    assert 0.0 < ratio.low < 1.0
    assert cal.settings()["detectability_ratio"] == 1.0


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_the_chains_memory_counts_the_misses_behind_others():
    """Person 1 is always detected; person 2 is detected in frames 1-10, hidden (visibility
    0.3) and missed in 11-20, detected again in 21-40, all within the horizon. The visible
    people's memory (the detector's own) has no pair after a miss; the tracked people's
    (the tracker's chain) has after a hit 39 + 9 + 1 + 19 pairs with one miss, after a miss 10
    pairs with one hit: lambda = 67/68 - 1/10, and every model's file takes that ratio."""
    frames = 40
    f = np.arange(1, frames + 1)
    keep = np.stack([np.ones(frames, bool), (f <= 10) | (f > 20)], axis=1)
    gt, det = _static_people(2, frames, keep)
    hidden = (gt.id == gt.id.max()) & (gt.frame > 10) & (gt.frame <= 20)
    gt = MotTable(gt.frame, gt.id, gt.box, gt.score, gt.cls, np.where(hidden, 0.3, 1.0))
    cal = calibrate([Labelled("HIDDEN", gt, det, SIZE, 30.0, frames)])
    assert math.isnan(cal.memory_visible.value) and cal.memory_visible.n == 39 + 28
    assert cal.memory_tracked.n == 78
    assert cal.memory_tracked.value == pytest.approx(67 / 68 - 1 / 10, rel=1e-12)
    ratio = 1 - (67 / 68 - 1 / 10) ** 15
    assert cal.ratio_tracked.value == pytest.approx(ratio, rel=1e-12)
    for occlusion in (False, True):
        assert cal.settings(occlusion)["detectability_ratio"] == pytest.approx(ratio)


def test_interval_helpers_on_hand_worked_input():
    # Wilson: no effective rows, no information; p = 1 reaches 1
    assert _wilson(0.5, 0.0) == (0.0, 1.0) and _wilson(0.5, -1.0) == (0.0, 1.0)
    z2 = Z95 * Z95
    low = (1 + z2 / 6 - Z95 * math.sqrt(z2 / 36)) / (1 + z2 / 3)
    assert _wilson(1.0, 3.0) == (pytest.approx(low, rel=1e-12), 1.0)
    # percentile interval: 2.5 % and 97.5 % of 0..9 are 0.225 and 8.775; fewer than 10
    # finite draws give none; clusters widen it about the estimate, bounds cut it
    e = _percentile(4.5, np.r_[np.arange(10.0), np.nan, np.inf])
    assert (e.value, e.n) == (4.5, 0)
    assert (e.low, e.high) == (pytest.approx(0.225, rel=1e-12), pytest.approx(8.775, rel=1e-12))
    none = _percentile(4.5, np.r_[np.arange(9.0), np.nan], n=3)
    assert none.value == 4.5 and none.n == 3 and math.isnan(none.low) and math.isnan(none.high)
    assert math.isnan(_percentile(float("nan"), np.arange(20.0)).low)
    grow = _inflation(3)
    wide = _percentile(4.5, np.arange(10.0), 7, 3)
    assert wide.low == pytest.approx(4.5 - grow * 4.275, rel=1e-12) and wide.n == 7
    assert (_percentile(4.5, np.arange(10.0), 7, 3, (1.0, 8.0)).low,
            _percentile(4.5, np.arange(10.0), 7, 3, (1.0, 8.0)).high) == (1.0, 8.0)
    assert _inflation(1) == math.inf and _inflation(0) == math.inf
    assert _inflation(2) == pytest.approx(math.sqrt(2) * 12.706204736174698 / Z95, rel=1e-9)
    assert _bootstrap_weights(0, np.random.default_rng(0)).shape == (BOOTSTRAP, 0)
    counts = _bootstrap_weights(3, np.random.default_rng(0))
    assert counts.shape == (BOOTSTRAP, 3) and np.all(counts.sum(axis=1) == 3)


def _std_and_draws(values, cluster, n_clusters, weights):
    """The sample standard deviation of `values` and its cluster-bootstrap draws, from the
    per-cluster count, sum and sum of squares."""
    k = np.zeros((n_clusters, 3))
    for j, v in enumerate((np.ones_like(values), values, values * values)):
        np.add.at(k[:, j], cluster, v)
    boot = weights @ k
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = boot[:, 1] / boot[:, 0]
        draws = np.sqrt(np.maximum(boot[:, 2] / boot[:, 0] - mean ** 2, 0.0) * boot[:, 0]
                        / np.maximum(boot[:, 0] - 1, 1))
    return float(np.std(values, ddof=1)), draws, mean


def test_edge_intervals_count_the_people_with_rows_and_stds_stay_positive():
    """Three people: four rows of one, one of another (its left edge only measured), none of
    the third. The intervals are widened for the two people with rows (neither all three nor
    only the one with more than one row), and a standard deviation's interval is cut at 0
    where the widening would pass it."""
    cluster = np.array([0, 0, 0, 0, 1])
    err = np.array([[1.0], [-1.0], [3.0], [-2.0], [0.5]]) * np.ones((1, 4))
    height = np.full(5, 100.0)
    size = np.tile([40.0, 100.0, 40.0, 100.0], (5, 1))
    valid = np.ones((5, 4), bool)
    valid[4, 1:] = False
    weights = _bootstrap_weights(3, np.random.default_rng(0))
    out = _edge_noise(cluster, err, height, size, valid, 3, weights)
    rel = err[:, 0] / 100.0
    sd, draws, means = _std_and_draws(rel, cluster, 3, weights)
    std = out["edge_std"]["left"]
    assert std.value == pytest.approx(sd, rel=1e-12) and std.n == 5
    expected = _percentile(sd, draws, 5, 2, (0.0, math.inf))
    assert (std.low, std.high) == (pytest.approx(expected.low, rel=1e-9),
                                   pytest.approx(expected.high, rel=1e-9))
    assert std.low == 0.0 and _percentile(sd, draws, 5, 2).low < 0.0  # the cut at 0 bites
    assert out["edge_std_own"]["left"].low == 0.0
    bias = out["edge_bias"]["left"]
    assert bias.value == pytest.approx(rel.mean(), rel=1e-12)
    assert bias.high == pytest.approx(_percentile(rel.mean(), means, 5, 2).high, rel=1e-9)
    top = out["edge_std"]["top"]  # one person's rows only: no spread to resample
    assert top.n == 4 and (top.low, top.high) == (0.0, math.inf)
    # pooled over the four edges, each about its own bias: 5 + 3 x 4 rows of two people
    centred = np.r_[rel - rel.mean(), np.tile(rel[:4] - rel[:4].mean(), 3)]
    who = np.r_[cluster, np.tile(cluster[:4], 3)]
    k = np.zeros((3, 3))
    for j, v in enumerate((np.ones_like(centred), centred, centred * centred)):
        np.add.at(k[:, j], who, v)
    sd = math.sqrt(k[:, 2].sum() / 16)  # centred values: the sum of squares over 17 - 1
    _, draws, _ = _std_and_draws(centred, who, 3, weights)
    noise = out["edge_noise"]
    assert noise.value == pytest.approx(sd, rel=1e-9) and noise.n == 17 and noise.low == 0.0
    assert noise.high == pytest.approx(_percentile(sd, draws, 17, 2).high, rel=1e-9)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_rate_and_proportion_design_effects_by_hand():
    """The design effect deff = max(1, bootstrap variance / the Poisson or binomial one) times
    the inflation of the number of clusters squared; the effective count is the count over
    deff. One bootstrap draw has no variance (0, not a warning); one block of frames bounds
    nothing above."""
    grow = _inflation(2) ** 2
    # rate, 30 events in 30 frames over two blocks of 15: r = 1, Poisson variance 1 / 30
    counts, blocks = np.array([[0], [30]]), np.array([15.0, 15.0])
    one_draw = rate(counts, 30.0, np.array([[1, 1]]), blocks)[0]
    assert one_draw.value == 1.0 and one_draw.n == 30
    assert one_draw.effective == pytest.approx(30 / grow, rel=1e-12)
    # two draws, each one block twice: rates 0 and 2, variance 2, deff 60 grow
    two = rate(counts, 30.0, np.array([[2, 0], [0, 2]]), blocks)[0]
    assert two.effective == pytest.approx(30 / (60 * grow), rel=1e-12)
    assert rate(np.array([[5]]), 10.0, np.ones((4, 1)), np.array([10.0])) == [
        Estimate(0.5, 0.0, math.inf, 5, 0.0)]
    # proportion, 3 clusters: hits 2, 2, 3 of 2, 4, 6 (p = 7 / 12)
    hits, totals = np.array([[2], [2], [3]]), np.array([[2], [4], [6]])
    binomial = (7 / 12) * (5 / 12) / 12
    grow3 = _inflation(3) ** 2
    one = proportion(hits, totals, np.array([[1, 1, 1]]))[0]
    assert one.value == pytest.approx(7 / 12, rel=1e-12) and one.n == 12
    assert one.effective == pytest.approx(12 / grow3, rel=1e-12)
    # two draws: clusters 1 and 2 three times each, proportions 1 and 1/2, variance 1/8
    two = proportion(hits, totals, np.array([[3, 0, 0], [0, 3, 0]]))[0]
    assert two.effective == pytest.approx(12 / (0.125 / binomial * grow3), rel=1e-12)
    # clusters of one row each, drawn singly: proportions 1, 0, 1 (variance 1/3)
    single = proportion(np.array([[1], [0], [1]]), np.ones((3, 1), int), np.eye(3))[0]
    binomial = (2 / 3) * (1 / 3) / 3
    assert single.effective == pytest.approx(3 / (1 / 3 / binomial * grow3), rel=1e-12)


def test_binning_sizes_and_score_centres():
    # below the first edge: the first bin; at or above the last: the last
    assert _bins(np.array([-3.0, 0.0, 0.2, 0.5, 0.999, 1.0, 5.0]), SCORE_BINS).tolist() == [
        0, 0, 0, 1, 4, 4, 4]
    # log-size ranges: the 1st-99th percentile span of log w and of log h (at least 0.1 each);
    # boxes without a positive width and height are left out; under two boxes: 1
    e = math.e
    assert _size_area(np.array([1.0, e]), np.array([1.0, e ** 2])) == pytest.approx(
        0.98 * 1.96, rel=1e-12)
    assert _size_area(np.array([0.5, 0.5 * e, 0.0, 3.0]), np.array([1.0, e, 4.0, 0.0])) == \
        pytest.approx(0.98 * 0.98, rel=1e-12)
    assert _size_area(np.array([5.0, 0.0]), np.array([5.0, 5.0])) == 1.0
    assert _size_area(np.array([5.0, 5.0, 5.0]), np.array([5.0, 5.0, 5.0])) == \
        pytest.approx(0.01, rel=1e-12)
    # the geometric mean of the scores of hits and false detections in a bin (not of those
    # set aside), the bin's midpoint where it has none
    got = _score_centres(np.array([1, 1, 1, 2]), np.array([0, 1, -1, 1]),
                         np.array([0.6, 0.8, 0.7, 0.95]))
    assert got.tolist() == pytest.approx([0.25, math.sqrt(0.48), 0.95, 0.9945, 0.9995],
                                         rel=1e-12)
    none = _recently_detected(np.zeros(0, int), np.zeros(0, int), np.zeros(0, bool), 3)
    assert none.dtype == bool and none.shape == (0,)


def test_thresholds_at_equality_and_missing_visibility():
    """Visibility exactly 0.75 is visible (its pairs count for the memory), exactly 0.5 counts
    for the edge noise, exactly 0 is a visibility (not a missing column); an edge exactly
    BORDER px from the image border is left out."""
    frames, people = 40, 4
    keep = np.tile((np.arange(frames) // 10 % 2 == 0)[:, None], (1, people))
    gt, det = _static_people(people, frames, keep)
    vis = np.select([gt.id == 1, gt.id == 2, gt.id == 3], [0.75, 0.5, 0.0], 1.0)
    gt = MotTable(gt.frame, gt.id, gt.box, gt.score, gt.cls, vis)
    cal = calibrate([Labelled("EQ", gt, det, SIZE, 30.0, frames)])
    assert cal.notes == []
    assert [e.n for _, _, e in cal.by_visibility] == [40, 0, 40, 80]
    assert cal.detectability.n == 80 and cal.detectability.value == 0.5
    assert cal.memory_visible.n == 2 * (frames - 1)
    assert cal.edge_std["left"].n == 60  # people 1, 2 and 4, detected in 20 frames each
    # a box edge exactly BORDER px from the border
    at_border = MotTable(gt.frame, gt.id, np.c_[np.full(len(gt.frame), 2.0), gt.box[:, 1:]],
                         gt.score, gt.cls, np.ones(len(gt.frame)))
    cal = calibrate([Labelled("B", at_border, _detected(at_border, keep), SIZE, 30.0, frames)])
    assert cal.edge_std["left"].n == 0 and cal.edge_std["top"].n == 80
    right = at_border.box[:, 0] + at_border.box[:, 2]
    shifted = MotTable(at_border.frame, at_border.id,
                       np.c_[SIZE[0] - 2.0 - at_border.box[:, 2], at_border.box[:, 1:]],
                       at_border.score, at_border.cls, at_border.visibility)
    assert np.all(right > 0)
    cal = calibrate([Labelled("R", shifted, _detected(shifted, keep), SIZE, 30.0, frames)])
    assert cal.edge_std["right"].n == 0 and cal.edge_std["left"].n == 80


def test_at_one_frame_a_second_the_tracker_holds_a_person_for_one_frame():
    """At 1 fps the horizon (0.67 s) rounds to 1 frame: of each run of 60 hits and 60 misses,
    the 59 hits after a hit and the first miss are the tracked rows."""
    frames, people = 480, 3
    keep = np.tile((np.arange(frames) // 60 % 2 == 0)[:, None], (1, people))
    gt, det = _static_people(people, frames, keep)
    cal = calibrate([Labelled("SLOW", gt, det, SIZE, 1.0, frames)])
    assert cal.detection_tracked.value == pytest.approx(59 / 60, rel=1e-12)


def test_default_seed_is_zero_and_a_lone_false_detection_has_a_positive_lower_bound():
    frames, people = 60, 3
    keep = np.random.default_rng(2).random((frames, people)) < 0.8
    gt, det = _static_people(people, frames, keep)
    false = MotTable(np.array([7]), np.array([-1]), np.array([[1500.0, 500.0, 40.0, 90.0]]),
                     np.array([0.7]), np.array([-1]), np.array([-1.0]))
    det = MotTable(*(np.concatenate([getattr(det, k), getattr(false, k)]) for k in
                     ("frame", "id", "box", "score", "cls", "visibility")))
    labelled = [Labelled("F", gt, det, SIZE, 30.0, frames)]
    rate_ = calibrate(labelled).false_per_frame
    assert (rate_.n, rate_.value) == (1, 1 / 60) and 0 < rate_.low < rate_.value
    gt = scene(5, frames=60, cols=4, rows=2)
    det = simulate_detections(gt, 5, CONFIG, image_size=SIZE, num_frames=60)
    labelled = [Labelled("S", gt, det, SIZE, 30.0, 60)]
    a, b, c = calibrate(labelled), calibrate(labelled, seed=0), calibrate(labelled, seed=1)
    same = [np.array_equal(x, y, equal_nan=True) for x, y in zip(_numbers(a), _numbers(b),
                                                                strict=True)]
    other = [np.array_equal(x, y, equal_nan=True) for x, y in zip(_numbers(a), _numbers(c),
                                                                 strict=True)]
    assert all(same) and not all(other)
