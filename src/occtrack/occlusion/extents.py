"""1-D extents seen from a point: nearer lanes hide farther ones (the highway's occlusion).

A shape [left, right] in lane k (distance d_k) covers the angles [left, right] / d_k (tangents,
which order the same way). Nearer lanes hide farther ones; shapes of one lane never hide each
other. A shape is reported unless one connected hidden part holds both its ends; an end that is
hidden lies in the connected part of the hidden angles (scaled back to metres in its lane) that
contains it.

Hidden parts are kept as sorted disjoint intervals and located with `searchsorted`; no float end
is ever compared for equality (the authors' prototype's equality test dropped hidden spans).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def union(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted disjoint intervals whose union is that of [lo_i, hi_i] (touching ones merged)."""
    if len(lo) == 0:
        return np.empty(0), np.empty(0)
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    reach = np.maximum.accumulate(hi)
    first = np.concatenate(([0], np.flatnonzero(lo[1:] > reach[:-1]) + 1))
    return lo[first], np.maximum.reduceat(hi, first)


def locate(x: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Index of the interval containing each x (closed), or -1."""
    if len(starts) == 0:
        return np.full(len(x), -1)
    i = np.searchsorted(starts, x, side="right") - 1
    inside = (i >= 0) & (x <= ends[np.maximum(i, 0)])
    return np.where(inside, i, -1)


@dataclass(frozen=True)
class Occluded:
    """What the occlusion pass found for each input shape."""

    reported: np.ndarray
    left_hidden: np.ndarray
    right_hidden: np.ndarray
    left_span: np.ndarray
    right_span: np.ndarray


def occlude(lane: np.ndarray, left: np.ndarray, right: np.ndarray,
            distances: np.ndarray) -> Occluded:
    """Nearer lanes hide farther ones. Returns, per shape, whether it is reported (not wholly
    hidden), which ends are hidden and the hidden interval (metres in its own lane) of each
    hidden end (NaN for a seen end)."""
    n = len(lane)
    reported = np.ones(n, bool)
    left_hidden = np.zeros(n, bool)
    right_hidden = np.zeros(n, bool)
    left_span = np.full((n, 2), np.nan)
    right_span = np.full((n, 2), np.nan)
    starts, ends = np.empty(0), np.empty(0)
    for k, d in enumerate(distances):
        sel = np.flatnonzero(lane == k)
        if len(sel) == 0:
            continue
        a, b = left[sel] / d, right[sel] / d
        ia, ib = locate(a, starts, ends), locate(b, starts, ends)
        left_hidden[sel], right_hidden[sel] = ia >= 0, ib >= 0
        reported[sel] = ~((ia >= 0) & (ia == ib))
        for i, span in ((ia, left_span), (ib, right_span)):
            h = i >= 0
            span[sel[h], 0] = starts[i[h]] * d
            span[sel[h], 1] = ends[i[h]] * d
        starts, ends = union(np.concatenate((starts, a)), np.concatenate((ends, b)))
    return Occluded(reported, left_hidden, right_hidden, left_span, right_span)
