"""Calibration of a tracker's confidence column: the reliability table and its ECE.

A tracker that writes a confidence c on each box (MOTChallenge's 7th column) says: a box
reported with c is a real object at that place with probability c. "Right" is decided as the
mot17 protocol decides a detection-level hit: boxes on distractors are left out (TrackEval's
preprocessing), and in each frame the remaining boxes are matched one to one to the true
pedestrians, maximising the number of pairs at IoU >= 0.5 (`RIGHT_IOU`). A matched box is right,
an unmatched one wrong.

The boxes are binned by confidence into `bins` equal intervals of [0, 1] (the last one closed);
per bin the table holds the boxes, their mean confidence and the share right. The expected
calibration error (Naeini et al. 2015, Guo et al. 2017) is

    ECE = sum_b (n_b / N) |mean confidence_b - share right_b|,

the gap between what a box says and how often it is right, weighted by where the boxes are.
Written here, not taken from a library: scikit-learn's `calibration_curve` bins the same way but
drops empty bins and returns no counts, and the matching is the tracking protocol's, not a
classifier's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.metrics.protocols import ScoredFrames
from occtrack.tracker.confidence import RIGHT_IOU  # the event the tracker's confidence is of

__all__ = ["BINS", "RIGHT_IOU", "Reliability", "pooled", "reliability", "reliability_table",
           "right_boxes"]

BINS = 10


@dataclass(frozen=True)
class Reliability:
    """A reliability table: per bin b (confidence in [edges[b], edges[b + 1]), the last bin
    closed), `boxes[b]` reported boxes, `confidence[b]` their mean confidence and `right[b]`
    the share of them right (NaN for an empty bin); `ece` the expected calibration error and
    `num_boxes` the boxes scored."""

    edges: np.ndarray
    boxes: np.ndarray
    confidence: np.ndarray
    right: np.ndarray
    ece: float

    @property
    def num_boxes(self) -> int:
        return int(self.boxes.sum())

    def as_dict(self) -> dict:
        def plain(values):
            return [None if not np.isfinite(v) else round(float(v), 6) for v in values]
        return {"ece": round(self.ece, 6), "bins": len(self.boxes),
                "boxes": self.boxes.astype(int).tolist(),
                "confidence": plain(self.confidence), "right": plain(self.right)}

    @classmethod
    def from_dict(cls, values: dict) -> Reliability:
        """The table `as_dict` wrote (a benchmark report's "calibration" entries; an empty
        bin's null read as NaN), to be `pooled` with others."""
        def array(key):
            return np.array([np.nan if v is None else v for v in values[key]], dtype=float)
        return cls(np.linspace(0.0, 1.0, int(values["bins"]) + 1),
                   np.asarray(values["boxes"], dtype=np.int64), array("confidence"),
                   array("right"), float(values["ece"]))


def right_boxes(frames: ScoredFrames) -> tuple[np.ndarray, np.ndarray]:
    """(rows, right): the result rows the protocol scores, in frame order, and whether each is
    matched one to one to a true object at IoU >= `RIGHT_IOU` (the most such pairs a frame)."""
    rows, right = [], []
    for est, iou in zip(frames.estimate_rows, frames.iou, strict=True):
        hit = np.zeros(len(est), bool)
        if iou.size:
            good = iou >= RIGHT_IOU - 1e-12
            if good.any():
                truth, estimate = linear_sum_assignment(good, maximize=True)
                hit[estimate[good[truth, estimate]]] = True
        rows.append(np.asarray(est, dtype=np.int64))
        right.append(hit)
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0, bool)
    return np.concatenate(rows), np.concatenate(right)


def reliability_table(confidence: np.ndarray, right: np.ndarray, bins: int = BINS) -> Reliability:
    """The reliability table and ECE of boxes with `confidence` (in [0, 1]) that are `right`
    (bool) or not."""
    confidence = np.asarray(confidence, dtype=float)
    right = np.asarray(right, dtype=bool)
    if confidence.shape != right.shape:
        raise ValueError(f"{len(confidence)} confidences for {len(right)} boxes")
    if not np.isfinite(confidence).all() or confidence.min(initial=0) < 0 or \
            confidence.max(initial=0) > 1:
        raise ValueError("confidences must be probabilities in [0, 1]")
    if bins < 1:
        raise ValueError(f"bins must be at least 1, not {bins}")
    which = np.minimum(np.floor(confidence * bins).astype(np.int64), bins - 1)
    return _from_totals(np.linspace(0.0, 1.0, bins + 1), np.bincount(which, minlength=bins),
                        np.bincount(which, weights=confidence, minlength=bins),
                        np.bincount(which, weights=right.astype(float), minlength=bins))


def _from_totals(edges, count, total_conf, total_right) -> Reliability:
    """The table from per-bin box counts, summed confidences and right boxes."""
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_conf, share = total_conf / count, total_right / count
    ece = float(np.abs(total_conf - total_right).sum() / max(int(count.sum()), 1))
    return Reliability(edges, count, mean_conf, share, ece)


def reliability(frames: ScoredFrames, confidence: np.ndarray, bins: int = BINS) -> Reliability:
    """The reliability table of a result under a protocol's scored frames: `confidence` is the
    result table's confidence column (one entry a row of the result table)."""
    rows, right = right_boxes(frames)
    return reliability_table(np.asarray(confidence, dtype=float)[rows], right, bins)


def pooled(tables: list[Reliability]) -> Reliability:
    """The reliability table of the boxes of several tables (same bins) taken together: per
    bin the summed boxes, confidences and right boxes."""
    if not tables:
        return reliability_table(np.zeros(0), np.zeros(0, bool))
    if len({len(t.boxes) for t in tables}) > 1:
        raise ValueError("tables with different bins cannot be pooled")
    return _from_totals(tables[0].edges, sum(t.boxes for t in tables),
                        sum(np.nan_to_num(t.confidence * t.boxes) for t in tables),
                        sum(np.nan_to_num(t.right * t.boxes) for t in tables))
