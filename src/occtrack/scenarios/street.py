"""The demo's street (`occtrack demo`): people walking past each other, stopping, turning back
and waiting, seen by an upright camera and a detector measured on MOT17.

Geometry (a scene choice, as `scenarios.pedestrians.Crowd`): feet between rows 500 and 1060 of
a 1920 x 1080 image, box height 0.3 px per px of feet below the horizon at row 250 (75 to 243
px), width 0.4 of the height; a person whose feet are lower is nearer and hides the people
behind. Motion (`config.street.StreetMotion`, measured on MOT17-04's ground truth): a share of
the people stand the whole time; the others walk along the street at their own speed, stop at
a measured rate for an exponential time, and after a stop walk back with a measured
probability. When a person leaves the image another enters at an edge, so `people` are about
in view throughout.

The detector (`config.street.StreetDetector`, measured by `occtrack calibrate` on MOT17-04, -05
and -11): each person is detected with the probability measured for their visible share (so a
person hidden by more than half is almost never seen), with the measured memory from frame to
frame while they stay in view (visible share >= 0.75: where calibrate measures it); each edge
gets the measured bias and noise in box heights; scores follow the measured scores of detected
people; false boxes come at the measured rate per score bin, anywhere in the image,
person-shaped, of heights seen in the scene.

Everything random comes from one seeded numpy Generator: a seed gives the same scene.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.config.street import StreetDetector, StreetMotion
from occtrack.scenarios.pedestrians import Scene, _table


@dataclass(frozen=True)
class Street:
    people: int = 12
    frames: int = 1800
    image_size: tuple[float, float] = (1920.0, 1080.0)
    fps: float = 30.0
    horizon: float = 250.0
    height_per_px: float = 0.3
    nearest_bottom: float = 1060.0
    farthest_bottom: float = 500.0
    aspect: float = 0.4
    motion: StreetMotion = StreetMotion()
    detector: StreetDetector = StreetDetector()


@dataclass(frozen=True)
class StreetScene(Scene):
    """A street's truth and detections; `in_image` (one per truth row) is the share of the
    box inside the image, `hidden_by_others` the share covered by nearer people."""

    in_image: np.ndarray | None = None
    hidden_by_others: np.ndarray | None = None


def _walk(street: Street, rng: np.random.Generator):
    """Per frame, the boxes (left, top, width, height) of the people in view and their ids."""
    W, _ = street.image_size
    m, dt = street.motion, 1.0 / street.fps
    next_id = 1

    def newcomer(first: bool) -> dict:
        nonlocal next_id
        bottom = rng.uniform(street.farthest_bottom, street.nearest_bottom)
        height = street.height_per_px * (bottom - street.horizon)
        width = street.aspect * height
        standing = first and rng.random() < m.standing
        speed = m.walking_speed * np.exp(m.speed_spread * rng.standard_normal()) * height
        direction = 1.0 if rng.random() < 0.5 else -1.0
        if first:
            x = rng.uniform(0.0, W)
        else:
            x = -width / 2 if direction > 0 else W + width / 2
        person = dict(id=next_id, x=x, bottom=bottom, height=height, width=width,
                      speed=0.0 if standing else speed, direction=direction,
                      vy=rng.normal(0.0, m.drift) * speed, stopped=0.0, standing=standing)
        next_id += 1
        return person

    slots = [newcomer(True) for _ in range(street.people)]
    for _ in range(street.frames):
        boxes = np.array([(p["x"] - p["width"] / 2, p["bottom"] - p["height"], p["width"],
                           p["height"]) for p in slots]).reshape(-1, 4)
        yield boxes, np.array([p["id"] for p in slots], dtype=np.int64)
        for i, p in enumerate(slots):
            if p["standing"]:
                continue
            if p["stopped"] > 0:
                p["stopped"] -= dt
                if p["stopped"] <= 0 and rng.random() < m.turn_back:
                    p["direction"] = -p["direction"]
                continue
            if rng.random() < m.stop_rate * dt:
                p["stopped"] = rng.exponential(m.stop_mean)
                continue
            p["x"] += p["direction"] * p["speed"] * dt
            p["bottom"] = float(np.clip(p["bottom"] + p["vy"] * dt, street.farthest_bottom,
                                        street.nearest_bottom))
            gone = p["x"] + p["width"] / 2 < 0 if p["direction"] < 0 else \
                p["x"] - p["width"] / 2 > W
            if gone:
                slots[i] = newcomer(False)


def cover_by_nearer(boxes: np.ndarray) -> np.ndarray:
    """Share of each box (left, top, width, height) covered by nearer boxes (lower bottom
    edge), covers combined as independent: 1 - prod(1 - cover)."""
    if len(boxes) == 0:
        return np.zeros(0)
    x0, y0 = boxes[:, 0], boxes[:, 1]
    x1, y1 = x0 + boxes[:, 2], y0 + boxes[:, 3]
    iw = np.clip(np.minimum(x1[:, None], x1[None]) - np.maximum(x0[:, None], x0[None]), 0, None)
    ih = np.clip(np.minimum(y1[:, None], y1[None]) - np.maximum(y0[:, None], y0[None]), 0, None)
    cover = np.where(y1[None, :] > y1[:, None], iw * ih / (boxes[:, 2] * boxes[:, 3])[:, None],
                     0.0)
    return 1.0 - np.prod(1.0 - np.clip(cover, 0.0, 1.0), axis=1)


def _detect(boxes, visible, was_hit, det: StreetDetector, heights, image_size, rng):
    """One frame's detections (x0, y0, x1, y1 edges and scores) and who was detected."""
    W, H = image_size
    n = len(boxes)
    p = np.asarray(det.detect_by_visibility)[
        np.clip(np.searchsorted(det.visibility_bins, visible, side="right") - 1, 0,
                len(det.detect_by_visibility) - 1)]
    p_now = np.where(was_hit < 0, p, np.where(was_hit > 0, p + det.memory * (1 - p),
                                              p * (1 - det.memory)))
    hit = rng.random(n) < p_now
    edges = np.stack([boxes[:, 0], boxes[:, 1], boxes[:, 0] + boxes[:, 2],
                      boxes[:, 1] + boxes[:, 3]], 1)
    edges = edges + (np.asarray(det.edge_bias) + rng.standard_normal((n, 4))
                     * np.asarray(det.edge_std)) * boxes[:, 3:4]
    score = _scores(np.asarray(det.hit_scores), det.score_bins, n, rng)
    counts = rng.poisson(det.false_per_bin)
    m = int(counts.sum())
    lo, hi = np.log(heights.min()), np.log(heights.max())
    h = np.exp(rng.uniform(lo, hi, m))
    w = 0.4 * h
    x, y = rng.uniform(0, W - w), rng.uniform(0, H - h)
    bins = np.asarray(det.score_bins)
    which = np.repeat(np.arange(len(counts)), counts)
    false_score = rng.uniform(bins[which], bins[which + 1])
    edges = np.concatenate([edges[hit], np.stack([x, y, x + w, y + h], 1)])
    score = np.concatenate([score[hit], false_score])
    edges[:, [0, 2]] = np.clip(edges[:, [0, 2]], 0, W)
    edges[:, [1, 3]] = np.clip(edges[:, [1, 3]], 0, H)
    ok = (edges[:, 2] - edges[:, 0] >= 2) & (edges[:, 3] - edges[:, 1] >= 2)
    return edges[ok], np.round(score[ok], 4), hit


def _scores(weights: np.ndarray, bins, n: int, rng) -> np.ndarray:
    which = rng.choice(len(weights), n, p=weights / weights.sum())
    edges = np.asarray(bins)
    return rng.uniform(edges[which], edges[which + 1])


def street_scene(street: Street = Street(), seed: int = 0) -> StreetScene:
    """A street from its settings and a seed."""
    rng = np.random.default_rng(seed)
    W, H = street.image_size
    heights = street.height_per_px * (np.array([street.farthest_bottom,
                                                street.nearest_bottom]) - street.horizon)
    truth_rows, det_rows, shares, covers = [], [], [], []
    last_hit: dict[int, bool] = {}  # people in the top visibility bin last frame
    for f, (boxes, ids) in enumerate(_walk(street, rng), start=1):
        x0, y0 = boxes[:, 0], boxes[:, 1]
        x1, y1 = x0 + boxes[:, 2], y0 + boxes[:, 3]
        in_image = ((np.clip(x1, 0, W) - np.clip(x0, 0, W)) * (np.clip(y1, 0, H)
                    - np.clip(y0, 0, H)) / (boxes[:, 2] * boxes[:, 3]))
        seen = in_image > 0
        boxes, ids, in_image = boxes[seen], ids[seen], in_image[seen]
        cover = cover_by_nearer(boxes)
        visible = (1.0 - cover) * in_image
        top = visible >= street.detector.visibility_bins[-2]
        was = np.array([(1 if last_hit[i] else 0) if t and i in last_hit else -1
                        for i, t in zip(ids.tolist(), top, strict=True)])
        edges, scores, hit = _detect(boxes, visible, was, street.detector, heights,
                                     (W, H), rng)
        last_hit = {i: h for i, h, t in zip(ids.tolist(), hit.tolist(), top, strict=True) if t}
        truth_rows.extend((f, i, *b, 1, 1, v) for i, b, v in zip(ids, boxes, visible,
                                                                 strict=True))
        shares.append(in_image)
        covers.append(cover)
        order = np.argsort(-scores, kind="stable")
        det_rows.extend((f, -1, e[0], e[1], e[2] - e[0], e[3] - e[1], s, -1, -1)
                        for e, s in zip(edges[order], scores[order], strict=True))
    truth = _table(truth_rows, "street truth")
    dets = _table(det_rows, "street detections")
    return StreetScene(truth, dets, street.frames, (float(W), float(H)), float(street.fps),
                       np.concatenate(shares), np.concatenate(covers))
