"""Camera motion between two frames, estimated from the detections alone.

A hand-held or carried camera moves every box in the image by about the same shift, while the
people move by their own small amounts. Two consecutive frames' detections give the shift:

1. candidate shifts: the centre displacement c_j - p_i of every pair of boxes (previous i,
   current j) of similar height (ratio within `height_ratio`) that moved less than one box
   height;
2. the mode: the candidate with the most others within `mode_radius` box heights of it (the
   people who stood still or moved alike vote together, and a crowd walking one way does not
   outvote the background when the camera is still: a still camera gives a mode near 0);
3. refinement: the previous boxes moved by the mode are matched to the current ones (mutual
   best IoU above `min_iou`) and the median of those pairs' displacements is the estimate.

Under `min_pairs` matched pairs there is no estimate (None) and the tracker assumes a still
camera for that frame. A uniform scale is not estimated: measured on MOT17-11, a similarity
fit (also RANSAC, LMedS) is biased by the people's own motion and tracks worse (DESIGN 2.2).
Written here because no maintained library estimates image motion from boxes alone (OpenCV's
estimators need image features).
"""

from __future__ import annotations

import numpy as np


def _centres(boxes: np.ndarray) -> np.ndarray:
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.clip(hi - lo, 0.0, None).prod(axis=-1)
    union = a[:, None, 2:].prod(axis=-1) + b[None, :, 2:].prod(axis=-1) - inter
    return inter / np.maximum(union, 1e-12)


def estimate_shift(previous: np.ndarray, current: np.ndarray, height_ratio: float = 1.25,
                   mode_radius: float = 0.05, min_iou: float = 0.5,
                   min_pairs: int = 3) -> np.ndarray | None:
    """The image translation (dx, dy) in px from the boxes of the previous frame to the
    current one, both (N, 4) left, top, width, height; None when too few boxes pair up."""
    if len(previous) < min_pairs or len(current) < min_pairs:
        return None
    hp, hc = previous[:, 3], current[:, 3]
    scale = np.sqrt(hp[:, None] * hc[None, :])
    ratio = hc[None, :] / np.maximum(hp[:, None], 1e-9)
    shift = _centres(current)[None, :, :] - _centres(previous)[:, None, :]
    near = (ratio < height_ratio) & (ratio > 1.0 / height_ratio) & (
        np.abs(shift).max(axis=-1) < scale)
    if near.sum() < min_pairs:
        return None
    candidates = shift[near]
    unit = scale[near]
    gap = np.abs(candidates[:, None, :] - candidates[None, :, :]).max(axis=-1)
    votes = (gap < mode_radius * np.minimum(unit[:, None], unit[None, :])).sum(axis=1)
    # ties go to the smallest shift, then the lowest (dx, dy): the order of the boxes is no
    # information
    top = np.flatnonzero(votes == votes.max())
    tied = candidates[top]
    mode = tied[np.lexsort((tied[:, 1], tied[:, 0], np.abs(tied).sum(axis=1)))[0]]
    moved = previous.copy()
    moved[:, :2] += mode
    iou = _iou(moved, current)
    best_cur = iou.argmax(axis=1)
    best_prev = iou.argmax(axis=0)
    mutual = (best_prev[best_cur] == np.arange(len(previous))) & (
        iou[np.arange(len(previous)), best_cur] > min_iou)
    if mutual.sum() < min_pairs:
        return None
    i = np.flatnonzero(mutual)
    return np.median(shift[i, best_cur[i]], axis=0)
