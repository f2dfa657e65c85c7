"""Gating changes the cost, not the tracks: every mot17 metric with gating on and off.

    python benchmarks/bench_gating.py [--data DIR] [--sequences MOT17-04-FRCNN,MOT17-11-FRCNN]

Each occlusion model, default settings, on the public FRCNN detections (`--data`, else
$OCCTRACK_DATA or ../shared/data/mot17), once with `gating = true` (the default: likelihoods,
occlusion geometry and loopy BP only over the pairs that can interact) and once with
`gating = false` (every pair). Problems of at most `occtrack.spatial.DENSE_PAIRS` pairs are
computed whole even when gating is on (it is faster, and exact); MOT17-11's frames are mostly
that small, so a third run gates every frame ("always"). Prints HOTA, IDF1, MOTA, DetA, AssA,
LocA under the `mot17` protocol (TrackEval) for each, the largest difference from `off`
(target: at most 0.002), the largest difference of any reported box and existence, and the
tracking rate.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import occtrack.filters.gmpmb
import occtrack.occlusion.box_geometry
import occtrack.spatial
import occtrack.tracker.camera
from occtrack.experiments.benchmark import load_sequence
from occtrack.io.data import find_sequence
from occtrack.io.mot import MotTable
from occtrack.metrics.protocols import scored_frames
from occtrack.metrics.trackeval_mot17 import sequence_results, summary
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig

METRICS = ("hota", "idf1", "mota", "deta", "assa", "loca")


SMALL = (occtrack.filters.gmpmb, occtrack.occlusion.box_geometry, occtrack.spatial,
         occtrack.tracker.camera)  # the modules with a small-problem shortcut


def run(seq, occlusion: str, gating: str):
    config = TrackerConfig(occlusion=occlusion, image_size=(seq.width, seq.height),
                           fps=seq.fps, gating=gating != "off")
    saved = [module.DENSE_PAIRS for module in SMALL]
    if gating == "always":
        for module in SMALL:
            module.DENSE_PAIRS = 0
    try:
        start = time.process_time()
        out = Tracker(config).run(seq.det, seq.length)
        seconds = time.process_time() - start
    finally:
        for module, value in zip(SMALL, saved, strict=True):
            module.DENSE_PAIRS = value
    n = len(out.frame)
    table = MotTable(out.frame, out.id, out.box, out.existence, np.full(n, -1),
                     np.full(n, -1.0), "<occtrack>")
    scores = summary(sequence_results(scored_frames(seq.gt, table, "mot17",
                                                    seq.length).trackeval))
    return out, scores, seq.length / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None)
    parser.add_argument("--sequences", default="MOT17-04-FRCNN,MOT17-11-FRCNN")
    args = parser.parse_args()
    print(f"{'sequence':<10}{'occlusion':<18}{'gating':<7}"
          + "".join(f"{m.upper():>7}" for m in METRICS) + f"{'frames/s':>10}")
    worst = 0.0
    for name in args.sequences.split(","):
        seq = load_sequence(find_sequence(args.data, name))
        for occlusion in OCCLUSION_NAMES:
            runs = {gating: run(seq, occlusion, gating) for gating in ("on", "always", "off")}
            for gating, (_, scores, rate) in runs.items():
                print(f"{name[:8]:<10}{occlusion:<18}{gating:<7}"
                      + "".join(f"{scores[m]:>7.3f}" for m in METRICS) + f"{rate:>10.0f}")
            off, s_off, _ = runs["off"]
            for gating in ("on", "always"):
                on, s_on, _ = runs[gating]
                diff = max(abs(s_on[m] - s_off[m]) for m in METRICS)
                worst = max(worst, diff)
                same = len(on.id) == len(off.id) and (on.id == off.id).all() and (
                    on.frame == off.frame).all()
                detail = (f"boxes within {np.abs(on.box - off.box).max():.1e} px, existence "
                          f"within {np.abs(on.existence - off.existence).max():.1e}" if same
                          else f"{len(on.id)} against {len(off.id)} reported boxes")
                print(f"{'':<10}{'':<18}{gating[:2] + '-off':<7}"
                      + "".join(f"{abs(s_on[m] - s_off[m]):>7.3f}" for m in METRICS)
                      + f"   ids {'identical' if same else 'differ'}; {detail}")
    print(f"largest metric difference, gating on against off: {worst:.4f} (target <= 0.002)")


if __name__ == "__main__":
    main()
