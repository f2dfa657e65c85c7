"""The confidence in a world drawn from the tracker's own model: where its exact form holds.

    python benchmarks/calibration_model_world.py [--seeds 6] [--frames 150]

Each seed draws 8 people whose boxes move as the filter's motion model says (nearly constant
velocity and size, the default process noises in units of box height,
`occtrack.models.motion`), seen on every frame with probability 0.9, each edge with the default
edge noise (0.069 box heights), plus Poisson(1) false boxes a frame anywhere; a 3840 x 2160
image at 30 fps keeps them inside. Tracked with `occlusion = "none"` under both
`confidence_centre` forms. A reported box is right when it is matched one to one (most pairs)
to a true box at IoU >= 0.5. Printed per form: boxes, mean confidence, share right, its z-score
(the gap over the standard error sqrt(sum c (1 - c)) / N) and the ECE of the boxes of all
seeds, and the reliability table.

The exact form ("posterior": the posterior box about its mean) is the calibrated one here,
where the noise settings are the world's; "detection" (the default, the posterior's spread
about the detection) leaves out how far the detection lies from the posterior and is too sure.
On the real MOT17 detections it is the other way round (README, "The confidence of a reported
box"): the settings are wider than the detector's errors.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack import Tracker, TrackerConfig
from occtrack.metrics.reliability import reliability_table
from occtrack.models.motion import ConstantVelocity

SIZE, FPS, PEOPLE = (3840.0, 2160.0), 30.0, 8


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.prod(np.clip(hi - lo, 0.0, None), axis=-1)
    return inter / (np.prod(a[:, None, 2:], -1) + np.prod(b[None, :, 2:], -1) - inter)


def run(seed: int, centre: str, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """(confidence, right) of every reported box of one seed's world."""
    rng = np.random.default_rng(seed)
    config = TrackerConfig(occlusion="none", image_size=SIZE, fps=FPS, camera_motion="none",
                           confidence_centre=centre)
    model = ConstantVelocity(1.0 / FPS, config.position_noise, config.velocity_noise,
                             config.size_noise)
    root = np.linalg.cholesky(model.Q)
    W, H = SIZE
    height = rng.uniform(150.0, 250.0, PEOPLE)
    state = np.zeros((PEOPLE, 2, 3))  # per axis (centre, velocity, half-size)
    state[:, 0, 0] = rng.uniform(0.25, 0.75, PEOPLE) * W
    state[:, 1, 0] = rng.uniform(0.3, 0.7, PEOPLE) * H
    state[:, 0, 2], state[:, 1, 2] = 0.2 * height, 0.5 * height
    tracker = Tracker(config)
    confidence, right = [], []
    for _ in range(frames):
        h = 2.0 * state[:, 1, 2]
        noise = rng.standard_normal((PEOPLE, 2, 3)) @ root.T
        state = state @ model.F.T + noise * h[:, None, None]
        truth = np.c_[state[:, :, 0] - state[:, :, 2], 2.0 * state[:, :, 2]]
        seen = truth[rng.random(PEOPLE) < 0.9]
        edges = np.c_[seen[:, :2], seen[:, :2] + seen[:, 2:]]
        edges += rng.standard_normal(edges.shape) * config.edge_noise * seen[:, 3:]
        boxes = np.c_[edges[:, :2], np.maximum(edges[:, 2:] - edges[:, :2], 1.0)]
        k = rng.poisson(1.0)
        fake_h = rng.uniform(80.0, 260.0, k)
        fake = np.c_[rng.uniform(0, W - 200, k), rng.uniform(0, H - 300, k), 0.4 * fake_h,
                     fake_h]
        tracks = tracker.step(np.r_[boxes, fake])
        hit = np.zeros(len(tracks), bool)
        good = _iou(tracks.boxes, truth) >= 0.5
        if good.any():
            person, box = linear_sum_assignment(good.T, maximize=True)
            hit[box[good.T[person, box]]] = True
        confidence.append(tracks.confidence)
        right.append(hit)
    return np.concatenate(confidence), np.concatenate(right)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--frames", type=int, default=150)
    args = parser.parse_args()
    for centre in ("posterior", "detection"):
        runs = [run(seed, centre, args.frames) for seed in range(args.seeds)]
        c = np.concatenate([r[0] for r in runs])
        ok = np.concatenate([r[1] for r in runs])
        error = np.sqrt((c * (1.0 - c)).sum()) / len(c)
        table = reliability_table(c, ok)
        print(f"confidence_centre = {centre!r}: {len(c)} boxes, confidence {c.mean():.3f}, "
              f"right {ok.mean():.3f} (z {(c.mean() - ok.mean()) / error:+.1f}), "
              f"ECE {table.ece:.3f}")
        for b in range(len(table.boxes)):
            if table.boxes[b]:
                print(f"  [{table.edges[b]:.1f}, {table.edges[b + 1]:.1f})  {table.boxes[b]:5d} "
                      f"boxes  confidence {table.confidence[b]:.3f}  right {table.right[b]:.3f}")


if __name__ == "__main__":
    main()
