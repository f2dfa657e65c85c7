"""KITTI 3D tracking scored on the ground plane (`occtrack eval --protocol kitti-bev`).

TrackEval scores KITTI only in the image (`Kitti2DBox`, IoU of 2D boxes): it has no protocol
on the ground plane, where a 3D tracker's error is. Here its own HOTA, CLEAR and Identity
metrics run on the (x, z) centres of the rectified camera frame with the similarity
max(0, 1 - d / 2 m) (`occtrack.metrics.hota_points`, as for the lidar scans), so HOTA's
alpha is a distance and CLEAR and Identity match within 1 m. Before them, Kitti2DBox's own
preprocessing with that similarity in place of IoU: per class (car, pedestrian), per frame,
result rows of the class matched (Hungarian, similarity >= 0.5) to a distractor (van for car,
person sitting for pedestrian) or to a truncated or largely hidden true object are removed,
and only the class's untruncated, visible-enough objects are scored. Its rules in the image
(boxes 25 px tall or less, DontCare regions) have no ground-plane meaning and are not applied;
true rows without a 3D position are left out with a note. Sequences are combined by
TrackEval's `combine_sequences` on each metric, as the kitti protocol combines them.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.config.arguments import DAY_AT_30_FPS
from occtrack.errors import OcctrackError
from occtrack.io.kitti import TYPES, KittiTable
from occtrack.io.mot import check_gaps
from occtrack.metrics.hota_points import point_data, similarity
from occtrack.metrics.protocols import ScoredFrames
from occtrack.metrics.trackeval_kitti import (
    CLASS_TYPE,
    CLASSES,
    KEYS,
    MAX_OCCLUSION,
    MAX_TRUNCATION,
    _by_frame,
    check_frames,
    check_result,
    sequence_length,
)
from occtrack.metrics.trackeval_mot17 import combined_results, sequence_results, summary

__all__ = ["CLASSES", "DISTANCE", "KEYS", "evaluate", "ground_steps", "scored_frames",
           "unknown_3d"]

DISTANCE = 2.0
"""m: the similarity of two centres d apart is max(0, 1 - d / DISTANCE)."""
MATCH = 0.5
"""The similarity Kitti2DBox's preprocessing, CLEAR and Identity need (d <= 1 m at 2 m)."""
DISTRACTOR = {"car": TYPES.index("Van"), "pedestrian": TYPES.index("Person")}
_EPS = np.finfo(float).eps


def unknown_3d(table: KittiTable) -> np.ndarray:
    """Rows without a 3D box: -1000 in any of h w l x y z (a 2D row writes x y z -1000,
    KITTI's DontCare labels h w l -1000)."""
    return (table.box3d[:, :6] == -1000).any(axis=1)


def _check_3d(result: KittiTable, classes) -> None:
    """Refuse a result row that would be scored but has no ground-plane position."""
    types = [CLASS_TYPE[c] for c in classes]
    bad = np.flatnonzero(np.isin(result.type, types) & (result.id >= 0) & unknown_3d(result))
    if len(bad):
        i = bad[0]
        h, w, l, x, y, z = result.box3d[i, :6]
        raise OcctrackError(f"{TYPES[result.type[i]]} row without a 3D box (h w l x y z = "
                            f"{h:g} {w:g} {l:g} {x:g} {y:g} {z:g}): the kitti-bev protocol "
                            f"scores ground-plane centres; score a 2D result with --protocol "
                            f"kitti", result.path or None,
                            None if result.line is None else int(result.line[i]))


def ground_steps(gt: KittiTable, result: KittiTable, num_frames: int, cls: str,
                 distance: float = DISTANCE
                 ) -> tuple[list[tuple], list[np.ndarray], list[np.ndarray]]:
    """For class `cls`, per frame 0..num_frames - 1: the step `point_hota` takes (truth ids,
    truth (x, z), result ids, result (x, z)) after the preprocessing, and the rows of `gt`
    and of `result` behind it, in its order."""
    if cls not in CLASSES:
        raise OcctrackError(f"KITTI's evaluation scores {' and '.join(CLASSES)}, not {cls!r}")
    _check_3d(result, [cls])
    near = np.isin(gt.type, [CLASS_TYPE[cls], DISTRACTOR[cls]]) & (gt.id >= 0) & ~unknown_3d(gt)
    scored = ((gt.type == CLASS_TYPE[cls]) & (gt.occluded.astype(int) <= MAX_OCCLUSION)
              & (gt.truncated.astype(int) <= MAX_TRUNCATION))
    mine = (result.type == CLASS_TYPE[cls]) & (result.id >= 0)
    gt_xz, result_xz = gt.box3d[:, [3, 5]], result.box3d[:, [3, 5]]
    steps, truth_rows, estimate_rows = [], [], []
    for truth, estimate in zip(_by_frame(gt, np.flatnonzero(near), num_frames),
                               _by_frame(result, np.flatnonzero(mine), num_frames), strict=True):
        sim = similarity(gt_xz[truth], result_xz[estimate], distance)
        if sim.size:  # Kitti2DBox's removal, with the ground-plane similarity for IoU
            matching = np.where(sim < MATCH - _EPS, 0.0, sim)
            rows, cols = linear_sum_assignment(-matching)
            hit = matching[rows, cols] > _EPS
            estimate = np.delete(estimate, cols[hit][~scored[truth[rows[hit]]]])
        truth = truth[scored[truth]]
        truth_rows.append(truth)
        estimate_rows.append(estimate)
        steps.append((gt.id[truth], gt_xz[truth], result.id[estimate], result_xz[estimate]))
    return steps, truth_rows, estimate_rows


def scored_frames(gt: KittiTable, result: KittiTable, num_frames: int,
                  classes: tuple[str, ...] | list[str] = CLASSES,
                  distance: float = DISTANCE) -> dict[str, ScoredFrames]:
    """Per class, what the protocol scores: TrackEval's sequence dict in `trackeval` and, per
    frame (entry t is frame t), the rows of `gt` and `result` kept and their similarity (in
    `iou`). Frames run 0..num_frames - 1."""
    check_frames(gt, num_frames)
    check_frames(result, num_frames)
    check_result(result)
    _check_3d(result, classes)
    out = {}
    for cls in classes:
        steps, truth, estimates = ground_steps(gt, result, num_frames, cls, distance)
        data = point_data(steps, distance)
        out[cls] = ScoredFrames("kitti-bev", truth, estimates, data["similarity_scores"], data)
    return out


def _no_3d_note(gt: KittiTable, classes) -> str | None:
    kinds = [t for c in classes for t in (CLASS_TYPE[c], DISTRACTOR[c])]
    odd = np.flatnonzero(np.isin(gt.type, kinds) & (gt.id >= 0) & unknown_3d(gt))
    if not len(odd):
        return None
    first = "" if gt.line is None else f", first at line {int(gt.line[odd[0]])}"
    return f"{gt.path}: {len(odd)} true rows without a 3D box{first}, not scored"


def evaluate(pairs, classes: tuple[str, ...] | list[str] = CLASSES, frames: int | None = None,
             calibration: bool = False, max_gap_frames: int = DAY_AT_30_FPS,
             distance: float = DISTANCE) -> dict:
    """Score each (name, ground truth, result) on the ground plane: per class, each sequence's
    numbers (`KEYS`; MOTP is the mean similarity of CLEAR's matches) and TrackEval's
    COMBINED_SEQ over them; with `calibration`, per class the reliability table of the
    score column (a row is right when matched within 1 m to a true object of its class),
    pooled over the sequences. Sequence lengths and the checks are the kitti protocol's
    (`occtrack.metrics.trackeval_kitti.evaluate`); a scored result row without a 3D box is
    refused with its file and line.
    Returns {"protocol": "kitti-bev", "distance": metres, "classes": {CLASS: {"sequences":
    {NAME: values}, "combined": values[, "calibration": table]}}, "notes": [...]}."""
    from occtrack.io.kitti import read_kitti
    from occtrack.metrics.reliability import pooled, reliability

    if not distance > 0:
        raise OcctrackError(f"the distance must be > 0 m, not {distance}")
    per_class: dict[str, dict] = {c: {"sequences": {}, "raw": [], "tables": []} for c in classes}
    notes = []
    for name, gt_path, result_path in pairs:
        gt, result = read_kitti(gt_path), read_kitti(result_path)
        for table in (gt, result):
            if table.unknown():
                notes.append(f"{table.path}: {table.unknown()}, not scored")
            check_gaps(table, max_gap_frames)
        if _no_3d_note(gt, classes):
            notes.append(_no_3d_note(gt, classes))
        n = frames or sequence_length(gt_path) or max(gt.num_frames, result.num_frames, 1)
        check_frames(gt, n)
        check_frames(result, n)
        n = min(n, max(gt.num_frames, result.num_frames, 1))
        if calibration:
            bad = np.flatnonzero(~((result.score >= 0) & (result.score <= 1)))
            if len(bad):
                raise OcctrackError(f"score (column 18) {result.score[bad[0]]:g} is not a "
                                    f"probability in [0, 1], which --calibration needs",
                                    result.path, int(result.line[bad[0]]))
        for cls, scored in scored_frames(gt, result, n, classes, distance).items():
            results = sequence_results(scored.trackeval)
            entry = per_class[cls]
            entry["raw"].append(results)
            entry["sequences"][name] = {key: summary(results)[key] for key in KEYS}
            if calibration:
                entry["tables"].append(reliability(scored, result.score))
    out = {"protocol": "kitti-bev", "distance": distance, "classes": {}, "notes": notes}
    for cls, entry in per_class.items():
        combined = summary(combined_results(entry["raw"]))
        out["classes"][cls] = {"sequences": entry["sequences"],
                               "combined": {key: combined[key] for key in KEYS}}
        if calibration:
            out["classes"][cls]["calibration"] = pooled(entry["tables"])
    return out
