"""`occtrack demo`: the three occlusion models on a built-in street whose people and detector
are measured on MOT17."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

from occtrack.cli.arguments import positive_int

if TYPE_CHECKING:
    from occtrack.scenarios.street import StreetScene

NAME = "demo"
HELP = "track a built-in street (people and detector measured on MOT17) with none, " \
       "object-wise and measurement-wise occlusion"
DESCRIPTION = """\
Simulate a street seen by an upright camera: people walk past each other, stop, turn back and
wait, at the pace, stop rate and stop length measured on MOT17-04's ground truth; a detector
measured on MOT17-04, -05 and -11 by `occtrack calibrate` (detection probability by visible
share, so a person hidden by more than half is almost never seen; misses that come in runs;
edge noise; scores; false boxes) sees them. Track it with the Poisson multi-Bernoulli tracker,
default settings, under each occlusion model, and print:

  MOTA, IDF1, ID switches   CLEAR MOT and identity scores (motmetrics) against every person
                            in the image, hidden ones included; a match needs IoU >= 0.5
  kept through full occl.   k / n: of the n spells of at least 0.5 s in which a person is more
                            than half hidden by nearer people (seen before and after), the k
                            after which the person's track is the one before (reported boxes
                            and people matched one to one at IoU >= 0.5 each frame)
  false boxes               reported boxes that match no person
  ECE                       expected calibration error of the boxes' confidence (10 bins)
  steps / s                 frames tracked a second, time inside Tracker.step, measured after
                            a warm-up run over the same frames: the steady state, as
                            benchmarks/bench_tracker.py measures it (it varies with the load)

--figure draws one full occlusion (the longest that object-wise occlusion keeps and the
tracker without occlusion does not, if any): before, hidden and after, for none and
object-wise; the hidden person filled orange, tracks held without a detection dotted."""


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
    parser.add_argument("--frames", type=positive_int, default=1800,
                        help="frames at 30 fps (1800: a minute)")
    parser.add_argument("--figure", metavar="PNG", help="draw one full occlusion into this PNG")
    parser.add_argument("--force", action="store_true", help="overwrite an existing figure")
    parser.add_argument("--json", action="store_true", help="print the scores as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from occtrack.experiments.demo import HIDDEN, MIN_SPELL, run_demo, telling_spell
    from occtrack.scenarios.street import Street
    from occtrack.viz.frame import check_new

    if args.figure:
        check_new(args.figure, args.force)
    out = run_demo(Street(people=args.people, frames=args.frames), args.seed, args.quiet)
    scene, scores, detector = out["scene"], out["scores"], out["detector"]
    if args.json:
        print(json.dumps({"detector": detector, "occlusions": len(out["spells"]),
                          "trackers": scores}, indent=2))
    else:
        print(f"Street, seed {args.seed}: {args.people} people in view "
              f"({len(np.unique(scene.truth.id))} in all), {scene.frames} frames at "
              f"{scene.fps:g} fps, every frame tracked, default settings")
        print(f"detector measured on MOT17: recall {detector['recall']:.3f}, precision "
              f"{detector['precision']:.3f}, {detector['false_per_frame']:.2f} false boxes "
              f"a frame")
        print(f"full occlusions (more than {HIDDEN:.0%} hidden for {MIN_SPELL:g} s or more): "
              f"{len(out['spells'])}\n")
        print(f"{'occlusion':<18}{'MOTA':>7}{'IDF1':>7}{'ID switches':>13}"
              f"{'kept through full occlusions':>30}{'false boxes':>13}{'ECE':>7}"
              f"{'steps / s':>11}")
        for name, s in scores.items():
            kept = f"{s['kept']} / {s['occlusions']}"
            print(f"{name:<18}{s['mota']:>7.3f}{s['idf1']:>7.3f}{s['id_switches']:>13d}"
                  f"{kept:>30}{s['false_boxes']:>13d}{s['ece']:>7.3f}"
                  f"{s['steps_per_second']:>11.0f}")
        print("\n(steps / s: after a warm-up run, the steady state; it varies with the load, "
              "the scores do not)")
    if args.figure:
        picked = telling_spell(out)
        _draw(args.figure, out, picked)
        if not args.json:
            where = (f"person {picked[0].person} hidden in frames {picked[0].first}-"
                     f"{picked[0].last}" if picked else "no full occlusion: the middle frame")
            print(f"\n{where} drawn in {args.figure}")
    return 0


def _draw(path: str, out: dict, picked) -> None:
    import numpy as np

    from occtrack.viz.frame import draw_panels

    scene: StreetScene = out["scene"]
    truth = scene.truth
    if picked is None:
        frames, person = [scene.frames // 2 + 1], None
        titles = [f"frame {frames[0]}"]
    else:
        spell, before, after = picked
        frames, person = [before, (spell.first + spell.last) // 2, after], spell.person
        titles = [f"frame {before}: seen", f"frame {frames[1]}: hidden",
                  f"frame {after}: seen again"]
    W, H = scene.image_size
    if person is not None:
        rows = (truth.id == person) & np.isin(truth.frame, frames)
        b = truth.box[rows]
        cx, cy = np.mean(b[:, 0] + b[:, 2] / 2), np.mean(b[:, 1] + b[:, 3] / 2)
    else:
        cx, cy = W / 2, H / 2
    x0, y0 = float(np.clip(cx - W / 6, 0, W * 2 / 3)), float(np.clip(cy - H / 6, 0, H * 2 / 3))
    window = (x0, y0, x0 + W / 3, y0 + H / 3)
    panels = []
    for name in ("none", "object-wise"):
        result = out["results"][name]
        for frame, title in zip(frames, titles, strict=True):
            t, d, r = truth.frame == frame, scene.detections.frame == frame, \
                result.frame == frame
            mine = t & (truth.id == person) if person is not None else np.zeros_like(t)
            panels.append(dict(truth=truth.box[t], detections=scene.detections.box[d],
                               track_ids=result.id[r], track_boxes=result.box[r],
                               track_hidden=result.coasting[r],
                               highlight=truth.box[mine][0] if mine.any() else None,
                               title=f"{name}, {title}"))
    draw_panels(path, scene.image_size, panels, window=window, columns=len(frames),
                caption="a third of the image; people grey (the one hidden filled orange), "
                        "detections dashed magenta, tracks blue with their labels (dotted: "
                        "held without a detection)")
