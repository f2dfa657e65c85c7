"""The confidence in a world drawn from the tracker's own model: where its exact form holds.

    python benchmarks/calibration_model_world.py [--seeds 6] [--frames 150]

Each seed draws a world from the tracker's own model (`occtrack.scenarios.model_world`: 8
people moving as the filter's motion model says, seen with probability 0.9, each edge off by
the default edge noise, Poisson(1) false boxes a frame; 3840 x 2160 at 30 fps). Tracked with
`occlusion = "none"` under both `confidence_centre` forms. A reported box is right when it is
matched one to one (most pairs) to a true box at IoU >= 0.5. Printed per form: boxes, mean
confidence, share right, its z-score (the gap over the standard error sqrt(sum c (1 - c)) / N)
and the ECE of the boxes of all seeds; the same for the overlap part alone (confidence over
existence) of the detected boxes against the person behind their detection; and the
reliability table.

The exact form ("posterior", the default: the posterior box about its mean) is the nearer one
here, where the noise settings are the world's (about .01 too unsure: the filter's
approximations); "detection" (the posterior's spread about the detection) leaves out how far
the detection lies from the posterior and is too sure.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack import Tracker, TrackerConfig
from occtrack.metrics.reliability import reliability_table
from occtrack.scenarios.model_world import iou_with, model_world


def run(seed: int, centre: str, frames: int) -> tuple[np.ndarray, ...]:
    """(confidence, right) of every reported box of one seed's world, and (overlap
    probability, right) of the detected boxes against the person behind their detection."""
    config = TrackerConfig(occlusion="none", image_size=(3840.0, 2160.0), fps=30.0,
                           camera_motion="none", confidence_centre=centre)
    tracker = Tracker(config)
    confidence, right, overlap, own = [], [], [], []
    for frame in model_world(config, frames=frames, seed=seed):
        tracks = tracker.step(frame.detections)
        iou = np.array([[iou_with(b, t) for t in frame.truth] for b in tracks.boxes])
        hit = np.zeros(len(tracks), bool)
        good = iou >= 0.5 if len(tracks) else np.zeros((0, len(frame.truth)), bool)
        if good.any():
            person, box = linear_sum_assignment(good.T, maximize=True)
            hit[box[good.T[person, box]]] = True
        confidence.append(tracks.confidence)
        right.append(hit)
        for i in np.flatnonzero(tracks.detection_index >= 0):
            who = frame.person[tracks.detection_index[i]]
            if who >= 0:
                overlap.append(tracks.confidence[i] / tracks.existence[i])
                own.append(iou[i, who] >= 0.5)
    return (np.concatenate(confidence), np.concatenate(right), np.array(overlap),
            np.array(own, bool))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--frames", type=int, default=150)
    args = parser.parse_args()
    for centre in ("posterior", "detection"):
        runs = [run(seed, centre, args.frames) for seed in range(args.seeds)]
        c, ok, p, own = (np.concatenate([r[i] for r in runs]) for i in range(4))
        table = reliability_table(c, ok)
        error = np.sqrt((c * (1.0 - c)).sum()) / len(c)
        p_error = np.sqrt((p * (1.0 - p)).sum()) / len(p)
        print(f"confidence_centre = {centre!r}: {len(c)} boxes, confidence {c.mean():.3f}, "
              f"right {ok.mean():.3f} (z {(c.mean() - ok.mean()) / error:+.1f}), "
              f"ECE {table.ece:.3f}; detected boxes against their own person: {len(p)}, "
              f"P(IoU >= 0.5) {p.mean():.3f}, right {own.mean():.3f} "
              f"(z {(p.mean() - own.mean()) / p_error:+.1f})")
        for b in range(len(table.boxes)):
            if table.boxes[b]:
                print(f"  [{table.edges[b]:.1f}, {table.edges[b + 1]:.1f})  {table.boxes[b]:5d} "
                      f"boxes  confidence {table.confidence[b]:.3f}  right {table.right[b]:.3f}")


if __name__ == "__main__":
    main()
