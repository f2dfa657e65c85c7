"""CLEAR MOT (Bernardin and Stiefelhagen 2008), identity measures (IDF1, Ristani et al. 2016)
and mostly tracked / lost, with motmetrics' conventions.

Objects are the boxes being scored against, hypotheses the boxes that explain them; each frame
gives a matrix of object-to-hypothesis distances, NaN where a pair may not match. motmetrics'
accumulator (`MOTAccumulator.update`) matches frame by frame: a pair matched before is kept
while its distance is finite, the rest are assigned by least total distance, and a match that
contradicts an object's previous hypothesis is a switch. Then

    MOTA = 1 - (misses + switches + false positives) / objects
    MOTP = sum of matched distances / matches                      (a distance: lower is better)
    IDF1 = 2 IDTP / (objects + hypotheses),  IDTP from one global one-to-one matching of object
           and hypothesis tracks that maximises the frames they are matchable together
    mostly tracked / lost = objects matched in >= 80 % / < 20 % of their frames.

Two implementations give the same numbers. `clear_mot_motmetrics` runs motmetrics itself.
`clear_mot` is an array port of that accumulator (same order of matching, motmetrics' own
assignment solver, so the same ties are broken the same way): motmetrics records every finite
object-hypothesis pair of every frame as a pandas event, which under the `paper` protocol (any
pair may match) is about 1.3 million events and 3 s on MOT17-04, against 0.2 s here. The tests
check that both agree on random sequences.

motmetrics 1.4's `distances.iou_matrix` calls `np.asfarray`, which numpy 2 removed; `iou_distances`
is that function with the call replaced (motmetrics' own `boxiou`, the same arithmetic).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from motmetrics.distances import boxiou
from motmetrics.lap import linear_sum_assignment as motmetrics_assignment
from scipy.optimize import linear_sum_assignment


@dataclass(frozen=True)
class ClearMot:
    """CLEAR MOT and identity measures, named as motmetrics names them. Ratios are NaN or
    infinite where their denominator is zero (motmetrics' `quiet_divide`)."""

    mota: float
    motp: float
    idf1: float
    mostly_tracked: int
    partially_tracked: int
    mostly_lost: int
    num_matches: int
    num_switches: int
    num_false_positives: int
    num_misses: int
    idtp: int
    idfp: int
    idfn: int
    num_objects: int
    num_predictions: int

    def as_dict(self) -> dict:
        return asdict(self)


def iou_distances(objects: np.ndarray, hypotheses: np.ndarray,
                  max_distance: float = 1.0) -> np.ndarray:
    """motmetrics' `iou_matrix`: 1 - IoU of (left, top, width, height) boxes, NaN above
    `max_distance`. With `max_distance` 1 every pair may match, even one with no overlap."""
    objects = np.asarray(objects, dtype=float).reshape(-1, 4)
    hypotheses = np.asarray(hypotheses, dtype=float).reshape(-1, 4)
    dist = 1.0 - boxiou(objects[:, None], hypotheses[None, :])
    return np.where(dist > max_distance, np.nan, dist)


def _quiet_divide(a: float, b: float) -> float:
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.true_divide(a, b))


def _relabel(ids: Sequence[np.ndarray]) -> tuple[list[np.ndarray], int]:
    flat = np.concatenate([np.asarray(i).ravel() for i in ids]) if len(ids) else np.empty(0)
    _, inverse = np.unique(flat, return_inverse=True)
    bounds = np.cumsum([0] + [len(i) for i in ids])
    n = int(inverse.max()) + 1 if len(inverse) else 0
    return [inverse[bounds[t]:bounds[t + 1]] for t in range(len(ids))], n


def _check(object_ids, hypothesis_ids, distances) -> None:
    if not len(object_ids) == len(hypothesis_ids) == len(distances):
        raise ValueError("object_ids, hypothesis_ids and distances need one entry per frame")
    for t, (o, h, d) in enumerate(zip(object_ids, hypothesis_ids, distances, strict=True)):
        if len(o) and len(h) and np.shape(d) != (len(o), len(h)):
            raise ValueError(f"frame {t}: distances are {np.shape(d)}, expected "
                             f"({len(o)}, {len(h)})")
        if len(np.unique(o)) != len(o) or len(np.unique(h)) != len(h):
            raise ValueError(f"frame {t}: an id appears twice")


def clear_mot(object_ids: Sequence[np.ndarray], hypothesis_ids: Sequence[np.ndarray],
              distances: Sequence[np.ndarray]) -> ClearMot:
    """Score a sequence: per frame t, object ids (n_o,), hypothesis ids (n_h,) and their
    (n_o, n_h) distances, NaN where a pair may not match."""
    _check(object_ids, hypothesis_ids, distances)
    oids, n_obj = _relabel(object_ids)
    hids, n_hyp = _relabel(hypothesis_ids)

    paired = np.full(n_obj, -1)
    obj_count = np.zeros(n_obj, dtype=np.int64)
    obj_tracked = np.zeros(n_obj, dtype=np.int64)
    hyp_count = np.zeros(n_hyp, dtype=np.int64)
    column = np.full(n_hyp, -1)
    matched_distances: list[np.ndarray] = []
    pair_codes: list[np.ndarray] = []
    matches = switches = misses = false_positives = 0

    for o, h, d in zip(oids, hids, distances, strict=True):
        n_o, n_h = len(o), len(h)
        obj_count[o] += 1
        hyp_count[h] += 1
        o_done = np.zeros(n_o, dtype=bool)
        h_done = np.zeros(n_h, dtype=bool)
        if n_o and n_h:
            d = np.asarray(d, dtype=float).reshape(n_o, n_h)
            finite_i, finite_j = np.nonzero(np.isfinite(d))
            pair_codes.append(o[finite_i] * n_hyp + h[finite_j])

            # 1. keep last pairings that are still matchable (first object wins a hypothesis)
            column[h] = np.arange(n_h)
            prev = paired[o]
            j = np.where(prev >= 0, column[np.maximum(prev, 0)], -1)
            i = np.flatnonzero(j >= 0)
            i = i[np.isfinite(d[i, j[i]])]
            _, first = np.unique(j[i], return_index=True)
            i = i[np.sort(first)]
            o_done[i] = True
            h_done[j[i]] = True
            matched_distances.append(d[i, j[i]])
            matches += len(i)
            column[h] = -1

            # 2. assign the rest by least total distance (motmetrics' solver and tie-breaking)
            rest = d.copy()
            rest[o_done, :] = np.nan
            rest[:, h_done] = np.nan
            rows, cols = motmetrics_assignment(rest)
            keep = np.isfinite(rest[rows, cols])
            rows, cols = rows[keep], cols[keep]
            before = paired[o[rows]]
            is_switch = (before >= 0) & (before != h[cols])
            switches += int(is_switch.sum())
            matches += int((~is_switch).sum())
            paired[o[rows]] = h[cols]
            o_done[rows] = True
            h_done[cols] = True
            matched_distances.append(rest[rows, cols])
        obj_tracked[o[o_done]] += 1
        misses += int(n_o - o_done.sum())
        false_positives += int(n_h - h_done.sum())
        # motmetrics sums a column holding 0 for each miss and false positive: same order, same
        # rounding
        matched_distances.append(np.zeros(n_o + n_h - 2 * o_done.sum()))

    num_objects, num_predictions = int(obj_count.sum()), int(hyp_count.sum())
    together = np.zeros(n_obj * n_hyp, dtype=np.int64)
    if pair_codes:
        together = np.bincount(np.concatenate(pair_codes), minlength=n_obj * n_hyp)
    together = together.reshape(n_obj, n_hyp)
    idtp = 0
    if together.size:
        rows, cols = linear_sum_assignment(together, maximize=True)
        idtp = int(together[rows, cols].sum())

    ratio = obj_tracked / np.maximum(obj_count, 1)
    distance_sum = float(np.sum(np.concatenate(matched_distances))) if matched_distances else 0.0
    return ClearMot(
        mota=1.0 - _quiet_divide(misses + switches + false_positives, num_objects),
        motp=_quiet_divide(distance_sum, matches + switches),
        idf1=_quiet_divide(2 * idtp, num_objects + num_predictions),
        mostly_tracked=int((ratio >= 0.8).sum()),
        partially_tracked=int(((ratio >= 0.2) & (ratio < 0.8)).sum()),
        mostly_lost=int((ratio < 0.2).sum()),
        num_matches=matches, num_switches=switches, num_false_positives=false_positives,
        num_misses=misses, idtp=idtp, idfp=num_predictions - idtp, idfn=num_objects - idtp,
        num_objects=num_objects, num_predictions=num_predictions)


_MOTMETRICS_NAMES = ("mota", "motp", "idf1", "mostly_tracked", "partially_tracked",
                     "mostly_lost", "num_matches", "num_switches", "num_false_positives",
                     "num_misses", "idtp", "idfp", "idfn", "num_objects", "num_predictions")


def clear_mot_motmetrics(object_ids: Sequence[np.ndarray], hypothesis_ids: Sequence[np.ndarray],
                         distances: Sequence[np.ndarray]) -> ClearMot:
    """The same scores through motmetrics' own accumulator and metrics (slow, for checking)."""
    import motmetrics

    _check(object_ids, hypothesis_ids, distances)
    acc = motmetrics.MOTAccumulator(auto_id=False)
    for t, (o, h, d) in enumerate(zip(object_ids, hypothesis_ids, distances, strict=True)):
        d = np.asarray(d, dtype=float) if len(o) and len(h) else np.empty((len(o), len(h)))
        acc.update(np.asarray(o), np.asarray(h), d, frameid=t)
    values = motmetrics.metrics.create().compute(acc, metrics=list(_MOTMETRICS_NAMES),
                                                 return_dataframe=False)
    ints = {name for name, kind in ClearMot.__annotations__.items() if kind == "int"}
    return ClearMot(**{name: int(values[name]) if name in ints else float(values[name])
                       for name in _MOTMETRICS_NAMES})
