"""One entry point for scoring a tracker's result against ground truth under a protocol.

`evaluate` returns the numbers of `occtrack eval --json`; `gospa_per_frame` the per-frame GOSPA
behind its total, for plots. See `occtrack.metrics.protocols` for what each protocol scores.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.metrics.clear import clear_mot
from occtrack.metrics.gospa import gospa_from_distances
from occtrack.metrics.protocols import GOSPA_C, GOSPA_P, KEYS, ScoredFrames, scored_frames
from occtrack.metrics.trackeval_mot17 import scores as trackeval_scores
from occtrack.metrics.trackeval_mot17 import summary as trackeval_summary

__all__ = ["KEYS", "check_truth", "evaluate", "evaluate_frames", "frame_gospa",
           "gospa_per_frame"]


def evaluate(gt: MotTable, result: MotTable, protocol: str,
             num_frames: int | None = None) -> dict:
    """Score `result` against `gt` under `protocol` ("paper" or "mot17").

    Returns a dict with exactly the keys in `KEYS`. Fractions (MOTA, MOTP, IDF1, HOTA) are in
    [0, 1], not percent (MOTA can be negative); counts are ints; GOSPA is summed over frames.
    A value is None where it is undefined: HOTA under `paper`, a ratio whose denominator is
    zero. `num_frames` is the sequence length (seqLength); by default the last frame present.
    A ground truth with no box that the protocol scores is an `OcctrackError` (every metric
    would be undefined), not a score of 0.
    """
    return evaluate_frames(scored_frames(gt, result, protocol, num_frames), gt, result)


def gospa_per_frame(gt: MotTable, result: MotTable, protocol: str,
                    num_frames: int | None = None) -> np.ndarray:
    """GOSPA of each frame (entry t is frame t + 1) on the boxes `protocol` scores; the sum is
    `evaluate(...)["gospa"]`."""
    return frame_gospa(scored_frames(gt, result, protocol, num_frames))


def frame_gospa(frames: ScoredFrames) -> np.ndarray:
    """Per-frame GOSPA (c = 1, p = 1, alpha = 2, distance 1 - IoU) of already scored frames."""
    return np.array([gospa_from_distances(1.0 - iou, GOSPA_C, GOSPA_P).total
                     for iou in frames.iou], dtype=float)


def evaluate_frames(frames: ScoredFrames, gt: MotTable, result: MotTable,
                    trackeval_results: dict | None = None) -> dict:
    """`evaluate` on frames already scored by `scored_frames(gt, result, ...)`, so that a plot
    of `frame_gospa(frames)` and the table share one preprocessing. `trackeval_results`, if
    given, are TrackEval's `sequence_results(frames.trackeval)`, already computed."""
    check_truth(frames, gt)
    if frames.protocol == "mot17":
        values = (trackeval_scores(frames.trackeval) if trackeval_results is None
                  else trackeval_summary(trackeval_results))
    else:
        objects = [result.id[r] for r in frames.estimate_rows]
        hypotheses = [gt.id[r] for r in frames.truth_rows]
        distances = [1.0 - iou.T for iou in frames.iou]
        c = clear_mot(objects, hypotheses, distances)
        values = {"mota": c.mota, "motp": c.motp, "idf1": c.idf1, "hota": None,
                  "mostly_tracked": c.mostly_tracked, "mostly_lost": c.mostly_lost,
                  "fp": c.idfp, "fn": c.idfn, "id_switches": c.num_switches}
    num_truth = frames.num_truth
    values["gospa"] = float(frame_gospa(frames).sum())
    values["cardinality_error"] = (frames.num_estimates / num_truth - 1.0) if num_truth else None
    return {key: _finite_or_none(values[key]) for key in KEYS}


SCORED_TRUTH = {
    "paper": "a person: class 1, 2 or 7 in column 8, with 1 in column 7",
    "mot17": "a pedestrian: class 1 in column 8, with 1 in column 7",
}


def check_truth(frames: ScoredFrames, gt: MotTable) -> None:
    """Refuse a ground truth without one box the protocol scores: MOTA, IDF1 and HOTA divide
    by the number of true boxes (or of matches), so a score against nothing is undefined, not
    0, and a 0 in a table would read as a tracker that failed."""
    if frames.num_truth:
        return
    what = ("ground truth has no rows" if not len(gt) else
            f"none of the ground truth's {len(gt)} rows is a box the {frames.protocol} "
            f"protocol scores ({SCORED_TRUTH[frames.protocol]})")
    raise OcctrackError(f"{what}, so the metrics are undefined; score against a ground truth "
                        f"that has at least one scored box", gt.path or None)


def _finite_or_none(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
