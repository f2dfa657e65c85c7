"""What occtrack learns while it tracks, per sequence, beside the same quantity measured on the
ground truth (issue 37: the online-learnt values against the truth).

    python benchmarks/learnt_models.py ../shared/data/mot17 ../shared/data/mot17-yolox \
        ../shared/data/kitti

Each sequence (a MOTChallenge folder of sequence folders, or a KITTI folder with its RRC
detections) is tracked with the default settings (object-wise occlusion). Printed per sequence:

- size noise: the half-size process noise the tracker learnt (`SizeNoiseLearner`, floored
  at the configured 0.044 box heights per square-root second), and the same two-lag estimate
  run on the ground truth's own boxes (consecutive frames of each true object, both edges of
  an axis inside the image), raw (no floor, no prior) and floored;
- score model: the learnt log-odds of clutter per score bin relative to the top bin
  (`ScoreLearner.log_ratio`), and the truth's: the detections matched one to one to a true
  object at IoU >= 0.5 are objects, the others clutter, the same log-odds per bin (bins with
  fewer than 20 detections shown as '.'); and the prior's, score^-2;
- occludability: the stationary value the tracker learnt (`OccludabilityLearner`, prior
  0.8), and the truth's, 1 - P(hit | hidden) / P(hit | visible), a true object hit when a
  detection matches it one to one at IoU >= 0.5: hidden is under a fifth visible by MOT17's
  visibility column (visible: at least nine tenths), on KITTI occlusion level 2, largely
  occluded (visible: level 0).

The estimators are the tracker's own, so the comparison says how well the filter's association
probabilities stand in for labels.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from occtrack.experiments import benchmark as mot_benchmark
from occtrack.experiments import benchmark_kitti
from occtrack.io.mot import MotTable
from occtrack.models.calibration import match
from occtrack.models.motion import SizeNoiseLearner
from occtrack.models.score_model import ScoreLearner
from occtrack.tracker import Tracker, TrackerConfig


def sequences(root: Path):
    """(name, detections MotTable, truth MotTable (targets only), width, height, fps, length,
    classes) of every sequence under `root`."""
    if benchmark_kitti.is_layout(root):
        detections = benchmark_kitti.pick_detections(root, None)
        for name in benchmark_kitti.sequence_names(root, detections):
            seq = benchmark_kitti.load_sequence(root, detections, name)
            gt = seq.gt
            keep = (gt.id >= 0) & (gt.type != 8)  # every labelled object but DontCare
            box = gt.box[keep]
            # KITTI's occlusion levels 0, 1, 2 (fully visible, partly, largely occluded) as a
            # visibility 1, .5, 0; level 3 (unknown) as MOT17's -1, absent
            level = gt.occluded[keep]
            visibility = np.where(level <= 2, 1.0 - level / 2.0, -1.0)
            truth = MotTable(gt.frame[keep] + 1, gt.id[keep] * 16 + gt.type[keep],
                             np.concatenate([box[:, :2], box[:, 2:] - box[:, :2]], axis=1),
                             np.ones(keep.sum()), np.full(keep.sum(), -1), visibility)
            yield (f"kitti {name}", seq.det, truth, seq.width, seq.height, seq.fps, seq.length,
                   True)
        return
    for folder in mot_benchmark.find_sequences(root):
        seq = mot_benchmark.load_sequence(folder)
        target = (seq.gt.cls == 1) & (seq.gt.score != 0)
        yield (seq.name, seq.det, seq.gt.select(target), seq.width, seq.height, seq.fps,
               seq.length, False)


def truth_size_noise(truth: MotTable, width: float, height: float, fps: float) -> float:
    """The two-lag estimate on the true boxes (raw: no prior, no floor)."""
    learner = SizeNoiseLearner(prior=0.0, memory=10**7, prior_weight=1)
    dt = 1.0 / fps
    for lag in (1, learner.lag):
        diffs = []
        for ident in np.unique(truth.id):
            rows = np.flatnonzero(truth.id == ident)
            rows = rows[np.argsort(truth.frame[rows])]
            frame = truth.frame[rows]
            l, t, w, h = truth.box[rows].T
            inside = np.stack([(l > 1) & (l + w < width - 1), (t > 1) & (t + h < height - 1)],
                              axis=1)
            index = {f: i for i, f in enumerate(frame)}
            for i, f in enumerate(frame):
                j = index.get(f + lag)
                if j is None:
                    continue
                both = inside[i] & inside[j]
                change = (np.array([w[j] - w[i], h[j] - h[i]]) / 2.0) / ((h[i] + h[j]) / 2.0)
                diffs.extend(change[both])
        learner.add(lag, np.array(diffs))
    n, v1, vl = (min(learner._count[1], learner._count[learner.lag]),
                 *(float(np.median(np.square(learner._diffs[k][:learner._count[k]])))
                   / learner.CHI2_MEDIAN for k in (1, learner.lag)))
    return float(np.sqrt(max(vl - v1, 0.0) / ((learner.lag - 1) * dt))) if n > 1 else 0.0


def truth_log_odds(det: MotTable, truth: MotTable, length: int, bins: int) -> np.ndarray:
    """Per score bin, log(clutter / objects) relative to the top bin, from the truth (nan
    where a bin has fewer than 20 detections)."""
    matched = match(truth, det, length)
    is_object = matched.det_kind != 0
    b = np.minimum((np.clip(det.score, 0, 1) * bins).astype(int), bins - 1)
    objects = np.bincount(b, weights=is_object.astype(float), minlength=bins)
    clutter = np.bincount(b, weights=(~is_object).astype(float), minlength=bins)
    odds = np.log((clutter + 1e-3) / (objects + 1e-3))
    odds = odds - odds[-1]
    odds[objects + clutter < 20] = np.nan
    return odds


def truth_occludability(det: MotTable, truth: MotTable, length: int) -> float:
    """1 - P(hit | under a fifth visible) / P(hit | at least nine tenths visible) of the true
    objects (nan without both kinds)."""
    hit = match(truth, det, length).gt_match >= 0
    hidden = (truth.visibility >= 0) & (truth.visibility < 0.2)
    visible = truth.visibility >= 0.9
    if not hidden.any() or not visible.any() or not hit[visible].any():
        return float("nan")
    return float(1.0 - hit[hidden].mean() / hit[visible].mean())


def row(values: np.ndarray) -> str:
    return " ".join("    ." if not np.isfinite(v) else f"{v:5.1f}" for v in values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    args = parser.parse_args()
    prior = ScoreLearner()
    print("score bins: tenths of [0, 1]; log-odds of clutter relative to the top bin; prior "
          "(score^-2): " + row(prior.log_ratio()))
    for root in args.folders:
        for name, det, truth, w, h, fps, length, classes in sequences(root):
            config = TrackerConfig.from_dict({"image_size": (w, h), "fps": fps})
            tracker = Tracker(config)
            tracker.run(det, length, classes=classes)
            learnt = tracker.filter.size_noise
            raw = truth_size_noise(truth, w, h, fps)
            floored = max(raw, config.size_noise)
            print(f"\n{name}: size noise learnt {learnt:.3f}, truth {raw:.3f} (floored "
                  f"{floored:.3f}) h/sqrt(s)")
            print(f"  score log-odds learnt {row(tracker._scores.log_ratio())}")
            print(f"  score log-odds truth  {row(truth_log_odds(det, truth, length, 10))}")
            print(f"  occludability learnt {tracker.filter.occludability.stationary:.2f}, "
                  f"truth {truth_occludability(det, truth, length):.2f}")


if __name__ == "__main__":
    main()
