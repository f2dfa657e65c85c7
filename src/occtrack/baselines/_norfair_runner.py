"""Runs inside norfair's own environment (numpy < 2): imports only numpy, json and norfair.

Usage: python _norfair_runner.py IN.npz CONFIG.json OUT.npz

IN.npz holds `frame` (N,), `box` (N, 4: left, top, width, height) and `score` (N,) of the
detections, plus `frames` (the frames to track, increasing). CONFIG.json holds the Tracker
settings and the filter name. OUT.npz gets `frame`, `id` and `box` of the active objects at
each tracked frame. norfair is deterministic, so the same input gives the same output.
"""

import json
import sys

import numpy as np
from norfair import Detection, Tracker
from norfair.filter import FilterPyKalmanFilterFactory, OptimizedKalmanFilterFactory

FILTERS = {"filterpy": FilterPyKalmanFilterFactory, "optimized": OptimizedKalmanFilterFactory}


def main(in_path, config_path, out_path):
    data = np.load(in_path, allow_pickle=False)
    with open(config_path, encoding="utf-8") as fh:
        config = json.load(fh)
    factory = FILTERS[config.pop("filter")]()
    tracker = Tracker(filter_factory=factory, **config)

    frame, box, score = data["frame"], data["box"], data["score"]
    corners = np.concatenate([box[:, :2], box[:, :2] + box[:, 2:]], axis=1)
    frames = data["frames"]
    bounds = np.searchsorted(frame, np.stack([frames, frames + 1]))
    out_frame, out_id, out_box = [], [], []
    previous = frames[0] - 1
    for f, lo, hi in zip(frames, bounds[0], bounds[1], strict=True):
        detections = [Detection(points=corners[k].reshape(2, 2),
                                scores=np.array([score[k], score[k]])) for k in range(lo, hi)]
        objects = tracker.update(detections=detections, period=int(f - previous))
        previous = f
        for obj in objects:
            (x0, y0), (x1, y1) = obj.estimate
            out_frame.append(f)
            out_id.append(obj.id)
            out_box.append((x0, y0, x1 - x0, y1 - y0))
    np.savez(out_path, frame=np.asarray(out_frame, dtype=np.int64),
             id=np.asarray(out_id, dtype=np.int64),
             box=np.asarray(out_box, dtype=np.float64).reshape(-1, 4))


if __name__ == "__main__":
    main(*sys.argv[1:4])
