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

3D detections (every row with its 3D columns, x y z not -1000, e.g. PointRCNN's; decided by
the files' content, not the folder's name): occtrack's models track the 3D boxes on the ground
plane (`occtrack.tracker.ground.track_kitti`, every class in one run as above) with each
sequence's camera poses (`DIR/poses/NNNN.txt`; without one the camera is taken as still, with
a note) and calibration (`DIR/calib/NNNN.txt`, required: its P2 projects a coasting box into
the image), and are scored twice: in the image as above (their 2D boxes: the detection's own
while detected, else the 3D box projected) and on the ground plane (`kitti_bev`: TrackEval's
HOTA, CLEAR and Identity on the (x, z) centres, similarity max(0, 1 - d / 2 m)). The peers
track the same detections' 2D boxes class by class, the scores turned into probabilities as
the ground tracker reads them (`detection_scores`: PointRCNN's logits through the logistic
function); they have no 3D output, so their ground-plane entries are null.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
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
from occtrack.io import kitti_geometry
from occtrack.io.kitti import (
    UNKNOWN_3D,
    KittiTable,
    clip_to_image,
    detections_to_mot,
    read_kitti,
)
from occtrack.io.mot import MotTable, read_seqinfo
from occtrack.metrics import kitti_bev
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
GROUND_METHOD = (f"kitti-bev: TrackEval's HOTA, CLEAR and Identity on the ground plane, (x, z) "
                 f"centres of the 3D boxes, similarity max(0, 1 - d / {kitti_bev.DISTANCE:g} m) "
                 f"(CLEAR and Identity match within {kitti_bev.DISTANCE * kitti_bev.MATCH:g} "
                 f"m), Kitti2DBox's distractor and truncation rules; peers have no 3D output "
                 f"(null)")
GROUND_COLUMNS = tuple(c for c in COLUMNS if c[0] != "frames_per_second")


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
    """One KITTI sequence, read: its ground truth and detections (every known class); for
    3D detections also the camera's calibration and poses (`three_d`)."""

    name: str
    width: int
    height: int
    fps: int
    length: int
    gt: KittiTable
    det: MotTable  # frames 1-based, cls the KITTI type index
    table: KittiTable | None = None  # the detection rows behind `det`, one a row, 3D columns
    calibration: kitti_geometry.Calibration | None = None  # set for 3D detections only
    poses: np.ndarray | None = None  # (F, 3, 4); None: no poses file (a still camera)

    @property
    def three_d(self) -> bool:
        """Whether occtrack's models track this sequence's 3D boxes on the ground plane."""
        return self.calibration is not None


def load_sequence(root: Path, detections: str, name: str, three_d: bool = False) -> Sequence:
    """A sequence of the folder; with `three_d`, its calibration (required) and poses (if
    any) too and the detection scores as probabilities (`with_geometry`)."""
    info = read_seqinfo(root / "seqinfo" / f"{name}.ini")
    gt = read_kitti(root / "label_02" / f"{name}.txt")
    raw = read_kitti(root / "det_02" / detections / f"{name}.txt")
    det, rows, _ = detections_to_mot(raw)
    n = int(info["length"])
    for frames, path in ((gt.num_frames, gt.path), (det.num_frames, det.path)):
        if frames > n:
            raise OcctrackError(f"rows reach frame {frames - 1} but seqinfo says seqLength={n} "
                                f"(frames 0..{n - 1})", path)
    seq = Sequence(name, int(info["width"]), int(info["height"]), int(info["fps"]), n, gt,
                   det, raw.select(rows))
    return with_geometry(root, seq) if three_d else seq


def geometry_files(root: Path, name: str) -> tuple[Path, Path]:
    """A sequence's calibration and pose files: DIR/calib/NNNN.txt, DIR/poses/NNNN.txt."""
    return root / "calib" / f"{name}.txt", root / "poses" / f"{name}.txt"


def with_geometry(root: Path, seq: Sequence) -> Sequence:
    """The sequence ready for the ground tracker: its calibration (an OcctrackError naming the
    file when there is none), its poses (None without a pose file: a still camera) and the
    detection scores as probabilities (`detection_scores`: logits through the logistic
    function), the same for occtrack's models and the peers."""
    from occtrack.tracker.ground import detection_scores

    calib, poses = geometry_files(root, seq.name)
    if not calib.is_file():
        raise OcctrackError(f"sequence {seq.name} has no calib/{calib.name}: its 3D detections "
                            f"need the camera's calibration (KITTI's calib/NNNN.txt; its P2 "
                            f"projects a coasting box into the image)", str(calib))
    table = seq.table
    assert table is not None
    score = detection_scores(table.score)
    return replace(seq, det=replace(seq.det, score=score.copy()),
                   table=replace(table, score=score),
                   calibration=kitti_geometry.read_calib(calib),
                   poses=(kitti_geometry.read_poses(poses, seq.length) if poses.is_file()
                          else None))


def has_3d(sequences: list[Sequence]) -> tuple[bool, str | None]:
    """Whether the detections are 3D: every row (of a known class) in every sequence has its
    3D columns (x y z not -1000), and there is a row. A folder where some rows have them and
    some not is tracked as 2D, with the note returned saying so."""
    total = missing = 0
    first = None
    for seq in sequences:
        table = seq.table
        assert table is not None
        unknown = np.flatnonzero((table.box3d[:, 3:6] == -1000).any(axis=1))
        total += len(table)
        missing += len(unknown)
        if len(unknown) and first is None:
            line = "" if table.line is None else f" line {int(table.line[unknown[0]])}"
            first = f"{table.path}{line}"
    if total and not missing:
        return True, None
    if missing and missing < total:
        return False, (f"{missing} of {total} detection rows have no 3D columns (x y z = "
                       f"-1000; first at {first}): the detections are tracked as 2D boxes")
    return False, None


_SEQUENCES: dict = {}


def cached_sequence(root: str, detections: str, name: str, three_d: bool = False) -> Sequence:
    """The sequence, read once per process and again when one of its files changed."""
    base = Path(root)
    files = [base / "seqinfo" / f"{name}.ini", base / "label_02" / f"{name}.txt",
             base / "det_02" / detections / f"{name}.txt"]
    if three_d:
        files += [path for path in geometry_files(base, name) if path.is_file()]
    key = (root, detections, name, three_d)
    stamp = tuple((str(path), path.stat().st_mtime_ns) for path in files)
    cached = _SEQUENCES.get(key)
    if cached is None or cached[0] != stamp:
        _SEQUENCES[key] = (stamp, load_sequence(base, detections, name, three_d))
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
          settings: dict | None = None, ground: dict | None = None) -> KittiTable:
    """One tracker on a sequence's boxes of `classes`: occtrack (by occlusion model, with
    `settings` over the defaults) on all of them at once, a peer class by class. For a 3D
    sequence (`Sequence.three_d`) occtrack tracks the 3D boxes on the ground plane, every
    class the detector reports (a box of one class can be the duplicate of a higher-scored
    box of another at the same place, `occtrack.models.footprints`), and its result has the
    3D columns; a peer tracks the 2D boxes."""
    types = [CLASS_TYPE[c] for c in classes]
    det = seq.det.select(np.isin(seq.det.cls, types))
    if name in MODELS and seq.three_d:
        from occtrack.tracker.ground import ground_config, track_kitti

        assert seq.table is not None
        config = ground_config({**(settings or {}), "occlusion": name, "fps": seq.fps,
                                "image_size": (seq.width, seq.height)})
        return track_kitti(seq.table, seq.length, config, seq.poses, seq.calibration,
                           (seq.width, seq.height), quiet=True, **(ground or {}))
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
    three_d: bool = False  # 3D detections: occtrack on the ground plane, also scored there
    ground: tuple = ()  # (name, value) pairs of `track_kitti`'s options (3D only)


def run_job(job: Job) -> dict:
    """Track and score one sequence with one tracker: per class TrackEval's results, the
    headline scores and the reliability table; for occtrack on 3D detections also the same
    on the ground plane under "ground" (`kitti_bev`), for a peer there None."""
    seq = cached_sequence(job.root, job.detections, job.sequence, job.three_d)
    peers.load_for(job.tracker)
    start = time.perf_counter()
    result = track(job.tracker, seq, job.classes, dict(job.settings), dict(job.ground))
    spent = time.perf_counter() - start
    out = {"seconds": spent, "classes": {}}
    tracks = {cls: int(len(np.unique(result.id[result.type == CLASS_TYPE[cls]])))
              for cls in job.classes}
    for cls, scored in scored_frames(seq.gt, result, seq.length, job.classes).items():
        results = sequence_results(scored.trackeval)
        calibration = reliability(scored, result.score)
        out["classes"][cls] = {
            "results": results, "calibration": calibration,
            "truth": int(scored.trackeval["num_gt_dets"]),
            "scores": {**summary(results), "ece": calibration.ece, "tracks": tracks[cls],
                       "seconds": spent,
                       "frames_per_second": seq.length / max(spent, 1e-9)}}
    if job.three_d:
        ground = (kitti_bev.scored_frames(seq.gt, result, seq.length, job.classes)
                  if job.tracker in MODELS else {})
        for cls in job.classes:
            out["classes"][cls]["ground"] = None
            if cls in ground:
                results = sequence_results(ground[cls].trackeval)
                calibration = reliability(ground[cls], result.score)
                out["classes"][cls]["ground"] = {
                    "results": results, "calibration": calibration,
                    "truth": int(ground[cls].trackeval["num_gt_dets"]),
                    "scores": {**summary(results), "ece": calibration.ece,
                               "tracks": tracks[cls]}}
    return out


def benchmark(root: str | os.PathLike, trackers: list[str], detections: str | None = None,
              classes: tuple[str, ...] = CLASSES, quiet: bool = False, engine=None,
              settings: dict | None = None, ground: dict | None = None) -> dict:
    """Track and score every sequence of a KITTI folder with every tracker; the report that
    `occtrack benchmark --json` writes for a KITTI folder. `settings`: TrackerConfig values
    over the defaults for occtrack's models; `ground`: `track_kitti`'s options over its
    defaults (3D detections only, e.g. {"lookahead": 0.0}). With 3D detections (`has_3d`)
    occtrack's models track on the ground plane and the report adds, per class, the
    ground-plane scores ("ground", see the module); "notes" says what the caller should
    print."""
    base = Path(root).resolve()
    if not is_layout(base):
        raise OcctrackError("not a KITTI tracking folder: it needs label_02/ and det_02/",
                            str(root))
    detections = pick_detections(base, detections)
    names = sequence_names(base, detections)
    sequences = [load_sequence(base, detections, name) for name in names]  # checked up front
    three_d, note = has_3d(sequences)
    notes = [note] if note else []
    if three_d:  # the calibrations (required) and poses read and checked before any run
        sequences = [with_geometry(base, seq) for seq in sequences]
        still = [seq.name for seq in sequences if seq.poses is None]
        if still:
            notes.append(f"no poses/NNNN.txt for {', '.join(still)}: the camera is taken as "
                         f"still there (its own motion falls to the tracker's noise)")
    for name in trackers:
        peers.load_for(name)
    pairs = tuple(sorted((k, tuple(v) if isinstance(v, list) else v)  # (hashable)
                         for k, v in (settings or {}).items()))
    options = tuple(sorted((ground or {}).items()))

    def job_of(sequence: str, tracker: str) -> Job:
        return Job(str(base), detections, sequence, tracker, tuple(classes), pairs, three_d,
                   options)

    jobs = [job_of(seq.name, name) for seq in sequences for name in trackers]
    done = run_jobs(jobs, engine, quiet, run_job,
                    lambda job: f"{job.tracker} on {job.sequence}")
    report: dict = {"protocol": PROTOCOL, "layout": "kitti", "folder": str(base),
                    "detections": detections, "detections_3d": three_d,
                    "trackers": list(trackers), "classes": list(classes), "sequences": {},
                    "combined": {"method": COMBINED_METHOD, "classes": {}},
                    "mean": {"method": MEAN_METHOD, "classes": {}}, "notes": notes}
    models = [name for name in trackers if name in MODELS]
    ground = three_d and bool(models)  # the ground-plane scores: occtrack's 3D runs only
    if ground:
        report["ground"] = {"protocol": "kitti-bev", "distance": kitti_bev.DISTANCE,
                            "method": GROUND_METHOD}
    for seq in sequences:
        entry = report["sequences"][seq.name] = {
            "frames": seq.length, "fps": seq.fps, "image_size": [seq.width, seq.height],
            "classes": {cls: {"truth": done[job_of(seq.name, trackers[0])]["classes"][cls]["truth"],
                              "trackers": {}, "calibration": {}} for cls in classes}}
        if three_d:
            entry["poses"] = seq.poses is not None
        if ground:
            for cls in classes:
                entry["classes"][cls]["ground"] = {
                    "truth": done[job_of(seq.name, models[0])]["classes"][cls]["ground"]["truth"],
                    "trackers": {}, "calibration": {}}
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
            if ground:
                _ground_scores(report, sequences, cls, name, outs)
    return report


def _ground_scores(report: dict, sequences: list[Sequence], cls: str, name: str,
                   outs: list[dict]) -> None:
    """One tracker's ground-plane entries of a class: per sequence, combined (TrackEval's
    COMBINED_SEQ) and the mean over the sequences with a true object there; None (null) for a
    peer, which has no 3D output."""
    combined = report["combined"]["classes"][cls].setdefault(
        "ground", {"trackers": {}, "calibration": {}})
    mean = report["mean"]["classes"][cls].setdefault("ground", {"trackers": {}})
    parts = [out["classes"][cls]["ground"] for out in outs]
    for seq, part in zip(sequences, parts, strict=True):
        entry = report["sequences"][seq.name]["classes"][cls]["ground"]
        entry["trackers"][name] = None if part is None else part["scores"]
        if part is not None:
            entry["calibration"][name] = part["calibration"].as_dict()
    if any(part is None for part in parts):
        combined["trackers"][name] = mean["trackers"][name] = None
        return
    calibration = pooled([part["calibration"] for part in parts])
    combined["calibration"][name] = calibration.as_dict()
    combined["trackers"][name] = {
        **summary(combined_results([part["results"] for part in parts])),
        "ece": calibration.ece, "tracks": sum(part["scores"]["tracks"] for part in parts)}
    per_seq = [part["scores"] for part in parts if part["truth"]]
    mean["trackers"][name] = {
        key: (float(np.mean([values[key] for values in per_seq])) if per_seq else None)
        for key in FRACTIONS}


def format_report(report: dict) -> str:
    """The tables `occtrack benchmark` prints for a KITTI folder: per class one table a
    sequence (only those with a true box of the class), then the combined scores and the
    mean."""
    lines = [f"Protocol kitti (TrackEval Kitti2DBox), detections {report['detections']}; "
             "HOTA, DetA, AssA and LocA are means over the 19 localisation thresholds; "
             "frames/s is the tracker call alone (occtrack: all classes in one run)."]
    if report.get("detections_3d"):
        lines.append("3D detections: occtrack's models track the 3D boxes on the ground plane "
                     "(each sequence's poses and calibration) and are scored on their 2D boxes "
                     "(the detection's while detected, else the 3D box projected); the peers "
                     "track the 2D boxes, the scores as probabilities.")
    if "ground" in report:
        lines.append(f"Ground plane: {report['ground']['method']}; LocA and MOTP are the mean "
                     f"similarity of the matches.")
    count = len(report["sequences"])
    mean_columns = [c for c in COLUMNS if c[0] in FRACTIONS]
    ground_mean = [c for c in GROUND_COLUMNS if c[0] in FRACTIONS]
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
            if "ground" in part:
                lines += _ground_table(f"{name} {cls} on the ground plane "
                                       f"({part['ground']['truth']} true objects):",
                                       part["ground"]["trackers"], GROUND_COLUMNS)
        lines += ["", f"{cls}, combined over {count} sequences "
                      f"({report['combined']['method']}):", _header()]
        combined = report["combined"]["classes"][cls]
        lines += [_row(tracker, values) for tracker, values in combined["trackers"].items()]
        if "ground" in combined:
            lines += _ground_table(f"{cls}, combined over {count} sequences, on the ground "
                                   f"plane:", combined["ground"]["trackers"], GROUND_COLUMNS)
        values = report["mean"]["classes"][cls]["trackers"]
        if all(v["hota"] is not None for v in values.values()):
            lines += ["", f"{cls}, mean over sequences ({report['mean']['method']}):",
                      _header(mean_columns)]
            lines += [_row(tracker, v, mean_columns) for tracker, v in values.items()]
        ground = report["mean"]["classes"][cls].get("ground")
        if ground and all(v is None or v["hota"] is not None
                          for v in ground["trackers"].values()):
            lines += _ground_table(f"{cls}, mean over sequences, on the ground plane:",
                                   ground["trackers"], ground_mean)
    return "\n".join(lines)


def _ground_table(title: str, rows: dict, columns) -> list[str]:
    """A ground-plane table: a row a tracker, "-" in every column for a peer (no 3D
    output)."""
    lines = ["", title, _header(columns)]
    for tracker, values in rows.items():
        lines.append(_row(tracker, values, columns) if values is not None else
                     f"  {tracker:<18}" + "".join(f"{'-':>9}" for _ in columns))
    return lines


__all__ = ["Job", "benchmark", "format_report", "has_3d", "is_layout", "run_job",
           "with_geometry"]
