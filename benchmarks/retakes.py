"""Identities taken back after a track went unseen: right or wrong, by how spread its
prediction was (the evidence behind `identity_spread`).

    python benchmarks/retakes.py [--data DIR] [--frame-steps 1 2 3] [--unseen 1.0]

Each sequence (MOT17-04, -05, -11; `--data`, else $OCCTRACK_DATA or ../shared/data/mot17) is
tracked by the object-wise and measurement-wise trackers with `identity_spread = inf` (no
object is recycled for its spread), at every frame step given. A take-back is a track that
takes a detection after more than `--unseen` seconds without one; its spread is the predicted
centre's standard deviation over its half-size, the larger of the two axes, at that step (what
`identity_spread` compares). It is right when the person the track is matched to at its first
match from then on (within 15 tracked frames) is the person of its last match before, matched
as the mot17 protocol matches (`occtrack.models.calibration.match`, IoU >= 0.5). Printed per
sequence and band of spread: take-backs right / all.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from occtrack.experiments.benchmark import load_sequence
from occtrack.io.data import find_sequence
from occtrack.io.mot import MotTable
from occtrack.models.calibration import match
from occtrack.tracker import Tracker, TrackerConfig

SEQUENCES = ("MOT17-04-FRCNN", "MOT17-05-FRCNN", "MOT17-11-FRCNN")
BANDS = (0.0, 0.6, 0.9, 1.2, 1.5, 2.0, math.inf)
LOOK = 15  # tracked frames after a take-back within which the track must be matched


def take_backs(sequence, occlusion: str, frame_step: int, unseen: float) -> list[tuple]:
    """(spread, right) of every take-back of one run."""
    config = TrackerConfig(occlusion=occlusion, image_size=(sequence.width, sequence.height),
                           fps=sequence.fps, frame_step=frame_step, identity_spread=math.inf)
    tracker = Tracker(config)
    f = tracker.filter
    predicted = {}

    def record() -> None:  # at each step, after the prediction (where the rule would act)
        r, means, centre_std = f.object_moments()
        predicted["spread"] = (centre_std / np.maximum(means[:, :, 2], 1e-9)).max(axis=1)
        predicted["coast"] = f.slot_coast.copy()
        predicted["used"] = f.slot_used.copy()

    f._recycle_unplaced = record
    det = sequence.det
    rows = det.frame_slices(sequence.length)
    events, out = [], {k: [] for k in ("frame", "id", "box")}
    for frame in range(1, sequence.length + 1, frame_step):
        ids_before = tracker._report_id.copy()
        tracks = tracker.step(det.box[rows[frame - 1]], det.score[rows[frame - 1]])
        used, coast = predicted["used"], predicted["coast"]
        for slot in np.flatnonzero(used & (coast > unseen)):
            if (slot < len(ids_before) and ids_before[slot] > 0 and f.slot_used[slot]
                    and f.slot_detection[slot] >= 0):
                events.append((frame, int(ids_before[slot]), float(predicted["spread"][slot])))
        out["frame"].append(np.full(len(tracks), frame))
        out["id"].append(tracks.ids)
        out["box"].append(tracks.boxes)
    n = sum(len(a) for a in out["id"])
    result = MotTable(np.concatenate(out["frame"]), np.concatenate(out["id"]),
                      np.concatenate(out["box"]), np.ones(n), np.full(n, -1),
                      np.full(n, -1.0), "<tracks>")
    truth = sequence.gt
    taken = match(truth, result, sequence.length).gt_match
    matched = np.flatnonzero((taken >= 0) & (truth.cls == 1) & (truth.score != 0))
    person_of = {(int(truth.frame[g]), int(result.id[taken[g]])): int(truth.id[g])
                 for g in matched}
    found = []
    for frame, track_id, spread in events:
        before = next((person_of[(g, track_id)] for g in range(frame - frame_step, 0, -frame_step)
                       if (g, track_id) in person_of), None)
        after = next((person_of[(g, track_id)]
                      for g in range(frame, frame + LOOK * frame_step, frame_step)
                      if (g, track_id) in person_of), None)
        if before is not None and after is not None:
            found.append((spread, before == after))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="folder of the MOT17 sequence folders")
    parser.add_argument("--frame-steps", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--unseen", type=float, default=1.0, help="seconds without a detection")
    args = parser.parse_args()
    bands = [f"{a:g}-{b:g}" for a, b in zip(BANDS[:-1], BANDS[1:], strict=True)]
    print(f"take-backs after more than {args.unseen:g} s unseen (object-wise and "
          f"measurement-wise, frame steps {' '.join(map(str, args.frame_steps))}), right / all "
          f"by the predicted centre's spread in half-sizes\n")
    print(f"{'sequence':<16}" + "".join(f"{b:>10}" for b in bands))
    for name in SEQUENCES:
        sequence = load_sequence(find_sequence(args.data, name))
        found = [e for occlusion in ("object-wise", "measurement-wise")
                 for step in args.frame_steps
                 for e in take_backs(sequence, occlusion, step, args.unseen)]
        spread = np.array([s for s, _ in found])
        right = np.array([r for _, r in found], dtype=bool)
        cells = []
        for a, b in zip(BANDS[:-1], BANDS[1:], strict=True):
            inside = (spread >= a) & (spread < b)
            cells.append(f"{int(right[inside].sum())}/{int(inside.sum())}")
        print(f"{name:<16}" + "".join(f"{c:>10}" for c in cells))


if __name__ == "__main__":
    main()
