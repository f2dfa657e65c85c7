"""A world drawn from the box tracker's own model, for checking its probabilities.

People's boxes move as the filter's motion model says (`occtrack.models.motion`: nearly
constant velocity and size, the configured process noises in units of box height), each is
detected in a frame with probability `p_detect`, each detected edge off by the configured
`edge_noise` (box heights), and Poisson(`clutter`) false boxes a frame fall anywhere. Where the
world is the model, what the tracker says can be held to what happens: a confidence said to be
.9 must be right 90 % of the time (tests/test_confidence.py,
benchmarks/calibration_model_world.py). The image is large (3840 x 2160 by default) so that the
walkers stay inside it.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from occtrack.models.motion import ConstantVelocity
from occtrack.tracker import TrackerConfig


@dataclass(frozen=True)
class ModelFrame:
    """One frame: the true boxes (people, 4), the detections (M, 4), both left, top, width,
    height, and the person behind each detection (M,), -1 for a false box."""

    truth: np.ndarray
    detections: np.ndarray
    person: np.ndarray


def model_world(config: TrackerConfig, people: int = 8, frames: int = 150, seed: int = 0,
                p_detect: float = 0.9, clutter: float = 1.0) -> Iterator[ModelFrame]:
    """The frames of one seeded world under `config`'s motion and box noise (its image size
    and frame rate)."""
    rng = np.random.default_rng(seed)
    model = ConstantVelocity(1.0 / config.fps, config.position_noise, config.velocity_noise,
                             config.size_noise)
    root = np.linalg.cholesky(model.Q)
    W, H = config.image_size
    height = rng.uniform(150.0, 250.0, people)
    state = np.zeros((people, 2, 3))  # per axis (centre, velocity, half-size)
    state[:, 0, 0] = rng.uniform(0.25, 0.75, people) * W
    state[:, 1, 0] = rng.uniform(0.3, 0.7, people) * H
    state[:, 0, 2], state[:, 1, 2] = 0.2 * height, 0.5 * height
    for _ in range(frames):
        h = 2.0 * state[:, 1, 2]
        noise = rng.standard_normal((people, 2, 3)) @ root.T
        state = state @ model.F.T + noise * h[:, None, None]
        truth = np.c_[state[:, :, 0] - state[:, :, 2], 2.0 * state[:, :, 2]]
        seen = np.flatnonzero(rng.random(people) < p_detect)
        edges = np.c_[truth[seen, :2], truth[seen, :2] + truth[seen, 2:]]
        edges += rng.standard_normal(edges.shape) * config.edge_noise * truth[seen, 3:]
        boxes = np.c_[edges[:, :2], np.maximum(edges[:, 2:] - edges[:, :2], 1.0)]
        k = rng.poisson(clutter)
        fake_h = rng.uniform(80.0, 260.0, k)
        fake = np.c_[rng.uniform(0, W - 200, k), rng.uniform(0, H - 300, k), 0.4 * fake_h,
                     fake_h]
        yield ModelFrame(truth, np.r_[boxes, fake], np.r_[seen, np.full(k, -1)])


def iou_with(box: np.ndarray, truth: np.ndarray) -> float:
    """IoU of two left, top, width, height boxes."""
    lo = np.maximum(box[:2], truth[:2])
    hi = np.minimum(box[:2] + box[2:], truth[:2] + truth[2:])
    inter = float(np.prod(np.clip(hi - lo, 0.0, None)))
    return inter / (float(np.prod(box[2:])) + float(np.prod(truth[2:])) - inter)
