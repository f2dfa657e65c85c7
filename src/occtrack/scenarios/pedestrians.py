"""A synthetic street seen by an upright camera: pedestrians crossing behind each other.

People walk at constant velocity across the image, each at their own depth: a person whose
feet are lower in the image is nearer, taller and hides the people behind. The detector
imitates a Faster-RCNN with non-maximum suppression:

- each person, unless mostly hidden by nearer people (visible fraction below `min_visible`),
  is a candidate with a score that falls with occlusion, and is detected with `p_detect`;
- box edges get Gaussian noise in proportion to the box height;
- candidates are kept greedily by score, and one whose box is covered by more than
  `suppress_cover` of its area by a kept box is dropped (measurement-wise occlusion, paper
  section II);
- a few false positives (Poisson, `clutter_rate` per frame) of person-like size.

Everything random comes from one seeded numpy Generator, so a seed gives the same scene.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.io.mot import MotTable


@dataclass(frozen=True)
class Walker:
    """One pedestrian: appears at `first_frame` (0-based) with box centre x `x` and feet at
    `bottom`, moves (vx, vy) px per second, box height and width in px."""

    first_frame: int
    x: float
    bottom: float
    vx: float
    vy: float
    height: float
    width: float


@dataclass(frozen=True)
class Detector:
    p_detect: float = 0.9
    edge_noise: float = 0.02  # std of each edge, as a fraction of the box height
    min_visible: float = 0.3
    suppress_cover: float = 0.5
    clutter_rate: float = 0.2  # false positives per frame


@dataclass(frozen=True)
class Crowd:
    """Random walkers, `people` of them in view at any time (a new one enters at the left or
    right edge when one leaves)."""

    people: int = 12
    frames: int = 600
    image_size: tuple[float, float] = (1920.0, 1080.0)
    fps: float = 30.0
    horizon: float = 250.0  # image row of the horizon: heights shrink to 0 there
    height_per_px: float = 0.3  # box height per pixel of feet below the horizon
    nearest_bottom: float = 1060.0
    farthest_bottom: float = 500.0
    speed: tuple[float, float] = (0.5, 0.9)  # box heights per second
    detector: Detector = Detector()


@dataclass(frozen=True)
class Scene:
    """Ground truth and detections of a synthetic sequence, as MOTChallenge tables."""

    truth: MotTable
    detections: MotTable
    frames: int
    image_size: tuple[float, float]
    fps: float


def _box_size(bottom: np.ndarray, crowd: Crowd) -> tuple[np.ndarray, np.ndarray]:
    height = crowd.height_per_px * (bottom - crowd.horizon)
    return height, 0.4 * height


def crowd_walkers(crowd: Crowd, rng: np.random.Generator) -> list[Walker]:
    """Walkers for a crowd scene: `people` in view from the first frame to the last."""
    W, _ = crowd.image_size
    walkers = []
    for _slot in range(crowd.people):
        frame, first = 0, True
        while frame < crowd.frames:
            bottom = rng.uniform(crowd.farthest_bottom, crowd.nearest_bottom)
            height, width = _box_size(np.array(bottom), crowd)
            speed = rng.uniform(*crowd.speed) * height
            direction = rng.choice([-1.0, 1.0])
            vy = rng.normal(0.0, 0.05) * height
            if first:
                x = rng.uniform(0.0, W)
            else:
                x = -width / 2 if direction > 0 else W + width / 2
            walker = Walker(frame, float(x), float(bottom), float(direction * speed), float(vy),
                            float(height), float(width))
            walkers.append(walker)
            distance = (W + width / 2 - x) if direction > 0 else (x + width / 2)
            frame += max(1, int(np.ceil(distance / speed * crowd.fps)))
            first = False
    return walkers


def simulate(walkers: list[Walker], frames: int, image_size: tuple[float, float],
             fps: float, detector: Detector, rng: np.random.Generator) -> Scene:
    """Move the walkers, find who hides whom, and run the detector on every frame."""
    W, H = image_size
    n = len(walkers)
    first = np.array([w.first_frame for w in walkers], dtype=float)
    x0 = np.array([w.x for w in walkers])
    b0 = np.array([w.bottom for w in walkers])
    v = np.array([[w.vx, w.vy] for w in walkers]).reshape(n, 2)
    size = np.array([[w.width, w.height] for w in walkers]).reshape(n, 2)
    sizes_seen = size[:, 1] if n else np.array([100.0])
    truth_rows, det_rows = [], []
    for f in range(frames):
        t = (f - first) / fps
        cx = x0 + v[:, 0] * t
        bottom = b0 + v[:, 1] * t
        ltwh = np.stack([cx - size[:, 0] / 2, bottom - size[:, 1], size[:, 0], size[:, 1]], 1)
        inside = (t >= 0) & (ltwh[:, 0] + ltwh[:, 2] > 0) & (ltwh[:, 0] < W) & (
            ltwh[:, 1] < H) & (ltwh[:, 1] + ltwh[:, 3] > 0)
        ids = np.flatnonzero(inside)
        boxes = ltwh[ids]
        visible = _visible_fraction(boxes, (W, H))
        for i, k in enumerate(ids):
            truth_rows.append((f + 1, k + 1, *boxes[i], 1, 1, visible[i]))
        det_rows.extend((f + 1, -1, *box, s, -1, -1)
                        for box, s in _detect(boxes, visible, (W, H), detector, sizes_seen, rng))
    truth = _table(truth_rows, "synthetic truth")
    dets = _table(det_rows, "synthetic detections")
    return Scene(truth, dets, frames, (float(W), float(H)), float(fps))


def _visible_fraction(boxes: np.ndarray, image_size) -> np.ndarray:
    """Share of each box neither hidden by nearer boxes (lower bottom) nor outside the image."""
    if len(boxes) == 0:
        return np.zeros(0)
    W, H = image_size
    x0, y0 = boxes[:, 0], boxes[:, 1]
    x1, y1 = x0 + boxes[:, 2], y0 + boxes[:, 3]
    area = boxes[:, 2] * boxes[:, 3]
    iw = np.clip(np.minimum(x1[:, None], x1[None]) - np.maximum(x0[:, None], x0[None]), 0, None)
    ih = np.clip(np.minimum(y1[:, None], y1[None]) - np.maximum(y0[:, None], y0[None]), 0, None)
    cover = iw * ih / area[:, None]
    nearer = y1[None, :] > y1[:, None]
    cover = np.where(nearer, cover, 0.0)
    in_image = (np.clip(x1, 0, W) - np.clip(x0, 0, W)) * (np.clip(y1, 0, H) - np.clip(y0, 0, H))
    return np.prod(1.0 - np.clip(cover, 0, 1), axis=1) * in_image / area


def _detect(boxes, visible, image_size, det: Detector, sizes_seen, rng):
    W, H = image_size
    n = len(boxes)
    score = np.clip(0.45 + 0.5 * visible + rng.normal(0.0, 0.05, n), 0.05, 1.0)
    hit = (visible >= det.min_visible) & (rng.random(n) < det.p_detect)
    noise = rng.normal(0.0, 1.0, (n, 4)) * det.edge_noise * boxes[:, 3:4]
    edges = np.stack([boxes[:, 0], boxes[:, 1], boxes[:, 0] + boxes[:, 2],
                      boxes[:, 1] + boxes[:, 3]], 1) + noise
    n_false = rng.poisson(det.clutter_rate)
    if n_false:
        h = rng.choice(sizes_seen, n_false) * rng.uniform(0.8, 1.2, n_false)
        w = 0.4 * h
        x = rng.uniform(0, W - w)
        y = rng.uniform(0, H - h)
        edges = np.concatenate([edges, np.stack([x, y, x + w, y + h], 1)])
        score = np.concatenate([score, rng.uniform(0.3, 0.7, n_false)])
        hit = np.concatenate([hit, np.ones(n_false, dtype=bool)])
    edges[:, [0, 2]] = np.clip(edges[:, [0, 2]], 0, W)
    edges[:, [1, 3]] = np.clip(edges[:, [1, 3]], 0, H)
    ok = hit & (edges[:, 2] - edges[:, 0] >= 2) & (edges[:, 3] - edges[:, 1] >= 2)
    edges, score = edges[ok], score[ok]
    order = np.argsort(-score, kind="stable")
    kept = []
    for i in order:
        if kept:
            k = np.array(kept)
            iw = np.clip(np.minimum(edges[k, 2], edges[i, 2]) - np.maximum(edges[k, 0],
                                                                           edges[i, 0]), 0, None)
            ih = np.clip(np.minimum(edges[k, 3], edges[i, 3]) - np.maximum(edges[k, 1],
                                                                           edges[i, 1]), 0, None)
            area = (edges[i, 2] - edges[i, 0]) * (edges[i, 3] - edges[i, 1])
            if (iw * ih / area > det.suppress_cover).any():
                continue
        kept.append(i)
    kept.sort()
    for i in kept:
        e = edges[i]
        yield (e[0], e[1], e[2] - e[0], e[3] - e[1]), score[i]


def _table(rows: list[tuple], path: str) -> MotTable:
    arr = np.array(rows, dtype=float).reshape(-1, 9)
    return MotTable(frame=arr[:, 0].astype(np.int64), id=arr[:, 1].astype(np.int64),
                    box=arr[:, 2:6].copy(), score=arr[:, 6].copy(),
                    cls=arr[:, 7].astype(np.int64), visibility=arr[:, 8].copy(), path=path)


def crowd_scene(crowd: Crowd = Crowd(), seed: int = 0) -> Scene:
    """A crowd scene from its settings and a seed."""
    rng = np.random.default_rng(seed)
    walkers = crowd_walkers(crowd, rng)
    return simulate(walkers, crowd.frames, crowd.image_size, crowd.fps, crowd.detector, rng)


OCCLUDING = Detector(p_detect=0.9)
MISSED_AT_RANDOM = Detector(p_detect=0.9, min_visible=0.0, suppress_cover=1.0)  # hidden or not


def dense_crowd(people: int, frames: int = 300, fps: float = 30.0,
                detector: Detector = OCCLUDING) -> Crowd:
    """Issue 10's crowds (benchmarks/bench_vs_bytetrack.py): `people` walkers in a 1920 x 1080
    image, boxes 50 px tall at the far edge (feet at row 130) to 120 px at the near one (row
    1060), heights linear in the feet's row. With `OCCLUDING`, people more than 70 % hidden
    go undetected and covered boxes are suppressed; with `MISSED_AT_RANDOM`, each person is
    detected with P_D 0.9 whether hidden or not (the crowd the issue measured)."""
    far, near, short, tall = 130.0, 1060.0, 50.0, 120.0
    per_px = (tall - short) / (near - far)
    return Crowd(people=people, frames=frames, fps=fps, horizon=far - short / per_px,
                 height_per_px=per_px, farthest_bottom=far, nearest_bottom=near,
                 detector=detector)

def crossing_pair(seed: int = 0, frames: int = 300, fps: float = 30.0,
                  detector: Detector = Detector(p_detect=0.95, clutter_rate=0.0)) -> Scene:
    """Two people: A, farther away, walks right; B, nearer, walks left and passes in front
    of A, whose detections vanish behind B for about a second. Truth id 1 is A, 2 is B."""
    a = Walker(0, 700.0, 650.0, 50.0, 0.0, 150.0, 60.0)
    b = Walker(0, 1200.0, 700.0, -50.0, 0.0, 180.0, 90.0)
    rng = np.random.default_rng(seed)
    return simulate([a, b], frames, (1920.0, 1080.0), fps, detector, rng)
