"""The simulated Faster-RCNN-like detector: repeatability, NMS, bounds, score model, scoring."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import expit

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable, read_mot
from occtrack.metrics.gospa import iou
from occtrack.scenarios.detector import (
    DetectorConfig,
    _ar1_per_person,
    detection_recall_precision,
    greedy_nms,
    simulate_detections,
)

EXACT = dict(person_std=0.0, noise_std=0.0, edge_noise_x=0.0, edge_noise_y=0.0,
             false_positive_rate=0.0)


def table(frame, ids, box, flag=None, cls=None, vis=None) -> MotTable:
    n = len(frame)
    return MotTable(frame=np.asarray(frame, dtype=np.int64), id=np.asarray(ids, dtype=np.int64),
                    box=np.asarray(box, dtype=float).reshape(n, 4),
                    score=np.ones(n) if flag is None else np.asarray(flag, dtype=float),
                    cls=np.ones(n, dtype=np.int64) if cls is None else np.asarray(cls),
                    visibility=np.ones(n) if vis is None else np.asarray(vis, dtype=float))


def crowd(n_frames=40, n_people=30, seed=7) -> MotTable:
    """People walking on a 640x480 image, often overlapping, some partly outside it."""
    rng = np.random.default_rng(seed)
    start = rng.uniform([-40, 0], [620, 380], (n_people, 2))
    speed = rng.normal(0, 3, (n_people, 2))
    height = rng.uniform(40, 200, n_people)
    f, i = np.meshgrid(np.arange(1, n_frames + 1), np.arange(1, n_people + 1), indexing="ij")
    f, i = f.ravel(), i.ravel()
    xy = start[i - 1] + speed[i - 1] * f[:, None]
    h = height[i - 1]
    box = np.column_stack([xy, 0.41 * h, h])
    vis = rng.uniform(0, 1, len(f))
    cls = np.where(i % 10 == 0, 7, 1)
    return table(f, i, box, cls=cls, vis=vis)


def write_gt(path: Path, gt: MotTable) -> None:
    with open(path, "w") as fh:
        for k in range(len(gt)):
            l, t, w, h = gt.box[k]
            fh.write(f"{gt.frame[k]},{gt.id[k]},{l:.3f},{t:.3f},{w:.3f},{h:.3f},"
                     f"{gt.score[k]:g},{gt.cls[k]},{gt.visibility[k]:.5f}\n")


def test_cli_output_is_byte_identical_per_seed_and_differs_across_seeds(tmp_path, capsys):
    gt_file = tmp_path / "gt.txt"
    write_gt(gt_file, crowd())
    outs = [tmp_path / name for name in ("a.txt", "b.txt", "c.txt")]
    for out, seed in zip(outs, (3, 3, 4), strict=True):
        assert main(["simulate-detections", str(gt_file), "--seed", str(seed), "-o", str(out),
                     "--image-size", "640x480"]) == 0
    assert outs[0].read_bytes() == outs[1].read_bytes()
    assert outs[0].read_bytes() != outs[2].read_bytes()
    summary = capsys.readouterr().out.strip().splitlines()[-1]
    assert "recall" in summary and "precision" in summary


def test_same_detections_whatever_the_gt_row_order():
    gt = crowd()
    shuffled = gt.select(np.random.default_rng(1).permutation(len(gt)))
    a, b = simulate_detections(gt, 5, image_size=(640, 480)), \
        simulate_detections(shuffled, 5, image_size=(640, 480))
    assert np.array_equal(a.frame, b.frame) and np.array_equal(a.box, b.box)
    assert np.array_equal(a.score, b.score)


def test_cli_refuses_to_overwrite_and_rejects_unknown_settings(tmp_path, capsys):
    gt_file, out = tmp_path / "gt.txt", tmp_path / "det.txt"
    write_gt(gt_file, crowd(n_frames=3))
    out.write_text("keep me\n")
    assert main(["simulate-detections", str(gt_file), "-o", str(out)]) == 1
    assert "exists already" in capsys.readouterr().err
    assert out.read_text() == "keep me\n"
    assert main(["simulate-detections", str(gt_file), "-o", str(out), "--force",
                 "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    assert out.read_text() != "keep me\n"
    config = tmp_path / "det.toml"
    config.write_text("[detector]\nbias = 2.0\nbogus = 1\n")
    assert main(["simulate-detections", str(gt_file), "-o", str(out), "--force",
                 "--config", str(config)]) == 1
    assert "unknown detector setting(s) bogus" in capsys.readouterr().err
    config.write_text("nms_order = 'sideways'\n")
    assert main(["simulate-detections", str(gt_file), "-o", str(out), "--force",
                 "--config", str(config)]) == 1
    assert "nms_order" in capsys.readouterr().err


@pytest.mark.parametrize("order", ["score", "bottom"])
def test_kept_boxes_never_overlap_above_the_nms_threshold(order):
    config = DetectorConfig(nms_order=order, nms_iou=0.4, false_positive_rate=3.0)
    det = simulate_detections(crowd(), 11, config, image_size=(640, 480))
    assert len(det) > 100
    for rows in det.frame_slices():
        overlap = iou(det.box[rows], det.box[rows])
        np.fill_diagonal(overlap, 0.0)
        assert overlap.max(initial=0.0) <= 0.4


def reference_nms(box, score, threshold, order):
    """Plain sequential greedy NMS for one frame."""
    key = [(-s, i) for i, s in enumerate(score)] if order == "score" else \
        [(-(b[1] + b[3]), -s, i) for i, (b, s) in enumerate(zip(box, score, strict=True))]
    keep = []
    for *_, i in sorted(key):
        if all(iou(box[[i]], box[[j]])[0, 0] <= threshold for j in keep):
            keep.append(i)
    return sorted(keep)


@pytest.mark.parametrize("order", ["score", "bottom"])
def test_greedy_nms_equals_sequential_reference(order):
    rng = np.random.default_rng(0)
    n = 300
    frame = rng.integers(1, 12, n)
    box = np.column_stack([rng.uniform(0, 100, (n, 2)), rng.uniform(10, 40, (n, 2))])
    score = rng.uniform(0, 1, n)
    keep = greedy_nms(frame, box, score, 0.3, order)
    for f in np.unique(frame):
        rows = np.flatnonzero(frame == f)
        expected = rows[reference_nms(box[rows], score[rows], 0.3, order)]
        assert np.array_equal(np.flatnonzero(keep & (frame == f)), expected)


def test_scores_in_unit_interval_and_boxes_inside_the_image():
    config = DetectorConfig(edge_noise_x=0.3, edge_noise_y=0.3, false_positive_rate=5.0,
                            score_threshold=0.2)
    det = simulate_detections(crowd(), 2, config, image_size=(640, 480))
    assert len(det) > 100
    assert np.all((det.score >= 0.2) & (det.score <= 1.0))
    l, t, w, h = det.box.T
    assert np.all((l >= 0) & (t >= 0) & (w >= config.min_size) & (h >= config.min_size))
    assert np.all((l + w <= 640 + 1e-9) & (t + h <= 480 + 1e-9))
    assert np.all(det.id == -1) and np.all(np.diff(det.frame) >= 0)


def test_score_follows_the_stated_logit_model_when_noise_is_off():
    config = DetectorConfig(**EXACT, score_threshold=0.0, candidate_threshold=0.0)
    vis = np.array([1.0, 0.8, 0.5, 0.3, 1.0])
    height = np.array([200.0, 200.0, 200.0, 200.0, 100.0 / math.e])
    box = np.column_stack([np.arange(5) * 300.0 + 10, np.full(5, 50.0), 0.4 * height, height])
    det = simulate_detections(table(np.ones(5), np.arange(1, 6), box, vis=vis), 0, config)
    logit = config.bias + config.visibility_weight * (vis - 1) \
        - config.height_weight * np.array([0, 0, 0, 0, 1.0])
    assert np.allclose(np.sort(det.score), np.sort(expit(logit)), rtol=0, atol=0.5e-4)
    assert np.allclose(np.sort(det.box[:, 0]), box[:, 0])


def test_per_person_difficulty_persists_over_frames():
    """With no frame noise, a person's score is the same in every frame."""
    config = DetectorConfig(**{**EXACT, "person_std": 1.0}, score_threshold=0.0,
                            candidate_threshold=0.0)
    frames = np.repeat(np.arange(1, 21), 3)
    ids = np.tile([1, 2, 3], 20)
    box = np.column_stack([ids * 300.0, np.full(60, 50.0), np.full(60, 80.0),
                           np.full(60, 200.0)])
    det = simulate_detections(table(frames, ids, box), 9, config)
    per_frame = det.score.reshape(20, 3)
    assert np.allclose(per_frame, per_frame[0])
    assert len(np.unique(per_frame[0].round(12))) == 3


def test_ar1_noise_has_unit_variance_the_stated_lag_correlation_and_no_carry_over():
    ids = np.repeat(np.arange(4000), 50)
    x = _ar1_per_person(ids, 8.0, np.random.default_rng(3)).reshape(4000, 50)
    a = math.exp(-1 / 8)
    n = x.size
    assert abs(x.var() - 1) < 5 * math.sqrt(2 / n) * (1 + a * a) / (1 - a * a)
    lag = np.mean(x[:, 1:] * x[:, :-1])
    assert abs(lag - a) < 0.02
    first = x[:, 0]
    assert abs(first.var() - 1) < 5 * math.sqrt(2 / 4000)
    carry = np.mean(x[1:, 0] * x[:-1, -1])
    assert abs(carry) < 5 / math.sqrt(4000)


def test_recall_and_precision_behave_as_designed():
    rng = np.random.default_rng(0)
    n_frames, n_people = 30, 8
    f = np.repeat(np.arange(1, n_frames + 1), n_people)
    i = np.tile(np.arange(1, n_people + 1), n_frames)
    box = np.column_stack([i * 200.0, np.full(len(f), 300.0), np.full(len(f), 80.0),
                           np.full(len(f), 200.0)])
    visible = table(f, i, box)
    exact = DetectorConfig(**EXACT)
    assert detection_recall_precision(visible, simulate_detections(visible, 1, exact)) == \
        (1.0, 1.0)
    hidden = table(f, i, box, vis=rng.uniform(0, 0.05, len(f)))
    clean = DetectorConfig(false_positive_rate=0.0)
    recall, precision = detection_recall_precision(hidden, simulate_detections(hidden, 1, clean))
    assert recall < 0.05
    noisy = DetectorConfig(**{**EXACT, "false_positive_rate": 20.0, "false_positive_logit": 3.0})
    recall, precision = detection_recall_precision(visible, simulate_detections(visible, 1, noisy))
    assert recall > 0.9 and precision < 0.6


def test_recall_precision_follows_trackeval_preprocessing():
    """Frame 1: a pedestrian, a static person (class 7), a flag-0 pedestrian and a car.
    Detections on the pedestrian and the static person, one on the flag-0 pedestrian, one
    half off the pedestrian of frame 2 (IoU 1/3), and one in empty space."""
    gt = table([1, 1, 1, 1, 2], [1, 2, 3, 4, 1],
               [[0, 0, 10, 20], [100, 0, 10, 20], [200, 0, 10, 20], [300, 0, 40, 20],
                [0, 0, 10, 20]],
               flag=[1, 0, 0, 0, 1], cls=[1, 7, 1, 3, 1])
    det = table([1, 1, 1, 1, 2], -np.ones(5),
                [[1, 0, 10, 20], [100, 1, 10, 20], [200, 0, 10, 20], [500, 500, 10, 20],
                 [5, 0, 10, 20]])
    recall, precision = detection_recall_precision(gt, det)
    assert recall == 1 / 2
    assert precision == 1 / 4


def test_recall_precision_needs_class_columns():
    gt = table([1], [1], [[0, 0, 10, 10]], cls=[-1])
    with pytest.raises(OcctrackError, match="class and consider-flag"):
        detection_recall_precision(gt, gt)


def test_bad_config_is_an_occtrack_error():
    with pytest.raises(OcctrackError, match="nms_iou"):
        DetectorConfig(nms_iou=0.0)
    with pytest.raises(OcctrackError, match="unknown detector setting"):
        DetectorConfig.from_dict({"nms": 0.5})
    with pytest.raises(OcctrackError, match="bias = 'high': expected float"):
        DetectorConfig.from_dict({"bias": "high"})
    assert DetectorConfig.from_dict({"bias": 3, "person_classes": [1, 7]}) == \
        DetectorConfig(bias=3.0, person_classes=(1, 7))


def test_calibrated_on_mot17_04(mot17_04_gt):
    gt = read_mot(mot17_04_gt, "gt")
    det = simulate_detections(gt, 0, image_size=(1920, 1080))
    recall, precision = detection_recall_precision(gt, det)
    assert 0.55 <= recall <= 0.65
    assert precision >= 0.93
