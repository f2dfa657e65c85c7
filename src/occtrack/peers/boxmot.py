"""boxmot 25.0.0's box-only trackers: one function each, MotTable in, MotTable out.

boxmot (PyPI `boxmot`) holds the strongest trackers a user reaches for after Roboflow's, one of
them built for occlusion: OccluBoost (BoostTrack with Kalman-gain damping on the motion spikes
of partial occlusion). Each runs as a user would run it on detections alone: the tracker's own
YAML defaults (`boxmot.create_tracker`), appearance off (`use_embeddings = False`: no ReID
weights), camera-motion compensation off (it needs the frames; with a blank image it would
estimate nothing at a cost), the sequence's frame rate where the tracker takes one, and every
detection row given as `[x1, y1, x2, y2, score, 0]` with a blank image of the sequence's size
(boxmot's update asks for one). A track's row is the box boxmot returns for it in that frame.

Left out: StrongSORT, which is appearance matching and nothing without its ReID weights, and
SAM2MOT, which tracks by segmentation masks from images. boxmot brings torch (about 3 GB with
its CUDA libraries), so it is its own extra, `pip install "occtrack[boxmot]"`, kept out of
`peers` and `all`.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.peers.rows import check_length, check_run, empty_table, result_table

INSTALL_HINT = 'install it with: pip install "occtrack[boxmot]" (about 3 GB: torch)'


def available() -> bool:
    """Whether boxmot can be imported."""
    return importlib.util.find_spec("boxmot") is not None


def load():
    """Import boxmot (a few seconds the first time: torch), or say how to install it."""
    try:
        import boxmot
        from boxmot.trackers.specs import TrackerSpec
    except ImportError as err:
        raise OcctrackError(f"the boxmot peer trackers need the `boxmot` package ({err}); "
                            f"{INSTALL_HINT}") from None
    return boxmot, TrackerSpec


# tracker name in boxmot -> the options that make it box-only (beside its YAML defaults)
BOX_ONLY = {
    "occluboost": {"use_embeddings": False, "use_cmc": False},
    "botsort": {"use_embeddings": False, "use_cmc": False},
    "boosttrack": {"use_embeddings": False, "use_cmc": False},  # BoostTrack++ by default
    "bytetrack": {},
    "ocsort": {},
    "sfsort": {},
    "hybridsort": {"use_embeddings": False, "cmc_method": None},
    "deepocsort": {"use_embeddings": False, "cmc_off": True},
}
FRAME_RATE = ("botsort", "bytetrack")
"""The trackers whose settings take the frame rate (`frame_rate`)."""


def _create(name: str, fps: float):
    boxmot, TrackerSpec = load()
    options = dict(BOX_ONLY[name])
    if name in FRAME_RATE:
        options["frame_rate"] = int(round(fps))
    return boxmot.create_tracker(TrackerSpec(name=name, options=tuple(sorted(options.items()))))


def _run(name: str, det: MotTable, num_frames: int, fps: float,
         image_size: tuple[int, int]) -> MotTable:
    """Feed frames 1..num_frames to boxmot's tracker `name`; every row it returns."""
    check_run(num_frames, fps)
    check_length(det, num_frames)
    tracker = _create(name, fps)
    width, height = (max(int(round(v)), 1) for v in image_size)
    blank = np.zeros((height, width, 3), np.uint8)
    rows = np.zeros((len(det), 6))
    rows[:, :2] = det.box[:, :2]
    rows[:, 2:4] = det.box[:, :2] + det.box[:, 2:]
    rows[:, 4] = np.clip(det.score.astype(float), 0.0, 1.0)  # (boxmot wants [0, 1])
    frames, ids, boxes, scores = [], [], [], []
    for frame, index in enumerate(det.frame_slices(num_frames), start=1):
        out = np.asarray(tracker.update(rows[index], blank), dtype=float).reshape(-1, 8)
        if len(out):  # x1, y1, x2, y2, id, confidence, class, detection index
            frames.append(np.full(len(out), frame))
            ids.append(out[:, 4].astype(np.int64))
            boxes.append(np.concatenate([out[:, :2], out[:, 2:4] - out[:, :2]], axis=1))
            scores.append(out[:, 5])
    if not frames:
        return empty_table()
    return result_table(np.concatenate(frames), np.concatenate(ids), np.concatenate(boxes),
                        np.concatenate(scores))


def _peer(name: str, doc: str) -> Callable[..., MotTable]:
    def run(det: MotTable, num_frames: int, fps: float,
            image_size: tuple[int, int] = (1920, 1080)) -> MotTable:
        return _run(name, det, num_frames, fps, image_size)
    run.__name__ = run.__qualname__ = name
    run.__doc__ = doc
    return run


occluboost = _peer("occluboost", "OccluBoost: BoostTrack with Kalman-gain damping on the "
                   "motion spikes of partial occlusion.")
botsort = _peer("botsort", "BoT-SORT (Aharon et al. 2022), boxmot's, without appearance "
                "and camera motion.")
boosttrack = _peer("boosttrack", "BoostTrack++ (Stanojevic and Todorovic 2024): detection "
                   "confidence boosting and soft box similarity.")
bytetrack = _peer("bytetrack", "ByteTrack (Zhang et al. 2022), boxmot's.")
ocsort = _peer("ocsort", "OC-SORT (Cao et al. 2023), boxmot's.")
sfsort = _peer("sfsort", "SFSORT (Morsali et al. 2024): two-stage matching with "
               "scene-dependent thresholds.")
hybridsort = _peer("hybridsort", "Hybrid-SORT (Yang et al. 2024): weak cues (confidence, "
                   "height) beside IoU, without appearance and camera motion.")
deepocsort = _peer("deepocsort", "Deep OC-SORT (Maggiolino et al. 2023) without its "
                   "appearance and camera-motion parts.")

PEERS: dict[str, Callable[..., MotTable]] = {
    "occluboost": occluboost, "boxmot-botsort": botsort, "boosttrack": boosttrack,
    "boxmot-bytetrack": bytetrack, "boxmot-ocsort": ocsort, "sfsort": sfsort,
    "hybridsort": hybridsort, "deepocsort": deepocsort,
}
"""Every boxmot peer by the name `occtrack benchmark --trackers` takes (boxmot's own version
of a tracker Roboflow's `trackers` also has carries the prefix `boxmot-`)."""
