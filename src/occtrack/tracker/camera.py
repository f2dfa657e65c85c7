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

In a crowd every step above would compare all pairs of boxes and all pairs of candidates,
which grows with the fourth power of the people in view; `estimate_shift` instead looks only
at the pairs that can qualify (boxes within reach, candidates within the mode radius, boxes
that overlap: `occtrack.spatial`) and returns exactly the same estimate.
"""

from __future__ import annotations

import numpy as np

from occtrack.spatial import iou, overlapping_pairs

DENSE_PAIRS = 4096  # more box pairs than this: the sparse form (faster from here on)
DENSE_VOTES = 64  # more candidates than this: votes counted by a sweep, not a C x C table


def _centres(boxes: np.ndarray) -> np.ndarray:
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def _edges(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) left, top, width, height -> (N, 2, 2) edges."""
    return np.stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]], axis=-1)


def _median(values: np.ndarray) -> np.ndarray:
    """np.median(values, axis=0), the same numbers, without its overhead."""
    ordered = np.sort(values, axis=0)
    half = len(ordered) // 2
    if len(ordered) % 2:
        return ordered[half]
    return (ordered[half - 1] + ordered[half]) / 2.0


def _mode(candidates: np.ndarray, votes: np.ndarray) -> np.ndarray:
    """The candidate shift with the most votes; ties go to the smallest shift, then the lowest
    (dx, dy), so that the order of the boxes, which is no information, does not matter."""
    tied = candidates[votes == votes.max()]
    return tied[np.lexsort((tied[:, 1], tied[:, 0], np.abs(tied).sum(axis=1)))[0]]


def _first_best(group: np.ndarray, value: np.ndarray, other: np.ndarray,
                size: int) -> tuple[np.ndarray, np.ndarray]:
    """Per group g < size: the largest value and, among ties, the smallest `other`
    (argmax's choice); groups without pairs get value 0 and index 0, as argmax over a row of
    zeros gives."""
    best_value, best_index = np.zeros(size), np.zeros(size, dtype=np.int64)
    if len(group):
        order = np.lexsort((other, -value, group))
        first = np.ones(len(order), dtype=bool)
        first[1:] = group[order[1:]] != group[order[:-1]]
        winners = order[first]
        best_value[group[winners]] = value[winners]
        best_index[group[winners]] = other[winners]
    return best_value, best_index


def estimate_shift(previous: np.ndarray, current: np.ndarray, height_ratio: float = 1.25,
                   mode_radius: float = 0.05, min_iou: float = 0.5,
                   min_pairs: int = 3) -> np.ndarray | None:
    """The image translation (dx, dy) in px from the boxes of the previous frame to the
    current one, both (N, 4) left, top, width, height; None when too few boxes pair up."""
    if len(previous) < min_pairs or len(current) < min_pairs:
        return None
    if len(previous) * len(current) > DENSE_PAIRS:
        return _estimate_sparse(previous, current, height_ratio, mode_radius, min_iou,
                                min_pairs)
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
    if len(candidates) > DENSE_VOTES:
        votes = _votes(candidates, mode_radius * unit)
    else:
        gap = np.abs(candidates[:, None, :] - candidates[None, :, :]).max(axis=-1)
        votes = (gap < mode_radius * np.minimum(unit[:, None], unit[None, :])).sum(axis=1)
    mode = _mode(candidates, votes)
    moved = previous.copy()
    moved[:, :2] += mode
    overlap = iou(moved, current)
    best_cur = overlap.argmax(axis=1)
    best_prev = overlap.argmax(axis=0)
    mutual = (best_prev[best_cur] == np.arange(len(previous))) & (
        overlap[np.arange(len(previous)), best_cur] > min_iou)
    if mutual.sum() < min_pairs:
        return None
    i = np.flatnonzero(mutual)
    return _median(shift[i, best_cur[i]])


def _estimate_sparse(previous: np.ndarray, current: np.ndarray, height_ratio: float,
                     mode_radius: float, min_iou: float, min_pairs: int) -> np.ndarray | None:
    """`estimate_shift` on the pairs that can qualify only; the same result."""
    hp, hc = previous[:, 3], current[:, 3]
    cp, cc = _centres(previous), _centres(current)
    # a qualifying pair moved less than sqrt(hp hc) < sqrt(height_ratio) hp on each axis
    reach = np.sqrt(height_ratio) * hp * (1.0 + 1e-9) + 1e-9
    around = np.stack([cp - reach[:, None], cp + reach[:, None]], axis=-1)
    i, j = overlapping_pairs(around, np.stack([cc, cc], axis=-1))
    scale = np.sqrt(hp[i] * hc[j])
    ratio = hc[j] / np.maximum(hp[i], 1e-9)
    shift = cc[j] - cp[i]
    near = (ratio < height_ratio) & (ratio > 1.0 / height_ratio) & (
        np.abs(shift).max(axis=-1) < scale)
    if near.sum() < min_pairs:
        return None
    order = np.lexsort((j[near], i[near]))  # the dense form's order: by previous, then current
    candidates = shift[near][order]
    unit = scale[near][order]
    mode = _mode(candidates, _votes(candidates, mode_radius * unit))
    moved = previous.copy()
    moved[:, :2] += mode
    p, c = overlapping_pairs(_edges(moved), _edges(current))
    overlap = _iou_pairs(moved[p], current[c])
    best_iou, best_cur = _first_best(p, overlap, c, len(previous))
    _, best_prev = _first_best(c, overlap, p, len(current))
    mutual = (best_prev[best_cur] == np.arange(len(previous))) & (best_iou > min_iou)
    if mutual.sum() < min_pairs:
        return None
    k = np.flatnonzero(mutual)
    return _median(cc[best_cur[k]] - cp[k])


def _votes(points: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """For each point a, how many points b (itself included) lie closer than
    min(radius_a, radius_b) on both axes. Each pair is looked at once: points sorted along
    x, b after a within radius_a."""
    order = np.argsort(points[:, 0], kind="stable")
    x, y, r = points[order, 0], points[order, 1], radius[order]
    C = len(x)
    stop = np.searchsorted(x, x + r, side="left")
    counts = np.maximum(stop - np.arange(C) - 1, 0)
    total = int(counts.sum())
    a = np.repeat(np.arange(C), counts)
    b = np.arange(total) + np.repeat(np.arange(C) + 1 - (np.cumsum(counts) - counts), counts)
    limit = np.minimum(r[a], r[b])
    close = (np.abs(x[b] - x[a]) < limit) & (np.abs(y[b] - y[a]) < limit)
    votes = 1 + np.bincount(a[close], minlength=C) + np.bincount(b[close], minlength=C)
    out = np.empty(C, dtype=np.int64)
    out[order] = votes
    return out


def _iou_pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of aligned boxes a[k], b[k] (K, 4), as `occtrack.spatial.iou` computes it."""
    lo = np.maximum(a[:, :2], b[:, :2])
    hi = np.minimum(a[:, :2] + a[:, 2:], b[:, :2] + b[:, 2:])
    inter = np.clip(hi - lo, 0.0, None).prod(axis=-1)
    union = a[:, 2:].prod(axis=-1) + b[:, 2:].prod(axis=-1) - inter
    return inter / np.maximum(union, 1e-12)
