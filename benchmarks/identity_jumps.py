"""Identity jumps after a gap: how often a track lost for a while comes back on someone else.

    python benchmarks/identity_jumps.py [--data DIR] [--sequences MOT17-04-FRCNN,...]

Each occlusion model, default settings, on the public FRCNN detections (`--data`, else
$OCCTRACK_DATA or ../shared/data/mot17). Every frame, the reported boxes are matched one to one
to the pedestrians of the ground truth at IoU >= 0.5 as the mot17 protocol matches them
(`occtrack.models.calibration.match`); a jump is a track matched to one person and, at its
next match, to another. Printed by the number of frames since the track's previous match: 1
(a swap between neighbours), 2 to 10, and more than 10 (a track that lost its person and came
back on another one: the failure an occlusion model invites when it keeps a hidden object
alive).
"""

from __future__ import annotations

import argparse

import numpy as np

from occtrack.experiments.benchmark import load_sequence, track
from occtrack.io.data import find_sequence
from occtrack.models.calibration import match
from occtrack.tracker import OCCLUSION_NAMES

SEQUENCES = "MOT17-04-FRCNN,MOT17-11-FRCNN,MOT17-05-FRCNN"


def gaps_of_jumps(sequence, occlusion: str) -> np.ndarray:
    """Frames since the previous match, for every jump of every track."""
    result = track(occlusion, sequence)
    truth = sequence.gt
    taken = match(truth, result, sequence.length).gt_match
    matched = np.flatnonzero(taken >= 0)
    ids = result.id[taken[matched]]
    order = np.lexsort((truth.frame[matched], ids))  # by track, then frame
    ids, person, frame = ids[order], truth.id[matched][order], truth.frame[matched][order]
    jump = (ids[1:] == ids[:-1]) & (person[1:] != person[:-1])
    return (frame[1:] - frame[:-1])[jump].astype(int)


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
