"""Speed and memory of the PMB box tracker on a synthetic street with 40 pedestrians in view.

    python benchmarks/bench_tracker.py [--frames 600] [--memory-frames 10000] [--repeats 3]

Then the same speed on `occtrack demo`'s street (seed 0, 12 people in view, 30 fps, the
demo's default settings): the figure the demo's steps / s column must match within noise.

Speed: tracked frames (calls of `Tracker.step`) per second for each occlusion model, default
settings (components and labels grow with the scene), time spent inside `step` only. Wall-clock
time is what a user waits; CPU time of this process is printed beside it because the machine
may be shared (other processes slow the wall clock, not the CPU time). The best of --repeats
runs counts.

Memory: the same scene run for --memory-frames tracked frames with tracemalloc on from before
the tracker is built; the memory held by Python and numpy (the tracker's arrays included)
after every 1000 frames, and the peak. Flat means the last figure equals the first.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

from occtrack.scenarios.pedestrians import Crowd, crowd_scene
from occtrack.scenarios.street import Street, street_scene
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig


def frames_of(scene):
    d = scene.detections
    return [(d.box[rows], d.score[rows]) for rows in d.frame_slices(scene.frames)]


def speed(frames, occlusion: str, repeats: int, **settings) -> tuple[float, float, int]:
    best_wall = best_cpu = float("inf")
    for _ in range(repeats):
        tracker = Tracker(TrackerConfig(occlusion=occlusion, frame_step=1, **settings))
        wall = cpu = 0.0
        for boxes, scores in frames:
            w0, c0 = time.perf_counter(), time.process_time()
            tracker.step(boxes, scores)
            wall += time.perf_counter() - w0
            cpu += time.process_time() - c0
        best_wall, best_cpu = min(best_wall, wall), min(best_cpu, cpu)
    return len(frames) / best_wall, len(frames) / best_cpu, tracker.filter.n


def memory(frames, occlusion: str, every: int = 1000) -> list[tuple[int, float, float]]:
    tracemalloc.start()
    tracker = Tracker(TrackerConfig(occlusion=occlusion, frame_step=1))
    marks = []
    for index, (boxes, scores) in enumerate(frames, start=1):
        tracker.step(boxes, scores)
        if index % every == 0:
            current, peak = tracemalloc.get_traced_memory()
            marks.append((index, current / 2**20, peak / 2**20))
    tracemalloc.stop()
    return marks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--memory-frames", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    scene = crowd_scene(Crowd(people=40, frames=args.frames, fps=15.0), seed=args.seed)
    frames = frames_of(scene)
    per_frame = len(scene.detections) / args.frames
    print(f"scene: 40 pedestrians in view, {per_frame:.1f} detections per frame, "
          f"{args.frames} tracked frames at 15 Hz, default settings")
    print(f"{'occlusion':<18}{'frames/s (wall)':>17}{'frames/s (CPU)':>16}{'components':>12}")
    for name in OCCLUSION_NAMES:
        wall, cpu, n = speed(frames, name, args.repeats)
        print(f"{name:<18}{wall:>17.0f}{cpu:>16.0f}{n:>12d}")

    street = street_scene(Street(), seed=0)
    street_frames = frames_of(street)
    print(f"\nthe demo's street (occtrack demo, seed 0): 12 people in view, "
          f"{len(street.detections) / street.frames:.1f} detections per frame, "
          f"{street.frames} frames at 30 fps")
    print(f"{'occlusion':<18}{'frames/s (wall)':>17}{'frames/s (CPU)':>16}{'components':>12}")
    for name in OCCLUSION_NAMES:
        wall, cpu, n = speed(street_frames, name, args.repeats,
                             image_size=street.image_size, fps=street.fps)
        print(f"{name:<18}{wall:>17.0f}{cpu:>16.0f}{n:>12d}")

    if args.memory_frames:
        long_scene = crowd_scene(Crowd(people=40, frames=args.memory_frames, fps=15.0),
                                 seed=args.seed)
        long_frames = frames_of(long_scene)
        print(f"\nmemory over {args.memory_frames} tracked frames (tracemalloc, MiB)")
        for name in OCCLUSION_NAMES:
            marks = memory(long_frames, name)
            held = [m[1] for m in marks]
            print(f"{name:<18}held after every 1000 frames: "
                  f"{' '.join(f'{h:.2f}' for h in held)}; peak {max(m[2] for m in marks):.2f};"
                  f" last / first {held[-1] / held[0]:.3f}")
        del long_frames


if __name__ == "__main__":
    main()
