"""occtrack's per-frame cost against ByteTrack's, on real detections and in crowds.

    python benchmarks/bench_vs_bytetrack.py [--data DIR] [--repeats 3] [--people 50,200,400]

Both trackers get the same detections, every frame, and only the per-frame call is timed, in
CPU time of this process (the machine may be shared: other work slows the wall clock, not the
CPU time): occtrack's `Tracker.step(boxes, scores)` against `trackers` 2.6.1
`ByteTrackTracker.update(detections)` with library defaults and the sequence's frame rate, the
`supervision.Detections` built beforehand. The trackers run in turn, one whole sequence each,
`--repeats` rounds, and the fastest round of each counts, so that a burst of load on the
machine hits both alike; the ratios are measured in this one run.

1. MOT17-04 and MOT17-11, the public FRCNN detections (`--data`, else $OCCTRACK_DATA or
   ../shared/data/mot17): frames per second of occtrack under each occlusion model and of
   ByteTrack, and their ratio (target: at least 1).
   With `--sets DIR,...` also every sequence of each folder given, a MOTChallenge folder of
   sequences (MOT17's YOLOX-X boxes) or a KITTI tracking folder (its RRC boxes): occtrack's
   default against ByteTrack, and the whole folder's frames over the whole time (issue 37:
   at least ByteTrack's per-frame speed on every set). On KITTI occtrack tracks cars and
   pedestrians in one run, as `occtrack benchmark` does, and ByteTrack one class at a time:
   its time is the sum of the two.
2. Crowds (`occtrack.scenarios.pedestrians`, seed 0): `people` walkers always in view of a
   1920 x 1080 image, boxes 50 to 120 px tall (perspective: feet lower, box taller), 300
   frames at 30 fps, in two kinds:
   - independent misses, issue 10's crowd: every person detected with P_D 0.9, hidden or
     not (there ByteTrack reported 90 % of the people at every size, which only misses
     independent of occlusion give);
   - an occluding crowd: P_D 0.9 only for a person less than 70 % hidden, and non-maximum
     suppression, so a person behind others goes unseen for spells of up to seconds.
   Tracks reported per frame as a % of the people in view (target 95-105 % for occtrack),
   over the whole run and after the first second (when the tracks of the people in view at
   the start are confirmed; the shares below start there too),
   frames per second of both (target: occtrack at least ByteTrack's at 200 and 400 people),
   and how many times the per-frame time grows from the smallest crowd to the largest
   (target: at most 10); then, per crowd, the share of person-frames whose person was detected
   in that frame, within the last `COAST` seconds and ever (what any tracker could report).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from occtrack import peers
from occtrack.io.data import find_sequence
from occtrack.io.mot import read_mot, read_seqinfo
from occtrack.scenarios.pedestrians import (
    MISSED_AT_RANDOM,
    OCCLUDING,
    Detector,
    crowd_scene,
    dense_crowd,
)
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig

DEFAULT = TrackerConfig().occlusion  # the crowds run the defaults
COAST = 0.67  # s: the horizon of the 'recently detected' share


def seen_shares(scene, within: int) -> tuple[float, float, float]:
    """Of the person-frames after the first second: the share whose person is detected in
    that frame (matched one to one at IoU >= 0.5, `occtrack.models.calibration.match`),
    detected within the last `within` frames, and detected at some earlier frame. The last two
    bound what a tracker that holds a person for `within` frames unseen, or for ever, could
    report."""
    from occtrack.models.calibration import match

    truth = scene.truth
    detected = match(truth, scene.detections, scene.frames).gt_match >= 0
    last: dict[int, int] = {}
    gaps = []
    for frame, rows in enumerate(truth.frame_slices(scene.frames)):
        for person in truth.id[rows[detected[rows]]]:
            last[int(person)] = frame
        if frame >= scene.fps:
            gaps.extend(frame - last.get(int(person), -10**9) for person in truth.id[rows])
    gaps = np.asarray(gaps)
    return float((gaps == 0).mean()), float((gaps <= within).mean()), float(
        (gaps < 10**8).mean())


CROWDS = {"independent misses, every person detected with P_D 0.9, hidden or not":
          MISSED_AT_RANDOM,
          "an occluding crowd, P_D 0.9 for a person less than 70 % hidden, "
          "non-maximum suppression": OCCLUDING}


def shares_text(shown: list[int], people: int, first: int) -> str:
    """Tracks reported per frame as a % of the people, over the whole run / from frame
    `first` on."""
    return f"{np.mean(shown) / people:.1%} / {np.mean(shown[first:]) / people:.1%}"


def frames_of(det, num_frames: int) -> list[tuple[np.ndarray, np.ndarray]]:
    return [(det.box[rows], det.score[rows]) for rows in det.frame_slices(num_frames)]


def run_occtrack(frames, config: TrackerConfig) -> tuple[float, list[int]]:
    """CPU seconds inside `step` over the whole sequence, and tracks reported per frame."""
    tracker = Tracker(config)
    spent, shown = 0.0, []
    for boxes, scores in frames:
        start = time.process_time()
        tracks = tracker.step(boxes, scores)
        spent += time.process_time() - start
        shown.append(len(tracks))
    return spent, shown


def run_bytetrack(detections, fps: float) -> tuple[float, list[int]]:
    _, trackers = peers.load()
    tracker = trackers.ByteTrackTracker(frame_rate=fps)
    spent, shown = 0.0, []
    for frame in detections:
        start = time.process_time()
        out = tracker.update(frame)
        spent += time.process_time() - start
        ids = out.tracker_id
        shown.append(0 if ids is None else int((ids >= 0).sum()))
    return spent, shown


def sv_frames(frames):
    sv, _ = peers.load()
    out = []
    for boxes, scores in frames:
        if len(boxes):
            xyxy = np.concatenate([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]], axis=1)
            out.append(sv.Detections(xyxy=xyxy, confidence=scores.astype(float)))
        else:
            out.append(sv.Detections.empty())
    return out


def race(frames, size, fps: float, models, repeats: int) -> dict[str, tuple[float, list]]:
    """Fastest of `repeats` rounds for each tracker, the trackers taking turns."""
    detections = sv_frames(frames)
    best: dict[str, tuple[float, list]] = {}
    for _ in range(repeats):
        for name in (*models, "bytetrack"):
            if name == "bytetrack":
                spent, shown = run_bytetrack(detections, fps)
            else:
                config = TrackerConfig(occlusion=name, image_size=size, fps=fps)
                spent, shown = run_occtrack(frames, config)
            if name not in best or spent < best[name][0]:
                best[name] = (spent, shown)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="folder of the MOT17 sequence folders")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--people", default="50,200,400",
                        help="crowd sizes, comma-separated (\"\": no crowds)")
    parser.add_argument("--frames", type=int, default=300, help="crowd frames")
    parser.add_argument("--skip-mot17", action="store_true")
    parser.add_argument("--sets", default="", help="more data sets: MOTChallenge folders of "
                        "sequences or KITTI tracking folders, comma-separated")
    args = parser.parse_args()
    peers.load()

    if not args.skip_mot17:
        print("Real detections, every frame, per-frame call in CPU time "
              f"(fastest of {args.repeats} rounds):")
        print(f"  {'sequence':<10}{'tracker':<18}{'frames/s':>10}{'ByteTrack':>11}{'ratio':>8}")
        for name in ("MOT17-04-FRCNN", "MOT17-11-FRCNN"):
            folder = find_sequence(args.data, name)
            info = read_seqinfo(folder)
            det = read_mot(folder / "det" / "det.txt", "det")
            n, fps = int(info["length"]), float(info["fps"])
            frames = frames_of(det, n)
            best = race(frames, (int(info["width"]), int(info["height"])), fps,
                        OCCLUSION_NAMES, args.repeats)
            bt = n / best["bytetrack"][0]
            for model in OCCLUSION_NAMES:
                rate = n / best[model][0]
                print(f"  {name[:8]:<10}{model:<18}{rate:>10.0f}{bt:>11.0f}{rate / bt:>8.2f}")

    for root in (r for r in args.sets.split(",") if r):
        set_table(Path(root), args.repeats)

    people = [int(p) for p in args.people.split(",") if p]  # (--people "": no crowds)
    for title, detector in CROWDS.items() if people else ():
        crowd_table(title, detector, people, args.frames, args.repeats)


def kitti_race(seq, repeats: int) -> tuple[float, float]:
    """(occtrack's CPU seconds, ByteTrack's) on a KITTI sequence, fastest of `repeats`:
    occtrack with every class in one run, ByteTrack a class at a time (cars and pedestrians,
    as `occtrack benchmark` runs it), its two times summed."""
    det = seq.det
    rows = list(det.frame_slices(seq.length))
    frames = [(det.box[r], det.score[r], det.cls[r]) for r in rows]
    config = TrackerConfig(image_size=(seq.width, seq.height), fps=seq.fps)
    per_class = [sv_frames([(det.box[r][det.cls[r] == c], det.score[r][det.cls[r] == c])
                            for r in rows]) for c in (0, 3)]
    best_occ = best_bt = float("inf")
    for _ in range(repeats):
        tracker = Tracker(config)
        spent = 0.0
        for boxes, scores, classes in frames:
            start = time.process_time()
            tracker.step(boxes, scores, classes=classes)
            spent += time.process_time() - start
        best_occ = min(best_occ, spent)
        best_bt = min(best_bt, sum(run_bytetrack(d, seq.fps)[0] for d in per_class))
    return best_occ, best_bt


def set_table(root: Path, repeats: int) -> None:
    """occtrack's default against ByteTrack on every sequence of a data set folder."""
    from occtrack.experiments import benchmark as mot_benchmark
    from occtrack.experiments import benchmark_kitti

    print(f"\n{root.resolve().name}: occtrack's default ({DEFAULT} occlusion) against "
          f"ByteTrack, per-frame call in CPU time (fastest of {repeats} rounds):")
    print(f"  {'sequence':<18}{'frames':>8}{'occtrack f/s':>14}{'ByteTrack f/s':>15}"
          f"{'ratio':>8}")
    total = [0, 0.0, 0.0]
    if benchmark_kitti.is_layout(root):
        base = root.resolve()
        detections = benchmark_kitti.pick_detections(base, None)
        runs = ((name, benchmark_kitti.load_sequence(base, detections, name))
                for name in benchmark_kitti.sequence_names(base, detections))
        timed = ((name, seq.length, *kitti_race(seq, repeats)) for name, seq in runs)
    else:
        def mot_runs():
            for folder in mot_benchmark.find_sequences(root):
                seq = mot_benchmark.load_sequence(folder)
                best = race(frames_of(seq.det, seq.length), (seq.width, seq.height), seq.fps,
                            (DEFAULT,), repeats)
                yield seq.name, seq.length, best[DEFAULT][0], best["bytetrack"][0]
        timed = mot_runs()
    for name, frames, occ, bt in timed:
        total[0] += frames
        total[1] += occ
        total[2] += bt
        print(f"  {name:<18}{frames:>8}{frames / occ:>14.0f}{frames / bt:>15.0f}"
              f"{bt / occ:>8.2f}")
    print(f"  {'all':<18}{total[0]:>8}{total[0] / total[1]:>14.0f}"
          f"{total[0] / total[2]:>15.0f}{total[2] / total[1]:>8.2f}")


def crowd_table(title: str, detector: Detector, people: list[int], num_frames: int,
                repeats: int) -> None:
    print(f"\nCrowds: {title}; 1920 x 1080, boxes 50-120 px tall, {num_frames} frames, "
          f"occtrack defaults ({DEFAULT} occlusion):")
    print(f"  {'people':>6}{'dets/frame':>12}{'occtrack tracks':>17}{'ByteTrack tracks':>18}"
          f"{'occtrack f/s':>14}{'ByteTrack f/s':>15}{'ratio':>7}  (tracks: whole run / after "
          f"the first second)")
    per_frame, shares = {}, {}
    for count in people:
        scene = crowd_scene(dense_crowd(count, num_frames, detector=detector), seed=0)
        frames = frames_of(scene.detections, scene.frames)
        best = race(frames, scene.image_size, scene.fps, (DEFAULT,), repeats)
        occ, bt = best[DEFAULT], best["bytetrack"]
        per_frame[count] = (occ[0] / scene.frames, bt[0] / scene.frames)
        first = round(scene.fps)
        print(f"  {count:>6}{len(scene.detections) / scene.frames:>12.1f}"
              f"{shares_text(occ[1], count, first):>17}{shares_text(bt[1], count, first):>18}"
              f"{scene.frames / occ[0]:>14.0f}{scene.frames / bt[0]:>15.0f}"
              f"{bt[0] / occ[0]:>7.2f}")
        shares[count] = seen_shares(scene, round(COAST * scene.fps))
    low, high = min(people), max(people)
    if low != high:
        print(f"  per-frame time from {low} to {high} people: occtrack "
              f"{per_frame[high][0] / per_frame[low][0]:.1f} x, ByteTrack "
              f"{per_frame[high][1] / per_frame[low][1]:.1f} x")
    print("  person-frames (after the first second) detected in that frame / within the "
          f"{COAST} s before / ever:")
    for count, (now, recent, ever) in shares.items():
        print(f"  {count:>6}{now:>10.1%}{recent:>10.1%}{ever:>10.1%}")


if __name__ == "__main__":
    main()
