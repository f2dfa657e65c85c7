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
camera for that frame. A uniform scale is not applied: measured on MOT17-11, a similarity
fit (also RANSAC, LMedS) is biased by the people's own motion and tracks worse (DESIGN 2.2).
What the one shift leaves out is measured instead, as an uncertainty: a camera walking
forward moves each point away from the image centre by k h (x - centre), h the box height
standing for inverse depth (`estimate_expansion`); the tracker widens a coasting box's
confidence by it.
Written here because no maintained library estimates image motion from boxes alone (OpenCV's
estimators need image features).

In a crowd every step above would compare all pairs of boxes and all pairs of candidates,
which grows with the fourth power of the people in view; `estimate_shift` instead looks only
at the pairs that can qualify (boxes within reach, candidates within the mode radius, boxes
that overlap: `occtrack.spatial`) and returns exactly the same estimate.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.jit import njit
from occtrack.spatial import overlapping_pairs

DENSE_PAIRS = 4096  # more box pairs than this: the sparse form (faster from here on)


def _centres(boxes: np.ndarray) -> np.ndarray:
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def _edges(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) left, top, width, height -> (N, 2, 2) edges."""
    return np.stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]], axis=-1)


@njit
def _first_best(group, value, other, size):
    """Per group g < size: the largest value and, among ties, the smallest `other`
    (argmax's choice); groups without pairs get value 0 and index 0, as argmax over a row of
    zeros gives."""
    best_value, best_index = np.zeros(size), np.zeros(size, dtype=np.int64)
    seen = np.zeros(size, dtype=np.bool_)
    for e in range(len(group)):
        g = group[e]
        if (not seen[g] or value[e] > best_value[g]
                or (value[e] == best_value[g] and other[e] < best_index[g])):
            seen[g] = True
            best_value[g], best_index[g] = value[e], other[e]
    return best_value, best_index


def estimate_shift(previous: np.ndarray, current: np.ndarray, height_ratio: float = 1.25,
                   mode_radius: float = 0.05, min_iou: float = 0.5,
                   min_pairs: int = 3) -> np.ndarray | None:
    """The image translation (dx, dy) in px from the boxes of the previous frame to the
    current one, both (N, 4) left, top, width, height; None when too few boxes pair up."""
    pairs = matched_shifts(previous, current, height_ratio, mode_radius, min_iou, min_pairs)
    return None if pairs is None else _median_rows(pairs)


def estimate_motion(previous: np.ndarray, current: np.ndarray,
                    **settings) -> tuple[np.ndarray, np.ndarray] | None:
    """`estimate_shift` and how well the detections pin it: (shift (2,), standard error (2,))
    in px, None when too few boxes pair up. The matched pairs' displacements are the camera's
    shift plus each person's own step; the median of P of them has the standard error
    sqrt(pi / 2) sigma / sqrt(P) (normal steps), sigma their spread by the median absolute
    deviation (1.4826 MAD), robust to the pairs that are no match."""
    matched = matched_pairs(previous, current, **settings)
    return None if matched is None else _shift_and_error(matched[0])


@njit
def _shift_and_error(pairs):
    """(median shift, its standard error) of the displacements (P, 2): `estimate_motion`."""
    shift = _median_rows(pairs)
    sigma = 1.4826 * _median_rows(np.abs(pairs - shift))
    return shift, math.sqrt(math.pi / 2.0) * sigma / math.sqrt(len(pairs))


def estimate_camera(previous: np.ndarray, current: np.ndarray, centre: np.ndarray,
                    height_ratio: float = 1.25, mode_radius: float = 0.05, min_iou: float = 0.5,
                    min_pairs: int = 3
                    ) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None] | None:
    """`estimate_motion` and `estimate_expansion` from one matching: (shift, its standard
    error, (k, its variance) or None); None when too few boxes pair up. (A frame small
    enough for every pair is one compiled call, `_camera_dense`.)"""
    if len(previous) < min_pairs or len(current) < min_pairs:
        return None
    if len(previous) * len(current) <= DENSE_PAIRS:
        found, shift, error, fitted, k, variance = _camera_dense(
            np.asarray(previous, dtype=float), np.asarray(current, dtype=float),
            np.asarray(centre, dtype=float), height_ratio, mode_radius, min_iou, min_pairs)
        if not found:
            return None
        return shift, error, ((k, variance) if fitted else None)
    matched = matched_pairs(previous, current, height_ratio, mode_radius, min_iou, min_pairs)
    if matched is None:
        return None
    return (*_shift_and_error(matched[0]),
            _expansion(*matched, previous, current, centre))


@njit
def _camera_dense(previous, current, centre, height_ratio, mode_radius, min_iou, min_pairs):
    """`estimate_camera` over every pair in one call: (found, shift, its standard error,
    whether k was fitted, k, its variance), the steps of `matched_pairs` (`_estimate_dense`),
    `_shift_and_error` and `_expansion_fit`."""
    found, pairs, which = _estimate_dense(previous, current, height_ratio, mode_radius,
                                          min_iou, min_pairs)
    if not found:
        return False, np.zeros(2), np.zeros(2), False, 0.0, 0.0
    shift, error = _shift_and_error(pairs)
    fitted, k, variance = _expansion_fit(pairs, which, previous, current, centre)
    return True, shift, error, fitted, k, variance


def estimate_expansion(previous: np.ndarray, current: np.ndarray, centre: np.ndarray,
                       **settings) -> tuple[float, float] | None:
    """What the one shift leaves out: a camera that moves forward or back moves each point
    away from (or toward) the focus of expansion, by (x - centre) Z'/Z, and a person's depth
    Z is inversely proportional to their box height h, so the displacement is k h (x - centre)
    with one k (per frame, 1 / px) for the whole scene. Fitted by least squares to the matched
    pairs' displacements, the shift as the intercept, centre the image's: (k, its variance);
    None when too few boxes pair up. Not applied to the boxes (as an estimate it is
    biased by the people's own steps, like a uniform scale): it says how far a prediction
    drifts that only follows the shift (`Tracker._camera_motion`)."""
    matched = matched_pairs(previous, current, **settings)
    return None if matched is None else _expansion(*matched, previous, current, centre)


def _expansion(pairs, which, previous, current, centre) -> tuple[float, float] | None:
    """`estimate_expansion` given the matched pairs (`matched_pairs`): least squares of the
    displacements on the levers h (x - centre) with the shift as each axis's intercept
    (`_expansion_fit`)."""
    found, k, variance = _expansion_fit(pairs, which, np.asarray(previous, dtype=float),
                                        np.asarray(current, dtype=float),
                                        np.asarray(centre, dtype=float))
    return (k, variance) if found else None


@njit
def _expansion_fit(pairs, which, previous, current, centre):
    """(found, k, its variance): with lever l = sqrt(h_prev h_cur) (previous centre - centre)
    and displacement d per pair and axis, both about their means over the pairs,
    k = sum(d l) / sum(l^2) and var k = sum((d - k l)^2) / (2 P - 3) / sum(l^2) (two intercepts
    and k); not found when the levers do not vary."""
    P = len(pairs)
    lever = np.empty((P, 2))
    mean_l, mean_d = np.zeros(2), np.zeros(2)
    for p in range(P):
        i, j = which[p, 0], which[p, 1]
        height = math.sqrt(previous[i, 3] * current[j, 3])
        for a in range(2):
            lever[p, a] = height * (previous[i, a] + previous[i, 2 + a] / 2.0 - centre[a])
            mean_l[a] += lever[p, a] / P
            mean_d[a] += pairs[p, a] / P
    norm, cross = 0.0, 0.0
    for p in range(P):
        for a in range(2):
            lever[p, a] -= mean_l[a]
            norm += lever[p, a] * lever[p, a]
            cross += (pairs[p, a] - mean_d[a]) * lever[p, a]
    if not norm > 0.0:
        return False, 0.0, 0.0
    k = cross / norm
    rss = 0.0
    for p in range(P):
        for a in range(2):
            e = pairs[p, a] - mean_d[a] - k * lever[p, a]
            rss += e * e
    return True, k, rss / max(2 * P - 3, 1) / norm


def matched_shifts(previous: np.ndarray, current: np.ndarray, height_ratio: float = 1.25,
                   mode_radius: float = 0.05, min_iou: float = 0.5,
                   min_pairs: int = 3) -> np.ndarray | None:
    """Steps 1-3 up to the median: the displacements (P, 2) of the box pairs matched after
    the mode, in the order of the previous boxes; None when fewer than `min_pairs`."""
    matched = matched_pairs(previous, current, height_ratio, mode_radius, min_iou, min_pairs)
    return None if matched is None else matched[0]


def matched_pairs(previous: np.ndarray, current: np.ndarray, height_ratio: float = 1.25,
                  mode_radius: float = 0.05, min_iou: float = 0.5,
                  min_pairs: int = 3) -> tuple[np.ndarray, np.ndarray] | None:
    """`matched_shifts` and which boxes each pair is: (displacements (P, 2), (previous,
    current) indices (P, 2)); None when fewer than `min_pairs`."""
    if len(previous) < min_pairs or len(current) < min_pairs:
        return None
    if len(previous) * len(current) > DENSE_PAIRS:
        return _estimate_sparse(previous, current, height_ratio, mode_radius, min_iou,
                                min_pairs)
    found, pairs, which = _estimate_dense(np.asarray(previous, dtype=float),
                                          np.asarray(current, dtype=float), height_ratio,
                                          mode_radius, min_iou, min_pairs)
    return (pairs, which) if found else None


@njit
def _qualifies(hp, hc, dx, dy, height_ratio):
    """Step 1's test of a pair: heights hp (previous) and hc (current) within height_ratio
    of each other, the centre moved by (dx, dy) less than sqrt(hp hc) on each axis."""
    ratio = hc / max(hp, 1e-9)
    return (ratio < height_ratio and ratio > 1.0 / height_ratio
            and max(abs(dx), abs(dy)) < math.sqrt(hp * hc))


@njit
def _iou(a, i, b, j):
    """IoU of boxes a[i] and b[j], left, top, width, height (0 for boxes without area)."""
    iw = max(min(a[i, 0] + a[i, 2], b[j, 0] + b[j, 2]) - max(a[i, 0], b[j, 0]), 0.0)
    ih = max(min(a[i, 1] + a[i, 3], b[j, 1] + b[j, 3]) - max(a[i, 1], b[j, 1]), 0.0)
    inter = iw * ih
    union = a[i, 2] * a[i, 3] + b[j, 2] * b[j, 3] - inter
    return inter / union if union > 0 else 0.0


@njit
def _estimate_dense(previous, current, height_ratio, mode_radius, min_iou, min_pairs):
    """Steps 1-3 over every pair of boxes: (found, the matched pairs' displacements, their
    (previous, current) box indices)."""
    N, M = len(previous), len(current)
    cp = previous[:, :2] + previous[:, 2:] / 2.0
    cc = current[:, :2] + current[:, 2:] / 2.0
    candidates, unit = np.empty((N * M, 2)), np.empty(N * M)
    C = 0
    for i in range(N):  # 1. candidates, in the order previous, then current
        for j in range(M):
            dx, dy = cc[j, 0] - cp[i, 0], cc[j, 1] - cp[i, 1]
            if _qualifies(previous[i, 3], current[j, 3], dx, dy, height_ratio):
                candidates[C, 0], candidates[C, 1] = dx, dy
                unit[C] = math.sqrt(previous[i, 3] * current[j, 3])
                C += 1
    if C < min_pairs:
        return False, np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64)
    mode = _mode_shift(candidates[:C], mode_radius * unit[:C])  # 2. the mode
    moved = previous.copy()  # 3. mutual best IoU after the mode, and the median
    moved[:, 0] += mode[0]
    moved[:, 1] += mode[1]
    overlap = np.zeros((N, M))
    for i in range(N):
        for j in range(M):
            overlap[i, j] = _iou(moved, i, current, j)
    best_prev = np.empty(M, dtype=np.int64)
    for j in range(M):
        best_prev[j] = np.argmax(overlap[:, j])
    pairs = np.empty((N, 2))
    which = np.empty((N, 2), dtype=np.int64)
    P = 0
    for i in range(N):
        j = np.argmax(overlap[i])
        if best_prev[j] == i and overlap[i, j] > min_iou:
            pairs[P, 0], pairs[P, 1] = cc[j, 0] - cp[i, 0], cc[j, 1] - cp[i, 1]
            which[P, 0], which[P, 1] = i, j
            P += 1
    if P < min_pairs:
        return False, np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64)
    return True, pairs[:P], which[:P]


def _estimate_sparse(previous: np.ndarray, current: np.ndarray, height_ratio: float,
                     mode_radius: float, min_iou: float,
                     min_pairs: int) -> tuple[np.ndarray, np.ndarray] | None:
    """`matched_pairs` on the pairs that can qualify only; the same result."""
    previous, current = np.asarray(previous, dtype=float), np.asarray(current, dtype=float)
    cp, cc = _centres(previous), _centres(current)
    candidates, unit = _candidates_within_reach(previous, current, cp, cc, height_ratio)
    if len(unit) < min_pairs:
        return None
    mode = _mode_shift(candidates, mode_radius * unit)
    moved = previous.copy()
    moved[:, :2] += mode
    p, c = overlapping_pairs(_edges(moved), _edges(current))
    shifts, which = _mutual_shifts(p, c, moved, current, cp, cc, min_iou)
    if len(shifts) < min_pairs:
        return None
    return shifts, which


def sparse_candidates(previous: np.ndarray, current: np.ndarray,
                      height_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Step 1 without testing every pair: the candidate shifts (C, 2) and their units (the
    geometric mean of the two heights), in the all-pairs order (by previous box, then
    current); boxes (N, 4) and (M, 4) left, top, width, height as floats."""
    return _candidates_within_reach(previous, current, _centres(previous), _centres(current),
                                    height_ratio)


def _candidates_within_reach(previous, current, cp, cc, height_ratio):
    """`sparse_candidates` given the boxes' centres cp and cc."""
    hp, hc = previous[:, 3], current[:, 3]
    # a qualifying pair moved less than sqrt(hp hc) < sqrt(height_ratio) hp on each axis
    reach = np.sqrt(height_ratio) * hp * (1.0 + 1e-9) + 1e-9
    around = np.stack([cp - reach[:, None], cp + reach[:, None]], axis=-1)
    i, j = overlapping_pairs(around, np.stack([cc, cc], axis=-1))
    return _candidates(i, j, hp, hc, cp, cc, height_ratio, len(current))


@njit
def _candidates(i, j, hp, hc, cp, cc, height_ratio, M):
    """Step 1 on the pairs (i, j) within reach: the candidate shifts and their units (box
    heights), in the dense form's order (by previous box, then current)."""
    keep = np.empty(len(i), dtype=np.int64)
    K = 0
    for e in range(len(i)):
        a, b = i[e], j[e]
        if _qualifies(hp[a], hc[b], cc[b, 0] - cp[a, 0], cc[b, 1] - cp[a, 1], height_ratio):
            keep[K] = e
            K += 1
    key = np.empty(K, dtype=np.int64)
    for t in range(K):
        key[t] = i[keep[t]] * M + j[keep[t]]
    order = np.argsort(key)
    candidates, unit = np.empty((K, 2)), np.empty(K)
    for t in range(K):
        e = keep[order[t]]
        a, b = i[e], j[e]
        candidates[t, 0], candidates[t, 1] = cc[b, 0] - cp[a, 0], cc[b, 1] - cp[a, 1]
        unit[t] = math.sqrt(hp[a] * hc[b])
    return candidates, unit


@njit
def _mutual_shifts(p, c, moved, current, cp, cc, min_iou):
    """Step 3 on the overlapping pairs (p, c) of moved previous and current boxes: the
    displacement of every pair that is each other's best IoU (ties: the lower index, as
    argmax), above min_iou, in the order of the previous boxes, and the pairs' (previous,
    current) indices."""
    E = len(p)
    overlap = np.empty(E)
    for e in range(E):
        overlap[e] = _iou(moved, p[e], current, c[e])
    N, M = len(moved), len(current)
    best_iou, best_cur = _first_best(p, overlap, c, N)
    _, best_prev = _first_best(c, overlap, p, M)
    shifts = np.empty((N, 2))
    which = np.empty((N, 2), dtype=np.int64)
    P = 0
    for k in range(N):
        if best_prev[best_cur[k]] == k and best_iou[k] > min_iou:
            b = best_cur[k]
            shifts[P, 0], shifts[P, 1] = cc[b, 0] - cp[k, 0], cc[b, 1] - cp[k, 1]
            which[P, 0], which[P, 1] = k, b
            P += 1
    return shifts[:P], which[:P]


@njit
def _mode_shift(candidates, radius):
    """The candidate shift with the most votes (`_votes`). Ties go to the smallest
    |dx| + |dy|, then the lowest (dx, dy), so that the order of the boxes, which is no
    information, does not matter."""
    C = len(candidates)
    votes = _votes(candidates[:, 0], candidates[:, 1], radius)
    top, best = votes.max(), -1
    for k in range(C):
        if votes[k] != top:
            continue
        if best < 0:
            best = k
            continue
        key = abs(candidates[k, 0]) + abs(candidates[k, 1])
        key_best = abs(candidates[best, 0]) + abs(candidates[best, 1])
        if key < key_best or (key == key_best and (
                candidates[k, 0] < candidates[best, 0] or (
                    candidates[k, 0] == candidates[best, 0]
                    and candidates[k, 1] < candidates[best, 1]))):
            best = k
    return candidates[best].copy()


@njit
def _votes(x, y, radius):
    """Per candidate a, the candidates b (a included) with |x_b - x_a| and |y_b - y_a| both
    below min(radius_a, radius_b). The candidates are binned in strips of y as tall as the
    largest radius (taller if that made more strips than candidates) and sorted by x within a
    strip; each pair is looked at once, from the one in the lower strip (or earlier in x),
    over its own strip and those within its radius above. The people who moved alike make a
    dense cluster of shifts, and a sweep along x alone compared each of them with every
    candidate in that column."""
    C = len(x)
    votes = np.ones(C, dtype=np.int64)
    if C == 0 or not radius.max() > 0:
        return votes
    low = y.min()
    tall = max(radius.max(), (y.max() - low) / C)  # any height is exact; C + 1 strips at most
    strip = np.floor((y - low) / tall).astype(np.int64)
    order = np.argsort(x, kind="mergesort")
    order = order[np.argsort(strip[order], kind="mergesort")]
    strips = strip[order[-1]] + 1
    start = np.zeros(strips + 1, dtype=np.int64)
    for k in range(C):
        start[strip[k] + 1] += 1
    start = np.cumsum(start)
    xs, ys, rs = x[order], y[order], radius[order]
    counted = np.ones(C, dtype=np.int64)
    for s in range(strips):
        for a in range(start[s], start[s + 1]):
            xa, ya, ra = xs[a], ys[a], rs[a]
            # a margin far above rounding, so that no pair within reach is left out
            mx, my = 1e-9 * (abs(xa) + ra), 1e-9 * (abs(ya) + abs(low) + ra)
            last = min(np.int64(np.floor((ya + ra + my - low) / tall)), strips - 1)
            own = 0
            for t in range(s, last + 1):
                b = a + 1 if t == s else start[t] + np.searchsorted(
                    xs[start[t]:start[t + 1]], xa - ra - mx)
                while b < start[t + 1] and xs[b] < xa + ra + mx:
                    limit = min(ra, rs[b])
                    near = np.int64(max(abs(xs[b] - xa), abs(ys[b] - ya)) < limit)
                    own += near
                    counted[b] += near
                    b += 1
            counted[a] += own
    votes[order] = counted
    return votes


@njit
def _median_rows(values):
    """np.median(values, axis=0) of (P, 2) values, P >= 1."""
    out = np.empty(2)
    P = len(values)
    for axis in range(2):
        ordered = np.sort(values[:, axis])
        half = P // 2
        out[axis] = ordered[half] if P % 2 else (ordered[half - 1] + ordered[half]) / 2.0
    return out
