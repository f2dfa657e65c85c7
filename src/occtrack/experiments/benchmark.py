"""occtrack's occlusion models against the box-only peers, on every sequence of a folder.

One number per tracker and sequence is what decides whether occlusion reasoning pays: each
sequence is tracked by occtrack under every occlusion model (all other settings the defaults)
and by the peers of `occtrack.peers` (library defaults, the sequence's frame rate), all on the
same detection file, and scored by the same code (`mot17` protocol, TrackEval). The combined
scores are TrackEval's own COMBINED_SEQ, the way MOTChallenge reports a benchmark; the plain
mean over sequences is given beside them, because one identity event in one sequence can move
a combined number.

Each (sequence, tracker) run is one task of `occtrack sweep`'s engine: a Dask LocalCluster
started and stopped here, a running Dask scheduler, or this process (`engine=None`); every
task is deterministic and the report is assembled in the order of the sequences and trackers,
so it does not depend on the engine (the run times aside).

On request the report also keeps what a page of the run needs (`occtrack report`): per frame,
each tracker's GOSPA and its counts of missed and false objects, and the counts of true and
reported objects (`per_frame=True`), and the boxes themselves (`keep_boxes=True`), all on the
boxes the protocol scores.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack import peers
from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable, read_mot, read_seqinfo
from occtrack.metrics.gospa import gospa_from_distances
from occtrack.metrics.protocols import GOSPA_C, GOSPA_P, ScoredFrames, scored_frames
from occtrack.metrics.reliability import pooled, reliability
from occtrack.metrics.trackeval_mot17 import combined_results, sequence_results, summary
from occtrack.progress import progress
from occtrack.tracker import Tracker, TrackerConfig

MODELS = ("none", "measurement-wise", "object-wise")
PROTOCOL = "mot17"
COMBINED_METHOD = ("TrackEval COMBINED_SEQ: counts summed over sequences, DetA, AssA, LocA and "
                   "HOTA from the summed counts and HOTA_TP-weighted averages, as MOTChallenge "
                   "reports a benchmark")
MEAN_METHOD = "plain mean over sequences of each sequence's number"

COLUMNS = (("hota", "HOTA", ".3f"), ("idf1", "IDF1", ".3f"), ("mota", "MOTA", ".3f"),
           ("deta", "DetA", ".3f"), ("assa", "AssA", ".3f"), ("loca", "LocA", ".3f"),
           ("fp", "FP", "d"), ("fn", "FN", "d"), ("id_switches", "IDSW", "d"),
           ("ece", "ECE", ".3f"), ("frames_per_second", "frames/s", ".0f"))
FRACTIONS = ("hota", "idf1", "mota", "deta", "assa", "loca", "motp", "ece")
# The state of a reported box kept with `keep_boxes` (occtrack's trackers only: a peer reports
# the detection boxes its tracks took).
DETECTED, COASTING, OCCLUDED = 0, 1, 2


@dataclass(frozen=True)
class Sequence:
    """One MOTChallenge sequence folder, read."""

    name: str
    folder: Path
    width: int
    height: int
    fps: int
    length: int
    det: MotTable
    gt: MotTable


def all_trackers() -> tuple[str, ...]:
    return MODELS + tuple(peers.ALL_PEERS)


def default_trackers() -> tuple[list[str], str | None]:
    """Every occlusion model, and every peer when `trackers` is installed; the note to print
    when the peers are left out."""
    if peers.available():
        return list(MODELS + tuple(peers.PEERS)), None
    return list(MODELS), ("the peers (" + ", ".join(peers.PEERS) + ") are left out: "
                          + peers.INSTALL_HINT)


def parse_trackers(text: str) -> list[str]:
    """A comma list of tracker names, checked, duplicates dropped, order kept."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    if not names:
        raise OcctrackError("--trackers names no tracker; choose from "
                            + ", ".join(all_trackers()))
    unknown = [name for name in names if name not in all_trackers()]
    if unknown:
        raise OcctrackError(f"unknown tracker {unknown[0]!r}; choose from "
                            + ", ".join(all_trackers()))
    what = peers.missing(names)
    if what:
        raise OcctrackError(what)
    return list(dict.fromkeys(names))


def _is_sequence(folder: Path) -> bool:
    return (folder / "det" / "det.txt").is_file() and (folder / "gt" / "gt.txt").is_file()


def find_sequences(root: str | os.PathLike) -> list[Path]:
    """`root` itself if it is a sequence folder (det/det.txt and gt/gt.txt), else its
    sub-folders that are, by name."""
    folder = Path(root)
    if not folder.is_dir():
        raise OcctrackError("no such folder", str(folder))
    if _is_sequence(folder):
        return [folder]
    found = sorted(sub for sub in folder.iterdir() if sub.is_dir() and _is_sequence(sub))
    if not found:
        raise OcctrackError("no sequence folder here: a sequence folder holds det/det.txt, "
                            "gt/gt.txt and seqinfo.ini (e.g. MOT17-04-FRCNN/)", str(folder))
    return found


def load_sequence(folder: Path) -> Sequence:
    info = read_seqinfo(folder)
    det = read_mot(folder / "det" / "det.txt", "det")
    gt = read_mot(folder / "gt" / "gt.txt", "gt")
    n = int(info["length"])
    for table, what in ((det, "detections"), (gt, "ground truth")):
        if table.num_frames > n:
            raise OcctrackError(f"{what} reach frame {table.num_frames} but seqinfo.ini says "
                                f"seqLength={n}", table.path)
    return Sequence(str(info["name"]), folder, int(info["width"]), int(info["height"]),
                    int(info["fps"]), n, det, gt)


_SEQUENCES: dict = {}


def cached_sequence(folder: str | os.PathLike) -> Sequence:
    """The sequence folder, read once per process (a worker keeps it for later tasks) and
    read again when one of its files changed."""
    path = Path(folder)
    stamp = tuple((path / part).stat().st_mtime_ns
                  for part in ("seqinfo.ini", "det/det.txt", "gt/gt.txt"))
    cached = _SEQUENCES.get(str(path))
    if cached is None or cached[0] != stamp:
        _SEQUENCES[str(path)] = (stamp, load_sequence(path))
    return _SEQUENCES[str(path)][1]


def track(name: str, seq: Sequence, settings: dict | None = None) -> MotTable:
    """Run one tracker, occtrack (by occlusion model, with `settings`: TrackerConfig values
    over the defaults) or a peer, on a whole sequence."""
    return track_with_states(name, seq, settings)[0]


def track_with_states(name: str, seq: Sequence, settings: dict | None = None
                      ) -> tuple[MotTable, np.ndarray | None]:
    """`track`, and for occtrack the state of each result row (DETECTED, COASTING: reported
    without a detection, OCCLUDED: coasting and its miss put down to occlusion); None for a
    peer."""
    if name in MODELS:
        config = TrackerConfig.from_dict({**(settings or {}), "occlusion": name,
                                          "image_size": (seq.width, seq.height),
                                          "fps": seq.fps})
        out = Tracker(config).run(seq.det, seq.length)
        n = len(out.frame)
        states = np.full(n, DETECTED)
        if out.coasting is not None:
            states[out.coasting] = COASTING
        if out.occluded is not None:
            states[out.occluded] = OCCLUDED
        return MotTable(out.frame, out.id, out.box, out.confidence, np.full(n, -1),
                        np.full(n, -1.0), "<occtrack>"), states
    return peers.track_peer(name, seq.det, seq.length, seq.fps, (seq.width, seq.height)), None


def per_frame_counts(frames: ScoredFrames) -> dict:
    """Per frame (entry t is frame t + 1) of scored frames: GOSPA (c = 1, p = 1, alpha = 2,
    1 - IoU, as `occtrack.metrics.evaluate.gospa_per_frame`), its missed and false objects, and
    the number of reported boxes scored."""
    split = [gospa_from_distances(1.0 - iou, GOSPA_C, GOSPA_P) for iou in frames.iou]
    return {"gospa": [round(g.total, 6) for g in split],
            "missed": [g.n_missed for g in split],
            "false": [g.n_false for g in split],
            "estimates": [int(len(rows)) for rows in frames.estimate_rows]}


def _box_rows(table: MotTable, rows: np.ndarray) -> dict:
    """Rows of a table in frame order, as JSON lists: frame, id, and left, top, width,
    height rounded to 0.1 px."""
    rows = rows[np.argsort(table.frame[rows], kind="stable")]
    return {"frame": table.frame[rows].astype(int).tolist(),
            "id": table.id[rows].astype(int).tolist(),
            "ltwh": np.round(table.box[rows], 1).tolist()}


def truth_boxes(frames: ScoredFrames, gt: MotTable) -> dict:
    """The ground-truth boxes the protocol scores, for a viewer."""
    return _box_rows(gt, np.concatenate([np.zeros(0, int), *frames.truth_rows]))


def result_boxes(frames: ScoredFrames, result: MotTable, states: np.ndarray | None) -> dict:
    """Every reported box, for a viewer, with `ignored` (indices of the rows the protocol
    leaves out: matched to a distractor, or of another class) and, for occtrack, each row's
    `state` (DETECTED, COASTING, OCCLUDED)."""
    order = np.argsort(result.frame, kind="stable")
    boxes = _box_rows(result, order)
    scored = np.zeros(len(result), bool)
    scored[np.concatenate([np.zeros(0, int), *frames.estimate_rows]).astype(int)] = True
    boxes["ignored"] = np.flatnonzero(~scored[order]).tolist()
    if states is not None:
        boxes["state"] = states[order].astype(int).tolist()
    return boxes


@dataclass(frozen=True)
class Job:
    """One task of a benchmark: a tracker on a sequence folder, and what to keep."""

    folder: str
    tracker: str
    per_frame: bool = False
    keep_boxes: bool = False
    settings: tuple = ()  # (name, value) pairs of TrackerConfig settings for occtrack's models


def run_job(job: Job) -> dict:
    """Track and score one sequence with one tracker (a task: it reads the folder itself, so
    only the job's text travels to a worker); the parts of the report it makes."""
    seq = cached_sequence(job.folder)
    peers.load_for(job.tracker)
    start = time.perf_counter()
    result, states = track_with_states(job.tracker, seq, dict(job.settings))
    spent = time.perf_counter() - start
    scored = scored_frames(seq.gt, result, PROTOCOL, seq.length)
    results = sequence_results(scored.trackeval)
    calibration = reliability(scored, result.score)
    out = {"results": results,
           "scores": {**summary(results), "ece": calibration.ece,
                      "tracks": int(len(np.unique(result.id))),
                      "seconds": spent, "frames_per_second": seq.length / max(spent, 1e-9)},
           "calibration": calibration}
    if job.per_frame or job.keep_boxes:
        out["truth"] = [int(len(rows)) for rows in scored.truth_rows]
        out["per_frame"] = per_frame_counts(scored)
    if job.keep_boxes:
        out["truth_boxes"] = truth_boxes(scored, seq.gt)
        out["boxes"] = result_boxes(scored, result, states)
    return out


def _run_jobs(jobs: list, engine, runner=None):
    """(job, result, error) as each job finishes: on `engine` (occtrack.experiments.sweep's
    DaskEngine, started by the caller) or, with None, here one after another. `runner`
    (default `run_job`) runs one job."""
    runner = runner or run_job
    if engine is not None:
        yield from engine.map(runner, jobs)
        return
    for job in jobs:
        try:
            yield job, runner(job), None
        except Exception as err:  # noqa: BLE001 - reported with its job, as on Dask
            yield job, None, err


def run_jobs(jobs: list, engine, quiet: bool, runner=None, where=None) -> dict:
    """Every job's result, {job: result}, run on `engine` (started here unless the caller
    started it) or here; once all have finished, an OcctrackError naming each failed run
    (`where(job)` says which: by default the job's tracker and folder)."""
    where = where or (lambda job: f"{job.tracker} on {job.folder}")
    done: dict = {}
    failed: list[str] = []
    with contextlib.ExitStack() as stack:
        if engine is not None:
            if not engine.started:  # else the caller started it and stops it
                stack.enter_context(engine)
            engine.warm("benchmark")
        for job, out, err in progress(_run_jobs(jobs, engine, runner), len(jobs), "benchmark",
                                      quiet):
            if err is not None:
                what = (err.message if isinstance(err, OcctrackError)
                        else f"{type(err).__name__}: {err}")
                failed.append(f"{where(job)}: {what}")
            else:
                done[job] = out
    if failed:
        raise OcctrackError(f"{len(failed)} of {len(jobs)} runs failed (the others finished): "
                            + "; ".join(failed))
    return done


def benchmark(root: str | os.PathLike, trackers: list[str], quiet: bool = False,
              per_frame: bool = False, keep_boxes: bool = False, engine=None,
              settings: dict | None = None) -> dict:
    """Track and score every sequence under `root` with every tracker named; the report that
    `--json` writes (see `occtrack benchmark --help` for its shape). `per_frame` adds each
    sequence's "per_frame" counts, `keep_boxes` its "boxes" (and the counts). `engine`: a
    `occtrack.experiments.sweep.DaskEngine` to run the (sequence, tracker) tasks on (started
    here after the inputs are checked, unless the caller started it), or None for this
    process. `settings`: TrackerConfig values over the defaults for occtrack's models (the
    image size, frame rate and occlusion model are the sequence's and the model's)."""
    per_frame = per_frame or keep_boxes
    folders = find_sequences(root)
    sequences = [load_sequence(folder) for folder in folders]
    names = [seq.name for seq in sequences]
    if len(set(names)) < len(names):
        raise OcctrackError("two sequence folders share a name in seqinfo.ini", str(root))
    for name in trackers:
        peers.load_for(name)
    pairs = tuple(sorted((k, tuple(v) if isinstance(v, list) else v)  # (hashable)
                         for k, v in (settings or {}).items()))
    jobs = [Job(str(seq.folder.resolve()), name, per_frame, keep_boxes, pairs)
            for seq in sequences for name in trackers]
    done = run_jobs(jobs, engine, quiet)
    raw: dict[str, list[dict]] = {name: [] for name in trackers}
    calibrations: dict[str, list] = {name: [] for name in trackers}
    seconds: dict[str, float] = dict.fromkeys(trackers, 0.0)
    report: dict = {"protocol": PROTOCOL, "trackers": list(trackers), "sequences": {}}
    for job, seq in zip(jobs, (seq for seq in sequences for _ in trackers), strict=True):
        name, out = job.tracker, done[job]
        raw[name].append(out["results"])
        calibrations[name].append(out["calibration"])
        seconds[name] += out["scores"]["seconds"]
        entry = report["sequences"].setdefault(seq.name, {
            "folder": str(seq.folder), "frames": seq.length, "fps": seq.fps,
            "image_size": [seq.width, seq.height], "trackers": {}})
        entry["trackers"][name] = out["scores"]
        entry.setdefault("calibration", {})[name] = out["calibration"].as_dict()
        if per_frame:
            if "per_frame" not in entry:
                entry["per_frame"] = {"truth": out["truth"], "trackers": {}}
            entry["per_frame"]["trackers"][name] = out["per_frame"]
        if keep_boxes:
            if "boxes" not in entry:
                entry["boxes"] = {"truth": out["truth_boxes"], "trackers": {}}
            entry["boxes"]["trackers"][name] = out["boxes"]
    frames = sum(seq.length for seq in sequences)
    report["combined"] = {"method": COMBINED_METHOD, "trackers": {}}
    report["mean"] = {"method": MEAN_METHOD, "trackers": {}}
    report["combined"]["calibration"] = {}
    for name in trackers:
        per_seq = [report["sequences"][seq.name]["trackers"][name] for seq in sequences]
        calibration = pooled(calibrations[name]).as_dict()
        report["combined"]["calibration"][name] = calibration
        report["combined"]["trackers"][name] = {
            **summary(combined_results(raw[name])),
            "ece": calibration["ece"],
            "tracks": sum(values["tracks"] for values in per_seq),
            "seconds": seconds[name], "frames_per_second": frames / max(seconds[name], 1e-9)}
        report["mean"]["trackers"][name] = {
            key: float(np.mean([values[key] for values in per_seq])) for key in FRACTIONS}
    return report


def _row(name: str, values: dict, columns=COLUMNS) -> str:
    return f"  {name:<18}" + "".join(f"{format(values[key], fmt):>9}" for key, _, fmt in columns)


def _header(columns=COLUMNS) -> str:
    return f"  {'tracker':<18}" + "".join(f"{title:>9}" for _, title, _ in columns)


def format_report(report: dict) -> str:
    """The tables `occtrack benchmark` prints: one per sequence, then the combined scores and
    the mean over sequences."""
    lines = ["Protocol mot17 (TrackEval: MotChallenge2DBox preprocessing, IoU >= 0.5); "
             "HOTA, DetA, AssA and LocA are means over the 19 localisation thresholds; "
             "frames/s is the tracker call alone."]
    for name, entry in report["sequences"].items():
        w, h = entry["image_size"]
        lines += ["", f"{name} ({w}x{h}, {entry['fps']} fps, {entry['frames']} frames)",
                  _header()]
        lines += [_row(tracker, values) for tracker, values in entry["trackers"].items()]
    count = len(report["sequences"])
    if count > 1:
        lines += ["", f"Combined over {count} sequences ({report['combined']['method']}):",
                  _header()]
        lines += [_row(tracker, values)
                  for tracker, values in report["combined"]["trackers"].items()]
        mean_columns = [c for c in COLUMNS if c[0] in FRACTIONS]
        lines += ["", f"Mean over {count} sequences ({report['mean']['method']}):",
                  _header(mean_columns)]
        lines += [_row(tracker, values, mean_columns)
                  for tracker, values in report["mean"]["trackers"].items()]
    return "\n".join(lines)


def to_json(report: dict) -> str:
    """The report as JSON text: objects indented, each list of numbers on one line (a
    per-frame list or a box is one line, not one line a number)."""
    def lay(value, depth: int) -> str:
        if isinstance(value, dict) and value:
            inner = "  " * (depth + 1)
            items = ",\n".join(f"{inner}{json.dumps(key)}: {lay(item, depth + 1)}"
                               for key, item in value.items())
            return "{\n" + items + "\n" + "  " * depth + "}"
        if isinstance(value, list) and any(isinstance(item, dict) for item in value):
            inner = "  " * (depth + 1)
            items = ",\n".join(inner + lay(item, depth + 1) for item in value)
            return "[\n" + items + "\n" + "  " * depth + "]"
        return json.dumps(value, separators=(",", ":"))
    return lay(report, 0) + "\n"
