"""HOTA of tracks of points (the lidar scan tracker's people): TrackEval's own HOTA
(`trackeval.metrics.HOTA.eval_sequence`, Luiten et al. 2021) with a distance similarity in
place of the boxes' IoU, s = max(0, 1 - d / threshold), so that HOTA's localisation level
alpha is a distance: a pair counts at alpha when it is closer than (1 - alpha) threshold.

Written here is only what TrackEval's box datasets do before the metric: gather each time
step's ids (renumbered 0..n-1, as its datasets do) and similarity matrix. The metric itself is
TrackEval's, so the score is the field's HOTA, only its similarity changed. `point_data` is
the sequence dict it is given, which TrackEval's CLEAR and Identity take too
(`occtrack.metrics.kitti_bev`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PointHota:
    """HOTA, DetA, AssA and LocA, each averaged over the 19 alphas (as TrackEval reports)."""

    hota: float
    deta: float
    assa: float
    loca: float


class PointTracks:
    """Time step by time step, the true and the reported points with their ids:
    `add(truth_ids, truth_xy, track_ids, track_xy)` once a step, then `score(threshold)`."""

    def __init__(self) -> None:
        self.steps: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def add(self, truth_ids, truth_xy, track_ids, track_xy) -> None:
        self.steps.append((np.asarray(truth_ids, np.int64), np.asarray(truth_xy, float),
                           np.asarray(track_ids, np.int64), np.asarray(track_xy, float)))

    def score(self, threshold: float) -> PointHota:
        return point_hota(self.steps, threshold)


def similarity(truth_xy: np.ndarray, track_xy: np.ndarray, threshold: float) -> np.ndarray:
    """The (n, m) similarity max(0, 1 - distance / threshold) of n true and m reported
    points."""
    truth_xy, track_xy = np.asarray(truth_xy, float), np.asarray(track_xy, float)
    if not (len(truth_xy) and len(track_xy)):
        return np.zeros((len(truth_xy), len(track_xy)))
    d = np.hypot(*(truth_xy[:, None, :] - track_xy[None, :, :]).transpose(2, 0, 1))
    return np.maximum(0.0, 1.0 - d / threshold)


def point_data(steps, threshold: float) -> dict:
    """The sequence dict TrackEval's metrics take (`eval_sequence` of HOTA, CLEAR, Identity,
    Count) for `steps` as `point_hota` takes them: ids renumbered 0..n-1, similarity
    max(0, 1 - distance / threshold)."""
    if not threshold > 0:
        raise ValueError(f"threshold must be > 0, not {threshold}")
    truth_all = np.unique(np.concatenate([s[0] for s in steps] or [np.zeros(0, np.int64)]))
    track_all = np.unique(np.concatenate([s[2] for s in steps] or [np.zeros(0, np.int64)]))
    data = {"gt_ids": [], "tracker_ids": [], "similarity_scores": [],
            "num_gt_ids": len(truth_all), "num_tracker_ids": len(track_all),
            "num_gt_dets": 0, "num_tracker_dets": 0, "num_timesteps": len(steps)}
    for tid, txy, eid, exy in steps:
        data["gt_ids"].append(np.searchsorted(truth_all, tid))
        data["tracker_ids"].append(np.searchsorted(track_all, eid))
        data["similarity_scores"].append(similarity(txy, exy, threshold))
        data["num_gt_dets"] += len(tid)
        data["num_tracker_dets"] += len(eid)
    return data


def point_hota(steps, threshold: float) -> PointHota:
    """HOTA over `steps`, each (truth ids (n,), truth points (n, 2), track ids (m,), track
    points (m, 2)), with similarity max(0, 1 - distance / threshold)."""
    from trackeval.metrics import HOTA

    res = HOTA(config={"PRINT_CONFIG": False}).eval_sequence(point_data(steps, threshold))
    return PointHota(*(float(np.mean(res[k])) for k in ("HOTA", "DetA", "AssA", "LocA")))
