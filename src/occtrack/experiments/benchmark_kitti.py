"""occtrack's occlusion models against the box-only peers on a KITTI tracking folder.

The KITTI layout (`DIR/label_02/NNNN.txt`, `DIR/det_02/NAME/NNNN.txt`, `DIR/seqinfo/NNNN.ini`,
`DIR/evaluate_tracking.seqmap`) is recognised by `is_layout`. Every sequence is tracked by
occtrack under each occlusion model and by each peer, and scored by KITTI's own protocol
(TrackEval's `Kitti2DBox`, `occtrack.metrics.trackeval_kitti`) class by class:

- occtrack tracks every class of the detection file in one run, as `occtrack track` does: a
  track keeps its class for life and takes only its class's boxes, and every box hides the
  others for the occlusion models (a van hides the pedestrian behind it whatever its class).
- The peers track one class at a time (their trackers know no classes; this is how users run
  them on KITTI), each class's ids kept apart.

The tables are per class: each sequence, TrackEval's COMBINED_SEQ over the sequences (as KITTI
reports a benchmark) and the plain mean over the sequences that have a true box of the class
(TrackEval gives a sequence without one HOTA 0 whatever the result). ECE is that of the
result's confidence column (a box is right when matched at IoU >= 0.5 to a true box of its
class), pooled over the sequences. Runs go on `occtrack sweep`'s engine, as
`occtrack.experiments.benchmark`'s do.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack import peers
from occtrack.errors import OcctrackError
from occtrack.experiments.benchmark import (
    COLUMNS,
    FRACTIONS,
    MODELS,
    _header,
    _row,
    run_jobs,
)
from occtrack.io.kitti import (
    UNKNOWN_3D,
    KittiTable,
    clip_to_image,
    detections_to_mot,
    read_kitti,
)
from occtrack.io.mot import MotTable, read_seqinfo
from occtrack.metrics.reliability import pooled, reliability
from occtrack.metrics.trackeval_kitti import (
    CLASS_TYPE,
    CLASSES,
    combined_results,
    read_seqmap,
    scored_frames,
    sequence_results,
    summary,
)
from occtrack.tracker import Tracker, TrackerConfig
from occtrack.tracker.boxes import from_ltwh

PROTOCOL = "kitti"
DEFAULT_DETECTIONS = "rrc"  # the 2D detections KITTI's 2D trackers are compared on
COMBINED_METHOD = ("TrackEval COMBINED_SEQ (Kitti2DBox): counts summed over sequences, DetA, "
                   "AssA, LocA and HOTA from the summed counts and HOTA_TP-weighted averages")
MEAN_METHOD = ("plain mean over the sequences with at least one scored true box of the class "
               "of each sequence's number")


def is_layout(root: str | os.PathLike) -> bool:
    """Whether `root` is a KITTI tracking folder (label_02/ and det_02/)."""
    folder = Path(root)
    return (folder / "label_02").is_dir() and (folder / "det_02").is_dir()


def pick_detections(root: Path, name: str | None) -> str:
    """The detector folder under det_02/: `name`, else the only one, else `rrc`."""
    found = sorted(sub.name for sub in (root / "det_02").iterdir() if sub.is_dir())
    if name is not None:
        if name not in found:
            raise OcctrackError(f"no detections {name!r} here; det_02/ holds "
                                f"{', '.join(found) or 'nothing'}", str(root / "det_02"))
        return name
    if len(found) == 1:
        return found[0]
    if DEFAULT_DETECTIONS in found:
        return DEFAULT_DETECTIONS
    raise OcctrackError(f"det_02/ holds {', '.join(found) or 'no detector folder'}; pick one "
                        f"with --detections NAME", str(root / "det_02"))


def sequence_names(root: Path, detections: str) -> list[str]:
    """The sequences to run: those `evaluate_tracking.seqmap` names, else every
    label_02/NNNN.txt; each needs its detection file and seqinfo/NNNN.ini."""
    names = list(read_seqmap(root / "evaluate_tracking.seqmap"))
    if not names:
        names = sorted(p.stem for p in (root / "label_02").glob("*.txt"))
    if not names:
        raise OcctrackError("no sequence here: label_02/ holds no NNNN.txt", str(root))
    for name in names:
        for path in (root / "label_02" / f"{name}.txt",
                     root / "det_02" / detections / f"{name}.txt",
                     root / "seqinfo" / f"{name}.ini"):
            if not path.is_file():
                raise OcctrackError(f"sequence {name} has no {path.parent.name}/{path.name}",
                                    str(path))
    return names


@dataclass(frozen=True)
class Sequence:
    """One KITTI sequence, read: its ground truth and detections (every known class)."""

    name: str
    width: int
    height: int
    fps: int
    length: int
    gt: KittiTable
    det: MotTable  # frames 1-based, cls the KITTI type index


def load_sequence(root: Path, detections: str, name: str) -> Sequence:
    info = read_seqinfo(root / "seqinfo" / f"{name}.ini")
    gt = read_kitti(root / "label_02" / f"{name}.txt")
    det, _, _ = detections_to_mot(read_kitti(root / "det_02" / detections / f"{name}.txt"))
    n = int(info["length"])
    for frames, path in ((gt.num_frames, gt.path), (det.num_frames, det.path)):
        if frames > n:
            raise OcctrackError(f"rows reach frame {frames - 1} but seqinfo says seqLength={n} "
                                f"(frames 0..{n - 1})", path)
    return Sequence(name, int(info["width"]), int(info["height"]), int(info["fps"]), n, gt,
                    det)


_SEQUENCES: dict = {}


def cached_sequence(root: str, detections: str, name: str) -> Sequence:
    """The sequence, read once per process and again when one of its files changed."""
    base = Path(root)
    files = (base / "seqinfo" / f"{name}.ini", base / "label_02" / f"{name}.txt",
             base / "det_02" / detections / f"{name}.txt")
    key = (root, detections, name)
    stamp = tuple(path.stat().st_mtime_ns for path in files)
    cached = _SEQUENCES.get(key)
    if cached is None or cached[0] != stamp:
        _SEQUENCES[key] = (stamp, load_sequence(base, detections, name))
    return _SEQUENCES[key][1]


def result_table(frame, ids, types, ltwh, score, image_size=None) -> KittiTable:
    """Tracker rows (frames 1-based, boxes left, top, width, height) as a KITTI result; with
    `image_size`, boxes clipped to the image as `occtrack track` writes them."""
    n = len(frame)
    box = from_ltwh(ltwh, "xyxy")
    if image_size is not None:
        box = clip_to_image(box, image_size)
    return KittiTable(frame=np.asarray(frame, np.int64) - 1, id=np.asarray(ids, np.int64),
                      type=np.asarray(types, np.int64), truncated=np.full(n, -1.0),
                      occluded=np.full(n, -1.0), alpha=np.full(n, -10.0), box=box,
                      box3d=np.tile(UNKNOWN_3D, (n, 1)), score=np.asarray(score, float),
                      path=f"<{n} result rows>")


def track(name: str, seq: Sequence, classes: tuple[str, ...],
          settings: dict | None = None) -> KittiTable:
    """One tracker on a sequence's boxes of `classes`: occtrack (by occlusion model, with
    `settings` over the defaults) on all of them at once, a peer class by class."""
    types = [CLASS_TYPE[c] for c in classes]
    det = seq.det.select(np.isin(seq.det.cls, types))
    if name in MODELS:
        config = TrackerConfig.from_dict({**(settings or {}), "occlusion": name,
                                          "fps": seq.fps,
                                          "image_size": (seq.width, seq.height)})
        out = Tracker(config).run(det, seq.length, classes=True)
        return result_table(out.frame, out.id, out.classes, out.box, out.confidence,
                            (seq.width, seq.height))
    parts = []
    offset = 0
    for kind in types:
        rows = peers.track_peer(name, det.select(det.cls == kind), seq.length, seq.fps,
                                (seq.width, seq.height))
        parts.append((rows.frame, rows.id + offset, np.full(len(rows), kind), rows.box,
                      rows.score))
        offset += int(rows.id.max(initial=0))
    return result_table(*(np.concatenate([part[i] for part in parts]) for i in range(5)))


@dataclass(frozen=True)
class Job:
    """One task: a tracker on one sequence of a KITTI folder, scored for `classes`."""

    root: str
    detections: str
    sequence: str
    tracker: str
    classes: tuple[str, ...] = CLASSES
    settings: tuple = ()  # (name, value) pairs of TrackerConfig settings for occtrack's models


def run_job(job: Job) -> dict:
    """Track and score one sequence with one tracker: per class TrackEval's results, the
    headline scores and the reliability table."""
    seq = cached_sequence(job.root, job.detections, job.sequence)
    peers.load_for(job.tracker)
    start = time.perf_counter()
    result = track(job.tracker, seq, job.classes, dict(job.settings))
    spent = time.perf_counter() - start
    out = {"seconds": spent, "classes": {}}
    for cls, scored in scored_frames(seq.gt, result, seq.length, job.classes).items():
        results = sequence_results(scored.trackeval)
        calibration = reliability(scored, result.score)
        out["classes"][cls] = {
            "results": results, "calibration": calibration,
            "truth": int(scored.trackeval["num_gt_dets"]),
            "scores": {**summary(results), "ece": calibration.ece,
                       "tracks": int(len(np.unique(result.id[result.type == CLASS_TYPE[cls]]))),
                       "seconds": spent,
                       "frames_per_second": seq.length / max(spent, 1e-9)}}
    return out


def benchmark(root: str | os.PathLike, trackers: list[str], detections: str | None = None,
              classes: tuple[str, ...] = CLASSES, quiet: bool = False, engine=None,
              settings: dict | None = None) -> dict:
    """Track and score every sequence of a KITTI folder with every tracker; the report that
    `occtrack benchmark --json` writes for a KITTI folder. `settings`: TrackerConfig values
    over the defaults for occtrack's models."""
    base = Path(root).resolve()
    if not is_layout(base):
        raise OcctrackError("not a KITTI tracking folder: it needs label_02/ and det_02/",
                            str(root))
    detections = pick_detections(base, detections)
    names = sequence_names(base, detections)
    sequences = [load_sequence(base, detections, name) for name in names]  # checked up front
    for name in trackers:
        peers.load_for(name)
    pairs = tuple(sorted((k, tuple(v) if isinstance(v, list) else v)  # (hashable)
                         for k, v in (settings or {}).items()))

    def job_of(sequence: str, tracker: str) -> Job:
        return Job(str(base), detections, sequence, tracker, tuple(classes), pairs)

    jobs = [job_of(seq.name, name) for seq in sequences for name in trackers]
    done = run_jobs(jobs, engine, quiet, run_job,
                    lambda job: f"{job.tracker} on {job.sequence}")
    report: dict = {"protocol": PROTOCOL, "layout": "kitti", "folder": str(base),
                    "detections": detections, "trackers": list(trackers),
                    "classes": list(classes), "sequences": {},
                    "combined": {"method": COMBINED_METHOD, "classes": {}},
                    "mean": {"method": MEAN_METHOD, "classes": {}}}
    for seq in sequences:
        report["sequences"][seq.name] = {
            "frames": seq.length, "fps": seq.fps, "image_size": [seq.width, seq.height],
            "classes": {cls: {"truth": done[job_of(seq.name, trackers[0])]["classes"][cls]["truth"],
                              "trackers": {}, "calibration": {}} for cls in classes}}
    frames = sum(seq.length for seq in sequences)
    for cls in classes:
        combined = report["combined"]["classes"].setdefault(cls, {"trackers": {},
                                                                  "calibration": {}})
        mean = report["mean"]["classes"].setdefault(cls, {"trackers": {}})
        for name in trackers:
            outs = [done[job_of(seq.name, name)] for seq in sequences]
            per_seq = []
            for seq, out in zip(sequences, outs, strict=True):
                part = out["classes"][cls]
                entry = report["sequences"][seq.name]["classes"][cls]
                entry["trackers"][name] = part["scores"]
                entry["calibration"][name] = part["calibration"].as_dict()
                if part["truth"]:
                    per_seq.append(part["scores"])
            calibration = pooled([out["classes"][cls]["calibration"] for out in outs])
            seconds = sum(out["seconds"] for out in outs)
            combined["calibration"][name] = calibration.as_dict()
            combined["trackers"][name] = {
                **summary(combined_results([out["classes"][cls]["results"] for out in outs])),
                "ece": calibration.ece,
                "tracks": sum(out["classes"][cls]["scores"]["tracks"] for out in outs),
                "seconds": seconds, "frames_per_second": frames / max(seconds, 1e-9)}
            mean["trackers"][name] = {
                key: (float(np.mean([values[key] for values in per_seq])) if per_seq
                      else None) for key in FRACTIONS}
    return report


def format_report(report: dict) -> str:
    """The tables `occtrack benchmark` prints for a KITTI folder: per class one table a
    sequence (only those with a true box of the class), then the combined scores and the
    mean."""
    lines = [f"Protocol kitti (TrackEval Kitti2DBox), detections {report['detections']}; "
             "HOTA, DetA, AssA and LocA are means over the 19 localisation thresholds; "
             "frames/s is the tracker call alone (occtrack: all classes in one run)."]
    count = len(report["sequences"])
    for cls in report["classes"]:
        lines += ["", f"== {cls} =="]
        for name, entry in report["sequences"].items():
            part = entry["classes"][cls]
            if not part["truth"]:
                continue
            w, h = entry["image_size"]
            lines += ["", f"{name} {cls} ({w}x{h}, {entry['fps']} fps, {entry['frames']} "
                          f"frames, {part['truth']} true boxes)", _header()]
            lines += [_row(tracker, values) for tracker, values in part["trackers"].items()]
        lines += ["", f"{cls}, combined over {count} sequences "
                      f"({report['combined']['method']}):", _header()]
        lines += [_row(tracker, values) for tracker, values in
                  report["combined"]["classes"][cls]["trackers"].items()]
        mean_columns = [c for c in COLUMNS if c[0] in FRACTIONS]
        values = report["mean"]["classes"][cls]["trackers"]
        if all(v["hota"] is not None for v in values.values()):
            lines += ["", f"{cls}, mean over sequences ({report['mean']['method']}):",
                      _header(mean_columns)]
            lines += [_row(tracker, v, mean_columns) for tracker, v in values.items()]
    return "\n".join(lines)


__all__ = ["Job", "benchmark", "format_report", "is_layout", "run_job"]
