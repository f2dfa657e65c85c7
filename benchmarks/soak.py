"""Soak: a long stream of the synthetic street through `Tracker.step`, resident memory
sampled every 1,000 frames, and every id checked never to be given to two objects.

    python benchmarks/soak.py [--frames 100000] [--occlusion measurement-wise]

A crowd of random walkers (`occtrack.scenarios.pedestrians.Crowd`, 12 people in view; not
`occtrack demo`'s street) is simulated for 10,000 frames and played
again and again (people then appear and vanish at the seams, which births and deaths must
absorb). Prints resident memory (MiB, from /proc/self/statm) after every 1,000 frames, its
spread after the first 10 % (the warm-up) and frames per second.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from occtrack.scenarios.pedestrians import Crowd, crowd_scene
from occtrack.tracker import Tracker, TrackerConfig


def resident_mib() -> float:
    with open("/proc/self/statm") as fh:
        pages = int(fh.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=100_000)
    parser.add_argument("--occlusion", default="measurement-wise")
    args = parser.parse_args()
    scene = crowd_scene(Crowd(frames=10_000), seed=0)
    slices = scene.detections.frame_slices(scene.frames)
    tracker = Tracker(TrackerConfig(occlusion=args.occlusion, image_size=scene.image_size,
                                    fps=scene.fps))
    owner: dict[int, int] = {}  # id -> the filter's serial of the Bernoulli that holds it
    memory = []
    start = time.perf_counter()
    for frame in range(args.frames):
        rows = slices[frame % len(slices)]
        tracks = tracker.step(scene.detections.box[rows], scene.detections.score[rows])
        if len(np.unique(tracks.ids)) != len(tracks.ids):
            raise SystemExit(f"frame {frame + 1}: an id is given twice")
        f = tracker.filter
        for slot in np.flatnonzero(f.slot_used & (tracker._reported_serial == f.slot_serial)):
            track_id, serial = int(tracker._report_id[slot]), int(f.slot_serial[slot])
            if owner.setdefault(track_id, serial) != serial:
                raise SystemExit(f"frame {frame + 1}: id {track_id} reused")
        if (frame + 1) % 1000 == 0:
            memory.append(resident_mib())
    seconds = time.perf_counter() - start
    settled = np.array(memory[max(1, len(memory) // 10):])
    print(f"soak: {args.frames} frames of the synthetic street ({args.occlusion}), "
          f"{len(owner)} ids, none given twice or reused")
    print("resident MiB every 1000 frames: " + " ".join(f"{m:.1f}" for m in memory))
    print(f"after warm-up: min {settled.min():.1f}, max {settled.max():.1f} MiB, "
          f"spread {settled.max() / settled.min() - 1:.1%}; {args.frames / seconds:.0f} "
          f"frames per second")


if __name__ == "__main__":
    main()
