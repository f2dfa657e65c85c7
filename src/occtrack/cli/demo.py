"""`occtrack demo`: the three occlusion models on a built-in synthetic street scene."""

from __future__ import annotations

import argparse
import json
import time
import warnings
from typing import TYPE_CHECKING

from occtrack.cli.arguments import positive_int

if TYPE_CHECKING:
    import numpy as np

    from occtrack.scenarios.pedestrians import Scene
    from occtrack.tracker import TrackResult

NAME = "demo"
HELP = "track a built-in synthetic street scene with none, object-wise and measurement-wise " \
       "occlusion"
DESCRIPTION = """\
Simulate a street seen by an upright camera (people crossing behind each other; a detector that
misses people, suppresses boxes overlapped by a stronger box as non-maximum suppression does,
and makes a few false positives), track it with the Poisson multi-Bernoulli tracker under each
occlusion model, and print the scores:

  MOTA, IDF1, ID switches   CLEAR MOT and identity scores (motmetrics), a match needs IoU >= 0.5
  GOSPA / frame             GOSPA with 1 - IoU, c = 1, p = 1, alpha = 2, averaged over frames
  tracks                    distinct track ids the tracker reported (compare with the
                            number of people in the ground truth: extra ids are broken
                            tracks or false ones)
  steps / s                 tracked frames per second of this run

--figure draws one frame (ground truth grey, detections dashed magenta, tracks blue with their
labels) for the tracker without occlusion and the measurement-wise one."""


def non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text} is negative")
    return value


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seed", type=non_negative_int, default=0, help="scene seed (0)")
    parser.add_argument("--people", type=positive_int, default=12,
                        help="people in view at any time (12)")
    parser.add_argument("--frames", type=positive_int, default=600,
                        help="frames at 30 fps (600)")
    parser.add_argument("--figure", metavar="PNG", help="draw one frame into this PNG file")
    parser.add_argument("--force", action="store_true", help="overwrite an existing figure")
    parser.add_argument("--frame", type=positive_int, default=None,
                        help="frame to draw (default: a tracked frame where occlusion "
                             "reasoning finds hidden people that the plain tracker loses)")
    parser.add_argument("--json", action="store_true", help="print the scores as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")


def score(scene: Scene, result: TrackResult) -> dict:
    """MOTA, IDF1 and ID switches (motmetrics, IoU >= 0.5) and GOSPA per frame."""
    import motmetrics as mm
    import numpy as np

    from occtrack.metrics.gospa import gospa, iou

    acc = mm.MOTAccumulator(auto_id=True)
    total = 0.0
    truth, res = scene.truth, result
    t_rows, r_rows = truth.frame_slices(scene.frames), _slices(res.frame, scene.frames)
    for t, r in zip(t_rows, r_rows, strict=True):
        distance = 1.0 - iou(truth.box[t], res.box[r])
        total += gospa(truth.box[t], res.box[r], "iou", c=1.0, p=1.0).total
        acc.update(truth.id[t], res.id[r], np.where(distance <= 0.5, distance, np.nan))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        summary = mm.metrics.create().compute(
            acc, metrics=["mota", "idf1", "num_switches"], name="demo").iloc[0]
    return {"mota": float(summary["mota"]), "idf1": float(summary["idf1"]),
            "id_switches": int(summary["num_switches"]), "gospa_per_frame": total / scene.frames,
            "tracks": result.num_tracks}


def _slices(frames: np.ndarray, n: int) -> list[np.ndarray]:
    import numpy as np

    order = np.argsort(frames, kind="stable")
    bounds = np.searchsorted(frames[order], np.arange(1, n + 2))
    return [order[bounds[f]:bounds[f + 1]] for f in range(n)]


def detector_figures(scene: Scene) -> dict:
    """Recall and precision of the detections against the truth (IoU >= 0.5)."""
    from scipy.optimize import linear_sum_assignment

    from occtrack.metrics.gospa import iou

    matched = 0
    for t, d in zip(scene.truth.frame_slices(scene.frames),
                    scene.detections.frame_slices(scene.frames), strict=True):
        if len(t) and len(d):
            overlap = iou(scene.truth.box[t], scene.detections.box[d])
            rows, cols = linear_sum_assignment(-overlap)
            matched += int((overlap[rows, cols] >= 0.5).sum())
    return {"recall": matched / max(len(scene.truth), 1),
            "precision": matched / max(len(scene.detections), 1)}


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from occtrack.scenarios.pedestrians import Crowd, crowd_scene
    from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig
    from occtrack.viz.frame import check_new

    if args.figure:
        check_new(args.figure, args.force)
    crowd = Crowd(people=args.people, frames=args.frames)
    scene = crowd_scene(crowd, seed=args.seed)
    results, scores = {}, {}
    for name in OCCLUSION_NAMES:
        config = TrackerConfig(occlusion=name, image_size=scene.image_size, fps=scene.fps)
        start = time.perf_counter()
        results[name] = Tracker(config).run(scene.detections, scene.frames, quiet=args.quiet,
                                            desc=name)
        seconds = time.perf_counter() - start
        scores[name] = score(scene, results[name])
        scores[name]["steps_per_second"] = -(-scene.frames // config.frame_step) / seconds
    detector = detector_figures(scene)
    if args.json:
        print(json.dumps({"detector": detector, "trackers": scores}, indent=2))
    else:
        print(f"Synthetic street, seed {args.seed}: {args.people} people in view, "
              f"{scene.frames} frames at {scene.fps:g} fps, every frame tracked")
        print(f"ground truth: {len(np.unique(scene.truth.id))} people in all; detector: "
              f"recall {detector['recall']:.3f}, precision {detector['precision']:.3f}\n")
        print(f"{'occlusion':<18}{'MOTA':>7}{'IDF1':>7}{'ID switches':>13}"
              f"{'GOSPA / frame':>15}{'tracks':>8}{'steps / s':>11}")
        for name, s in scores.items():
            print(f"{name:<18}{s['mota']:>7.3f}{s['idf1']:>7.3f}{s['id_switches']:>13d}"
                  f"{s['gospa_per_frame']:>15.3f}{s['tracks']:>8d}"
                  f"{s['steps_per_second']:>11.0f}")
    if args.figure:
        frame = args.frame or _telling_frame(scene, results)
        _draw(args.figure, scene, results, frame)
        if not args.json:
            print(f"\nframe {frame} drawn in {args.figure}")
    return 0


def _hidden(scene: Scene) -> np.ndarray:
    """Truth rows of people inside the image but mostly hidden by others."""
    W, H = scene.image_size
    b = scene.truth.box
    inside = (b[:, 0] >= 0) & (b[:, 1] >= 0) & (b[:, 0] + b[:, 2] <= W) & (b[:, 1] + b[:, 3] <= H)
    return inside & (scene.truth.visibility < 0.3)


def _telling_frame(scene: Scene, results: dict) -> int:
    """A tracked frame where the measurement-wise tracker covers the most hidden people that
    the tracker without occlusion does not (ties: the most hidden people)."""
    import numpy as np

    from occtrack.metrics.gospa import iou

    hidden = _hidden(scene)
    best, best_key = 1, (-1, -1)
    for f in range(1, scene.frames + 1, 2):
        rows = np.flatnonzero(hidden & (scene.truth.frame == f))
        if not len(rows):
            continue
        found = []
        for name in ("measurement-wise", "none"):
            r = results[name].frame == f
            overlap = iou(scene.truth.box[rows], results[name].box[r])
            found.append(int((overlap.max(axis=1, initial=0.0) >= 0.3).sum()))
        key = (found[0] - found[1], len(rows))
        if key > best_key:
            best, best_key = f, key
    return best


def _window(scene: Scene, frame: int) -> tuple[float, float, float, float]:
    """A quarter of the image around the frame's hidden people (or its centre)."""
    import numpy as np

    W, H = scene.image_size
    rows = np.flatnonzero(_hidden(scene) & (scene.truth.frame == frame))
    if len(rows):
        b = scene.truth.box[rows]
        cx, cy = np.mean(b[:, 0] + b[:, 2] / 2), np.mean(b[:, 1] + b[:, 3] / 2)
    else:
        cx, cy = W / 2, H / 2
    x0 = float(np.clip(cx - W / 4, 0, W / 2))
    y0 = float(np.clip(cy - H / 4, 0, H / 2))
    return x0, y0, x0 + W / 2, y0 + H / 2


def _draw(path: str, scene: Scene, results: dict, frame: int) -> None:
    from occtrack.viz.frame import draw_panels

    t = scene.truth.frame == frame
    d = scene.detections.frame == frame
    panels = []
    for name in ("none", "measurement-wise"):
        r = results[name].frame == frame
        panels.append(dict(truth=scene.truth.box[t], detections=scene.detections.box[d],
                           track_ids=results[name].id[r], track_boxes=results[name].box[r],
                           title=f"occlusion: {name}"))
    draw_panels(path, scene.image_size, panels, window=_window(scene, frame),
                caption=f"frame {frame} (a quarter of the image): truth grey, detections "
                        f"dashed magenta, tracks blue with their labels")
