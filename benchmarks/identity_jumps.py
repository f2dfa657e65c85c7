"""Identity jumps after a gap: how often a track lost for a while comes back on someone else.

    python benchmarks/identity_jumps.py [--data DIR] [--sequences MOT17-04-FRCNN,...]

Each occlusion model, default settings, on the public FRCNN detections (`--data`, else
$OCCTRACK_DATA or ../shared/data/mot17). Every frame, the reported boxes are matched one to one
to the pedestrians of the ground truth (class 1, not ignored) by IoU, at least 0.5 (Hungarian);
a jump is a track matched to one person and, at its next match, to another. Printed by the
number of frames since the track's previous match: 1 (a swap between neighbours), 2 to 10, and
more than 10 (a track that lost its person and came back on another one: the failure an
occlusion model invites when it keeps a hidden object alive).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.experiments.benchmark import load_sequence
from occtrack.io.data import find_sequence
from occtrack.spatial import iou
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig

SEQUENCES = "MOT17-04-FRCNN,MOT17-11-FRCNN,MOT17-05-FRCNN"


def gaps_of_jumps(sequence, occlusion: str) -> np.ndarray:
    """Frames since the previous match, for every jump of every track."""
    config = TrackerConfig(occlusion=occlusion, image_size=(sequence.width, sequence.height),
                           fps=sequence.fps)
    tracker = Tracker(config)
    gt, det = sequence.gt, sequence.det
    people = (gt.cls == 1) & (gt.score > 0)
    last: dict[int, tuple[int, int]] = {}  # track id -> (person, frame)
    gaps = []
    truth = gt.frame_slices(sequence.length)
    for frame, rows in enumerate(det.frame_slices(sequence.length)):
        tracks = tracker.step(det.box[rows], det.score[rows])
        present = truth[frame][people[truth[frame]]]
        if len(present) == 0 or len(tracks.ids) == 0:
            continue
        overlap = iou(gt.box[present], tracks.boxes)
        for a, b in zip(*linear_sum_assignment(-overlap), strict=True):
            if overlap[a, b] < 0.5:
                continue
            track, person = int(tracks.ids[b]), int(gt.id[present[a]])
            if track in last and last[track][0] != person:
                gaps.append(frame - last[track][1])
            last[track] = (person, frame)
    return np.array(gaps, dtype=int)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="folder of the MOT17 sequence folders")
    parser.add_argument("--sequences", default=SEQUENCES)
    args = parser.parse_args()
    print(f"{'sequence':<16}{'occlusion':<18}{'jumps':>6}{'gap 1':>7}{'2-10':>6}{'> 10':>6}")
    for name in args.sequences.split(","):
        sequence = load_sequence(find_sequence(args.data, name))
        for occlusion in OCCLUSION_NAMES:
            gaps = gaps_of_jumps(sequence, occlusion)
            print(f"{name:<16}{occlusion:<18}{len(gaps):>6}{int((gaps == 1).sum()):>7}"
                  f"{int(((gaps > 1) & (gaps <= 10)).sum()):>6}{int((gaps > 10).sum()):>6}")


if __name__ == "__main__":
    main()
