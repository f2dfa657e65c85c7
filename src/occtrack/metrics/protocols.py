"""Scoring protocols: which boxes are scored, and how they are matched (DESIGN §2.2).

`paper` reproduces the scoring of the paper's Table II exactly as the authors' script did it
(carstop/MWO/pedestrian/score.py), so that occtrack's table reads beside the paper's; `mot17`
is the official MOTChallenge protocol as TrackEval runs it, the one to quote. Both score GOSPA
(c = 1, p = 1, alpha = 2, base distance 1 - IoU, summed over frames) and the cardinality error
(result boxes / true boxes - 1) on the boxes the protocol keeps.

A protocol turns a ground-truth table and a result table into `ScoredFrames`: per frame, the
rows of each table it scores and their IoU. Input checks live here, at the boundary.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable, first_duplicate
from occtrack.metrics.protocol_text import (  # noqa: F401  (re-exported)
    DESCRIPTION,
    GOSPA_DESCRIPTION,
    KEYS,
    PROTOCOLS,
    SUMMARY,
)

PAPER_CLASSES = (1, 2, 7)
"""Pedestrian, person on vehicle, static person (MOTChallenge class numbers)."""
PEDESTRIAN = 1
MOT_CLASSES = range(1, 14)
GOSPA_C = 1.0
GOSPA_P = 1.0


@dataclass(frozen=True)
class ScoredFrames:
    """The boxes one protocol scores. Entry t is frame t + 1: `truth_rows[t]` and
    `estimate_rows[t]` index the ground-truth and result tables, `iou[t]` is their
    (n_truth, n_estimate) IoU as the protocol's reference tool computes it. `trackeval` is
    TrackEval's preprocessed sequence (mot17 only)."""

    protocol: str
    truth_rows: list[np.ndarray]
    estimate_rows: list[np.ndarray]
    iou: list[np.ndarray]
    trackeval: dict | None = None

    @property
    def num_frames(self) -> int:
        return len(self.iou)

    @property
    def num_truth(self) -> int:
        return int(sum(len(r) for r in self.truth_rows))

    @property
    def num_estimates(self) -> int:
        return int(sum(len(r) for r in self.estimate_rows))


def check_protocol(protocol: str) -> str:
    if protocol not in PROTOCOLS:
        raise OcctrackError(f"unknown protocol {protocol!r}; choose from {', '.join(PROTOCOLS)}")
    return protocol


def result_classes_left_out(result: MotTable, protocol: str) -> np.ndarray:
    """Mask of result rows that are not scored because their class column (8th) names a class
    other than pedestrian. TrackEval takes 1 or below (or no column) as pedestrian and refuses
    a file with anything else; occtrack leaves such rows out, under both protocols, so that a
    ground-truth file scores as a perfect result."""
    check_protocol(protocol)
    return result.cls > PEDESTRIAN


def check_tables(gt: MotTable, result: MotTable, num_frames: int | None = None) -> int:
    """Validate a ground-truth / result pair and return the number of frames scored: the
    given `num_frames` (seqLength), or the last frame of either table."""
    last = max(gt.num_frames, result.num_frames)
    if num_frames is None:
        num_frames = max(last, 1)
    elif num_frames < 1:
        raise OcctrackError(f"number of frames must be at least 1, got {num_frames}")
    for table, what in ((gt, "ground truth"), (result, "result")):
        late = np.flatnonzero(table.frame > num_frames)
        if len(late):
            raise OcctrackError(f"{what} has frame {table.frame[late[0]]} but the sequence has "
                                f"{num_frames} frames (seqLength)", table.path or None)
        negative = np.flatnonzero(table.id < 0)
        if len(negative):
            hint = " (a detection file? results need track ids)" if what == "result" else ""
            raise OcctrackError(f"{what} has negative id {table.id[negative[0]]} in frame "
                                f"{table.frame[negative[0]]}{hint}", table.path or None)
    bad = np.flatnonzero(~np.isin(gt.cls, MOT_CLASSES))
    if len(bad):
        raise OcctrackError(f"ground truth has class {gt.cls[bad[0]]} in frame "
                            f"{gt.frame[bad[0]]}; MOTChallenge classes are 1-13 (column 8; "
                            f"ground truth needs 9 columns)", gt.path or None)
    for table, what in ((gt, "ground truth"), (result, "result")):
        twice = first_duplicate(table.frame, table.id)
        if twice is not None:
            first = twice[0]
            raise OcctrackError(f"{what} has id {table.id[first]} twice in frame "
                                f"{table.frame[first]}", table.path or None)
    return int(num_frames)


def scored_frames(gt: MotTable, result: MotTable, protocol: str,
                  num_frames: int | None = None) -> ScoredFrames:
    """The rows of `gt` and `result` that `protocol` scores, frame by frame, and their IoU."""
    check_protocol(protocol)
    num_frames = check_tables(gt, result, num_frames)
    candidates = np.flatnonzero(~result_classes_left_out(result, protocol))
    if protocol == "mot17":
        from occtrack.metrics.trackeval_mot17 import preprocess

        data, truth_rows, kept = preprocess(gt, result.select(candidates), num_frames)
        return ScoredFrames(protocol, truth_rows, [candidates[k] for k in kept],
                            list(data["similarity_scores"]), data)

    from motmetrics.distances import boxiou

    truth = np.flatnonzero((gt.score == 1) & np.isin(gt.cls, PAPER_CLASSES))
    truth_rows = [truth[r] for r in gt.select(truth).frame_slices(num_frames)]
    estimate_rows = [candidates[r] for r in result.select(candidates).frame_slices(num_frames)]
    iou = [boxiou(gt.box[t][:, None], result.box[e][None, :])
           for t, e in zip(truth_rows, estimate_rows, strict=True)]
    return ScoredFrames(protocol, truth_rows, estimate_rows, iou)
