"""Frames per second of the ground-plane tracker (`track_kitti`) on KITTI's car sequences, against
AB3DMOT's 110 frames/s.

    python benchmarks/bench_ground.py [--data DIR] [--detections pointrcnn]

DIR is a KITTI tracking folder (label_02/, det_02/NAME/ with 3D detections, calib/, poses/,
seqinfo/): --data, else the kitti/ beside the folder $OCCTRACK_DATA names (the data folder's
kitti/, where the tests find it), else ../shared/data/kitti beside this checkout.

Every sequence with a true car (a Car row in label_02/NNNN.txt) is tracked once under each
occlusion model with the default settings (the sequence's frame rate and image size), on its
Car detections alone (AB3DMOT tracks one class at a time), with the sequence's poses (a still
camera where there are none) and calibration: `track_kitti` as `occtrack track --3d` and
`occtrack benchmark` call it. Timed: the `track_kitti` call alone (the files are read before),
one run each, in wall-clock time and in CPU time of this process (the machine may be shared:
other work slows the wall clock, not the CPU time). Printed: per model a table of the
sequences (frames, car detections, frames/s, and the ratio of the wall-clock frames/s to
AB3DMOT's), the whole set's frames over the whole time, then the three models side by side.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from occtrack.experiments import benchmark_kitti
from occtrack.io.kitti import TYPES
from occtrack.tracker import OCCLUSION_NAMES
from occtrack.tracker.ground import ground_config, track_kitti

ROOT = Path(__file__).resolve().parents[1]
AB3DMOT_FPS = 110.0
"""AB3DMOT's frames per second on KITTI's car sequences, the figure measured in issue 40 (a
constant: AB3DMOT is not run here)."""
CAR = TYPES.index("Car")


def data_folder(given: Path | None) -> Path:
    """The KITTI folder: --data, else $OCCTRACK_DATA's sibling kitti/, else the checkout's
    ../shared/data/kitti."""
    tried = [given] if given else []
    if os.environ.get("OCCTRACK_DATA"):
        tried.append(Path(os.environ["OCCTRACK_DATA"]).parent / "kitti")
    tried.append(ROOT.parent / "shared" / "data" / "kitti")
    for folder in tried:
        if benchmark_kitti.is_layout(folder):
            return folder.resolve()
    sys.exit("no KITTI tracking folder (label_02/ and det_02/) found in "
             + ", ".join(str(f) for f in tried) + ": pass --data DIR or set OCCTRACK_DATA")


def car_sequences(root: Path, detections: str) -> list:
    """The sequences with a true car, read with their 3D geometry, Car detections only."""
    out = []
    loaded = [benchmark_kitti.load_sequence(root, detections, name)
              for name in benchmark_kitti.sequence_names(root, detections)]
    three_d, note = benchmark_kitti.has_3d(loaded)
    if not three_d:
        sys.exit(f"det_02/{detections} holds no 3D detections (x y z = -1000)"
                 + (f": {note}" if note else ""))
    for seq in loaded:
        if not np.any((seq.gt.type == CAR) & (seq.gt.id >= 0)):
            continue
        seq = benchmark_kitti.with_geometry(root, seq)
        out.append((seq, seq.table.select(seq.table.type == CAR)))
    return out


def timed(seq, det, occlusion: str) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of one `track_kitti` call with the default settings."""
    config = ground_config({"occlusion": occlusion, "fps": seq.fps,
                            "image_size": (seq.width, seq.height)})
    wall, cpu = time.perf_counter(), time.process_time()
    track_kitti(det, seq.length, config, seq.poses, seq.calibration, (seq.width, seq.height))
    return time.perf_counter() - wall, time.process_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=None,
                        help="the KITTI tracking folder (default: $OCCTRACK_DATA/../kitti, "
                             "else ../shared/data/kitti)")
    parser.add_argument("--detections", default="pointrcnn",
                        help="the 3D detector folder det_02/NAME (default pointrcnn)")
    args = parser.parse_args()
    root = data_folder(args.data)
    detections = benchmark_kitti.pick_detections(root, args.detections)
    runs = car_sequences(root, detections)
    if not runs:
        sys.exit(f"{root}: no sequence has a true car")
    times = {model: [] for model in OCCLUSION_NAMES}
    for seq, det in runs:  # the models in turn on each sequence: a burst of load hits all
        for model in OCCLUSION_NAMES:
            times[model].append(timed(seq, det, model))

    still = [seq.name for seq, _ in runs if seq.poses is None]
    print(f"{root} det_02/{detections}: the ground tracker (track_kitti, default settings) on "
          f"the Car detections of the {len(runs)} sequences with a true car; one run each; "
          f"ratio = wall-clock frames/s / AB3DMOT's {AB3DMOT_FPS:g} (issue 40)"
          + (f"; no poses for {', '.join(still)} (a still camera)" if still else ""))
    total = sum(seq.length for seq, _ in runs)
    overall = {}
    for model in OCCLUSION_NAMES:
        print(f"\n{model}:")
        print(f"  {'sequence':<10}{'frames':>8}{'car dets':>10}{'frames/s':>10}"
              f"{'f/s (CPU)':>11}{'ratio':>8}")
        for (seq, det), (wall, cpu) in zip(runs, times[model], strict=True):
            rate = seq.length / wall
            print(f"  {seq.name:<10}{seq.length:>8}{len(det):>10}{rate:>10.0f}"
                  f"{seq.length / cpu:>11.0f}{rate / AB3DMOT_FPS:>8.2f}")
        wall = sum(t[0] for t in times[model])
        cpu = sum(t[1] for t in times[model])
        overall[model] = (total / wall, total / cpu)
        detected = sum(len(det) for _, det in runs)
        print(f"  {'all':<10}{total:>8}{detected:>10}{total / wall:>10.0f}{total / cpu:>11.0f}"
              f"{total / wall / AB3DMOT_FPS:>8.2f}")
    print(f"\nAll {len(runs)} car sequences, {total} frames (frames over the whole time):")
    print(f"  {'occlusion':<18}{'frames/s':>10}{'f/s (CPU)':>11}{'AB3DMOT':>9}{'ratio':>8}")
    for model, (wall, cpu) in overall.items():
        print(f"  {model:<18}{wall:>10.0f}{cpu:>11.0f}{AB3DMOT_FPS:>9.0f}"
              f"{wall / AB3DMOT_FPS:>8.2f}")


if __name__ == "__main__":
    main()
