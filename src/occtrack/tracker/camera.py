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

import numpy as np

from occtrack.spatial import overlapping_pairs
from occtrack.tracker._tracker import (  # noqa: F401 (kernels kept under their old names)
    _camera_dense,
    _candidates,
    _estimate_dense,
    _expansion_fit,
    _first_best,
    _iou,
    _median_rows,
    _mode_shift,
    _mutual_shifts,
    _qualifies,
    _shift_and_error,
    _votes,
)

DENSE_PAIRS = 4096  # more box pairs than this: the sparse form (faster from here on)


def _centres(boxes: np.ndarray) -> np.ndarray:
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def _edges(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) left, top, width, height -> (N, 2, 2) edges."""
    return np.stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]], axis=-1)


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
            np.ascontiguousarray(previous, dtype=float),
            np.ascontiguousarray(current, dtype=float), np.ascontiguousarray(centre, dtype=float),
            height_ratio, mode_radius, min_iou, min_pairs)
        if not found:
            return None
        return shift, error, ((k, variance) if fitted else None)
    matched = matched_pairs(previous, current, height_ratio, mode_radius, min_iou, min_pairs)
    if matched is None:
        return None
    return (*_shift_and_error(matched[0]),
            _expansion(*matched, previous, current, centre))


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
    found, k, variance = _expansion_fit(pairs, which,
                                        np.ascontiguousarray(previous, dtype=float),
                                        np.ascontiguousarray(current, dtype=float),
                                        np.ascontiguousarray(centre, dtype=float))
    return (k, variance) if found else None


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
    found, pairs, which = _estimate_dense(np.ascontiguousarray(previous, dtype=float),
                                          np.ascontiguousarray(current, dtype=float),
                                          height_ratio, mode_radius, min_iou, min_pairs)
    return (pairs, which) if found else None


def _estimate_sparse(previous: np.ndarray, current: np.ndarray, height_ratio: float,
                     mode_radius: float, min_iou: float,
                     min_pairs: int) -> tuple[np.ndarray, np.ndarray] | None:
    """`matched_pairs` on the pairs that can qualify only; the same result."""
    previous = np.ascontiguousarray(previous, dtype=float)
    current = np.ascontiguousarray(current, dtype=float)
    cp, cc = _centres(previous), _centres(current)
    candidates, unit = _candidates_within_reach(previous, current, cp, cc, height_ratio)
    if len(unit) < min_pairs:
        return None
    mode = _mode_shift(candidates, mode_radius * unit)
    moved = previous.copy()
    moved[:, :2] += mode
    p, c = overlapping_pairs(_edges(moved), _edges(current))
    shifts, which = _mutual_shifts(np.ascontiguousarray(p), np.ascontiguousarray(c), moved,
                                   current, cp, cc, min_iou)
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
    hp = np.ascontiguousarray(previous[:, 3], dtype=float)
    hc = np.ascontiguousarray(current[:, 3], dtype=float)
    # a qualifying pair moved less than sqrt(hp hc) < sqrt(height_ratio) hp on each axis
    reach = np.sqrt(height_ratio) * hp * (1.0 + 1e-9) + 1e-9
    around = np.stack([cp - reach[:, None], cp + reach[:, None]], axis=-1)
    i, j = overlapping_pairs(around, np.stack([cc, cc], axis=-1))
    return _candidates(np.ascontiguousarray(i), np.ascontiguousarray(j), hp, hc, cp, cc,
                       height_ratio, len(current))
