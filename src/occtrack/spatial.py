"""Pairs of overlapping axis-aligned boxes, found without testing every pair (floor 1).

Gating and occlusion both ask one question of two sets of boxes: which box of the first set
overlaps which box of the second. Testing all N x M pairs costs N M, which in a crowd of a few
hundred people is most of a frame; a sweep along one axis finds the pairs in about
N log M + (number of candidate pairs), so the cost follows the number of boxes that can
interact, not the square of the number of people.

The sweep: the second set is sorted by its low edge along the sweep axis; a box of the first
set [lo, hi] can overlap only those whose low edge lies in [lo - widest, hi], two binary
searches, and the candidate pairs in those ranges are tested exactly on both axes. Boxes of
the second set much wider than the others (a spurious detection across the image, a vague
component) would widen every range, so they are tested against all boxes of the first set
instead. Small problems (N M at most `DENSE_PAIRS`) are tested all at once: it is faster.

Boxes are edge arrays (..., 2, 2): [axis, low/high], axis 0 horizontal and 1 vertical.
Overlap is strict (boxes that only touch do not overlap). Written here because scipy's trees
answer distance queries between points, not overlap queries between boxes of many sizes. The
test of the candidates is compiled (`_sweep`): in a crowd they are a few thousand a frame, and
the array form made each of them pass through a dozen temporary arrays. `_sweep` is in
`occtrack/_occtrack.pyx`, the package's own extension.
"""

from __future__ import annotations

import numpy as np

from occtrack._occtrack import _sweep  # compiled: _occtrack.pyx

DENSE_PAIRS = 4096  # at most this many pairs: test them all at once


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of (left, top, width, height) boxes, all pairs:
    (len(a), len(b)), 0 where both boxes are empty."""
    ax0, ay0 = a[:, 0, None], a[:, 1, None]
    ax1, ay1 = ax0 + a[:, 2, None], ay0 + a[:, 3, None]
    bx0, by0 = b[None, :, 0], b[None, :, 1]
    bx1, by1 = bx0 + b[None, :, 2], by0 + b[None, :, 3]
    iw = np.clip(np.minimum(ax1, bx1) - np.maximum(ax0, bx0), 0, None)
    ih = np.clip(np.minimum(ay1, by1) - np.maximum(ay0, by0), 0, None)
    inter = iw * ih
    union = a[:, 2, None] * a[:, 3, None] + b[None, :, 2] * b[None, :, 3] - inter
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def _dense(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    hit = ((a[:, None, 0, 0] < b[None, :, 0, 1]) & (b[None, :, 0, 0] < a[:, None, 0, 1])
           & (a[:, None, 1, 0] < b[None, :, 1, 1]) & (b[None, :, 1, 0] < a[:, None, 1, 1]))
    i, j = np.nonzero(hit)
    return i, j


def overlapping_pairs(a: np.ndarray, b: np.ndarray,
                      dense_pairs: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(i, j): every pair of box a[i] (N, 2, 2) and box b[j] (M, 2, 2) that overlap, each once,
    in no particular order."""
    N, M = len(a), len(b)
    if N == 0 or M == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    if N * M <= (DENSE_PAIRS if dense_pairs is None else dense_pairs):
        return _dense(a, b)
    # (float64 in C order: `_sweep` reads them in place)
    a_x0, a_x1 = np.ascontiguousarray(a[:, 0, 0], float), np.ascontiguousarray(a[:, 0, 1], float)
    a_y0, a_y1 = np.ascontiguousarray(a[:, 1, 0], float), np.ascontiguousarray(a[:, 1, 1], float)
    b_x0, b_x1 = np.ascontiguousarray(b[:, 0, 0], float), np.ascontiguousarray(b[:, 0, 1], float)
    width = b_x1 - b_x0
    typical = float(np.partition(width, M // 2)[M // 2])
    wide = width > 4.0 * typical + 1e-9
    i_parts, j_parts = [], []
    normal = np.flatnonzero(~wide) if wide.any() else np.arange(M)
    if len(normal):
        order = normal[np.argsort(b_x0[normal], kind="stable")]
        low = b_x0[order]
        # the second set in sweep order, so that the candidates read contiguous runs
        s_x1, s_y0, s_y1 = b_x1[order], b[order, 1, 0], b[order, 1, 1]
        widest = float(width[normal].max())
        start = np.searchsorted(low, a_x0 - widest, side="left")
        stop = np.searchsorted(low, a_x1, side="left")
        i, j = _sweep(a_x0, a_y0, a_y1, s_x1, np.ascontiguousarray(s_y0, float),
                      np.ascontiguousarray(s_y1, float), order, start, stop)
        i_parts.append(i)
        j_parts.append(j)
    if wide.any():
        w = np.flatnonzero(wide)
        i, jj = _dense(a, b[w])
        i_parts.append(i)
        j_parts.append(w[jj])
    # (the box of median width is never wide, so the sweep always contributes a part)
    return np.concatenate(i_parts), np.concatenate(j_parts)
