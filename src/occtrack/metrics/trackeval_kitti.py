"""The official KITTI tracking protocol, run by TrackEval itself (`Kitti2DBox`).

TrackEval's `Kitti2DBox` dataset does KITTI's preprocessing and its `CLEAR`, `Identity` and
`HOTA` metrics do the scoring, so occtrack's numbers are TrackEval's numbers. Per class (car,
pedestrian), per frame:

- Ground truth of the class and of its distractor class (van for car, person sitting for
  pedestrian) is matched to the result boxes of the class by Hungarian assignment on
  IoU >= 0.5; result boxes matched to a distractor, or to a true box that is truncated
  (truncation > 0) or largely hidden (occlusion > 2), are removed. Unmatched result boxes
  25 px tall or less, or lying more than half inside a DontCare region, are removed too.
  Then only the class's own, untruncated, visible-enough true boxes are kept.
- CLEAR and Identity need IoU >= 0.5; HOTA is averaged over the localisation thresholds
  0.05 .. 0.95.

As for the mot17 protocol (`occtrack.metrics.trackeval_mot17`), the only thing not TrackEval's
is reading the files: `occtrack.io.kitti` reads and checks them, and the rows are handed to the
dataset the way its own reader would make them (DontCare rows as crowd-ignore regions, rows
with a negative id dropped, type names turned into its class ids; its class filter is a no-op
in TrackEval 1.3, so every other type stays in and is dropped by the per-class mask). Each
result row's index rides through the preprocessing in the confidence column, which none of the
metrics reads, so the rows that survive are known exactly (for `--calibration`). Ids are
relabelled 0..n-1 in order first (TrackEval relabels the same way later; it only keeps its id
tables small). A test runs TrackEval's own file-reading evaluator beside this and asserts
every number equal.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from trackeval.datasets import Kitti2DBox

from occtrack.config.arguments import DAY_AT_30_FPS
from occtrack.errors import OcctrackError
from occtrack.io.kitti import DONTCARE, TYPES, UNKNOWN, KittiTable
from occtrack.io.mot import check_gaps, first_duplicate
from occtrack.metrics.protocols import ScoredFrames
from occtrack.metrics.trackeval_mot17 import (
    _trackeval_errors,
    combined_results,
    sequence_results,
    summary,
)

__all__ = ["CLASSES", "combined_results", "scored_frames", "sequence_results", "summary"]

CLASSES = ("car", "pedestrian")
"""The classes KITTI's evaluation scores (TrackEval's `Kitti2DBox` knows no others)."""
CLASS_TYPE = {"car": TYPES.index("Car"), "pedestrian": TYPES.index("Pedestrian")}


def parse_classes(text: str | None) -> tuple[str, ...]:
    """`--classes car,pedestrian` (any case), checked: the classes KITTI's evaluation scores,
    duplicates dropped, order kept; None gives both."""
    if text is None:
        return CLASSES
    classes = tuple(dict.fromkeys(c.strip().lower() for c in text.split(",") if c.strip()))
    odd = [c for c in classes if c not in CLASSES]
    if odd or not classes:
        raise OcctrackError(f"--classes: KITTI's evaluation scores car and pedestrian, not "
                            f"{odd[0] if odd else 'nothing'!r}")
    return classes
_SEQ = "seq"
_TRACKER = "result"
MAX_OCCLUSION, MAX_TRUNCATION = 2, 0  # Kitti2DBox's


class _ArrayDataset(Kitti2DBox):
    """`Kitti2DBox` whose raw data come from arrays instead of its folder layout."""

    def __init__(self, gt_raw: dict, tracker_raw: dict, num_frames: int, classes: list[str]):
        with tempfile.TemporaryDirectory(prefix="occtrack-trackeval-") as folder:
            root = Path(folder)
            (root / "label_02").mkdir()
            (root / "label_02" / f"{_SEQ}.txt").touch()
            (root / "evaluate_tracking.seqmap.training").write_text(
                f"{_SEQ} empty 000000 {num_frames:06d}\n")
            (root / _TRACKER / "data").mkdir(parents=True)
            (root / _TRACKER / "data" / f"{_SEQ}.txt").touch()
            super().__init__({"GT_FOLDER": folder, "TRACKERS_FOLDER": folder,
                              "OUTPUT_FOLDER": folder, "TRACKERS_TO_EVAL": [_TRACKER],
                              "CLASSES_TO_EVAL": list(classes), "SPLIT_TO_EVAL": "training",
                              "PRINT_CONFIG": False})
        self._raw = {True: gt_raw, False: tracker_raw}

    def _load_raw_file(self, tracker, seq, is_gt):
        return self._raw[is_gt]


def check_frames(table: KittiTable, num_frames: int) -> None:
    """Refuse a row past the sequence's last frame (TrackEval would stop on it, without the
    line)."""
    late = np.flatnonzero(table.frame >= num_frames)
    if len(late):
        i = late[0]
        raise OcctrackError(f"frame {table.frame[i]} is past the sequence's {num_frames} "
                            f"frames (0..{num_frames - 1}); pass --frames N if the sequence is "
                            f"longer", table.path or None,
                            None if table.line is None else int(table.line[i]))


def _scored_rows(table: KittiTable, is_gt: bool) -> tuple[np.ndarray, np.ndarray]:
    """The rows TrackEval's reader keeps as boxes (a known type, id >= 0; DontCare rows of the
    ground truth are regions instead) and the DontCare regions' rows."""
    known = table.type != UNKNOWN
    if is_gt:
        dontcare = table.type == DONTCARE
        return np.flatnonzero(known & ~dontcare & (table.id >= 0)), np.flatnonzero(dontcare)
    return np.flatnonzero(known & (table.id >= 0)), np.zeros(0, np.int64)


def _by_frame(table: KittiTable, rows: np.ndarray, num_frames: int) -> list[np.ndarray]:
    order = rows[np.argsort(table.frame[rows], kind="stable")]
    bounds = np.searchsorted(table.frame[order], np.arange(num_frames + 1))
    return [order[bounds[t]:bounds[t + 1]] for t in range(num_frames)]


def _raw(table: KittiTable, num_frames: int, is_gt: bool) -> tuple[dict, list[np.ndarray]]:
    """The dict TrackEval's `_load_raw_file` returns for `table`, and per frame the rows of
    `table` behind its boxes, in its order."""
    rows, regions = _scored_rows(table, is_gt)
    _, ids = np.unique(table.id[rows], return_inverse=True)
    relabelled = np.zeros(len(table), np.int64)
    relabelled[rows] = ids.reshape(-1)
    per_frame = _by_frame(table, rows, num_frames)
    prefix = "gt" if is_gt else "tracker"
    raw = {f"{prefix}_ids": [relabelled[r] for r in per_frame],
           f"{prefix}_classes": [table.type[r] + 1 for r in per_frame],
           f"{prefix}_dets": [table.box[r] for r in per_frame],
           "num_timesteps": num_frames, "seq": _SEQ}
    if is_gt:
        raw["gt_extras"] = [{"truncation": table.truncated[r].astype(int),
                             "occlusion": table.occluded[r].astype(int)} for r in per_frame]
        raw["gt_crowd_ignore_regions"] = [table.box[r] for r in
                                          _by_frame(table, regions, num_frames)]
    else:
        raw["tracker_confidences"] = [r.astype(float) for r in per_frame]
    return raw, per_frame


def check_result(result: KittiTable) -> None:
    """Refuse a result that gives one id to two boxes of one class in a frame (TrackEval
    would, without the lines). Ids are a class's own: a car and a pedestrian may share one, as
    trackers that number each class apart write them."""
    rows, _ = _scored_rows(result, False)
    for kind in np.unique(result.type[rows]):
        same = rows[result.type[rows] == kind]
        twice = first_duplicate(result.frame[same], result.id[same])
        if twice is None:
            continue
        a, b = (same[i] for i in twice)
        lines = ("" if result.line is None else
                 f" (lines {result.line[a]} and {result.line[b]})")
        raise OcctrackError(f"id {result.id[a]} appears twice among the {TYPES[kind]} boxes of "
                            f"frame {result.frame[a]}{lines}", result.path or None,
                            None if result.line is None else int(result.line[b]))


def scored_frames(gt: KittiTable, result: KittiTable, num_frames: int,
                  classes: tuple[str, ...] | list[str] = CLASSES) -> dict[str, ScoredFrames]:
    """Per class, the boxes KITTI's protocol scores: TrackEval's preprocessed sequence in
    `trackeval` and, per frame (entry t is frame t), the rows of `gt` and `result` it keeps
    and their IoU. Frames run 0..num_frames - 1."""
    unknown = [c for c in classes if c not in CLASSES]
    if unknown:
        raise OcctrackError(f"KITTI's evaluation scores {' and '.join(CLASSES)}, not "
                            f"{unknown[0]!r}")
    check_frames(gt, num_frames)
    check_frames(result, num_frames)
    check_result(result)
    gt_raw, gt_rows = _raw(gt, num_frames, True)
    tracker_raw, _ = _raw(result, num_frames, False)
    out = {}
    with _trackeval_errors():
        dataset = _ArrayDataset(gt_raw, tracker_raw, num_frames, list(classes))
        raw = dataset.get_raw_seq_data(_TRACKER, _SEQ)
        for cls in classes:
            data = dataset.get_preprocessed_seq_data(raw, cls)
            keep = ((gt.type == CLASS_TYPE[cls]) & (gt.occluded.astype(int) <= MAX_OCCLUSION)
                    & (gt.truncated.astype(int) <= MAX_TRUNCATION))
            truth = [r[keep[r]] for r in gt_rows]
            assert all(len(a) == len(b) for a, b in zip(truth, data["gt_ids"], strict=True))
            estimates = [c.astype(np.int64) for c in data["tracker_confidences"]]
            out[cls] = ScoredFrames("kitti", truth, estimates,
                                    list(data["similarity_scores"]), data)
    return out


KEYS = ("hota", "deta", "assa", "loca", "mota", "idf1", "id_switches", "fp", "fn",
        "mostly_tracked", "mostly_lost", "motp")
"""The numbers `occtrack eval --protocol kitti` reports per class, in table order."""


def sequence_length(gt_path: str | Path) -> int | None:
    """A KITTI sequence's frame count from its layout: `DIR/seqinfo/NNNN.ini`, else
    `DIR/evaluate_tracking.seqmap` (its 4th field, as TrackEval reads it); None outside a
    layout."""
    from occtrack.io.kitti import find_seqinfo, layout_root, sequence_name
    from occtrack.io.mot import read_seqinfo

    ini = find_seqinfo(gt_path)
    if ini is not None:
        return int(read_seqinfo(ini)["length"])
    root = layout_root(gt_path)
    if root is not None:
        lengths = read_seqmap(root / "evaluate_tracking.seqmap")
        return lengths.get(sequence_name(gt_path))
    return None


def read_seqmap(path: Path) -> dict[str, int]:
    """{sequence: frames} of a KITTI seqmap (`NNNN empty 000000 NNNNNN`); {} if there is no
    such file."""
    if not path.is_file():
        return {}
    lengths = {}
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        parts = line.split()
        if not parts:
            continue
        try:
            lengths[parts[0]] = int(parts[3])
        except (IndexError, ValueError):
            raise OcctrackError("expected 'NAME empty 000000 FRAMES'", str(path), number) from None
    return lengths


def sequence_pairs(gt: str | Path, result: str | Path) -> list[tuple[str, Path, Path]]:
    """(name, ground truth, result) of each sequence to score: two files, or a ground-truth
    folder (a KITTI folder holding label_02/, or label_02/ itself: every NNNN.txt in it, or
    those its seqmap names) and a result folder holding NAME.txt for each (or a TrackEval
    tracker folder, RESULT/data/NAME.txt)."""
    gt, result = Path(gt), Path(result)
    if gt.is_file() != result.is_file() or not (gt.exists() and result.exists()):
        for path in (gt, result):
            if not path.exists():
                raise OcctrackError("no such file or folder", str(path))
        kinds = ["file" if path.is_file() else "folder" for path in (gt, result)]
        raise OcctrackError(f"give two files or two folders, not a {kinds[0]} of ground truth "
                            f"and a {kinds[1]} of results", str(result))
    if gt.is_file():
        return [(gt.stem, gt, result)]
    labels = gt / "label_02" if (gt / "label_02").is_dir() else gt
    names = list(read_seqmap(labels.parent / "evaluate_tracking.seqmap"))
    if not names:
        names = sorted(p.stem for p in labels.glob("*.txt"))
    if not names:
        raise OcctrackError("no ground-truth files here (NNNN.txt, or label_02/NNNN.txt)",
                            str(gt))
    results = result / "data" if (result / "data").is_dir() else result
    pairs = []
    for name in names:
        pair = (name, labels / f"{name}.txt", results / f"{name}.txt")
        for path in pair[1:]:
            if not path.is_file():
                raise OcctrackError(f"no file for sequence {name}", str(path))
        pairs.append(pair)
    return pairs


def evaluate(pairs: list[tuple[str, Path, Path]], classes: tuple[str, ...] | list[str] = CLASSES,
             frames: int | None = None, calibration: bool = False,
             max_gap_frames: int = DAY_AT_30_FPS) -> dict:
    """Score each (name, ground truth, result) under KITTI's protocol: per class, each
    sequence's numbers (`KEYS`) and TrackEval's COMBINED_SEQ over them; with `calibration`,
    per class the reliability table (`Reliability`) of the result's score column (a box is
    right when matched at IoU >= 0.5 to a true box of its class), pooled over the sequences.
    A sequence's length is `frames`, else its layout's seqinfo or seqmap, else its last
    frame + 1 in either file; more than `max_gap_frames` empty frames in a row in a file is
    refused (a stray frame number).
    Returns {"protocol": "kitti", "classes": {CLASS: {"sequences": {NAME: values},
    "combined": values, "calibration": table}}, "notes": [...]}."""
    from occtrack.io.kitti import read_kitti
    from occtrack.metrics.reliability import pooled, reliability

    per_class: dict[str, dict] = {c: {"sequences": {}, "raw": [], "tables": []} for c in classes}
    notes = []
    for name, gt_path, result_path in pairs:
        gt, result = read_kitti(gt_path), read_kitti(result_path)
        for table in (gt, result):
            if table.unknown():
                notes.append(f"{table.path}: {table.unknown()}, not scored")
        last = max(gt.num_frames, result.num_frames, 1)
        for table in (gt, result):
            check_gaps(table, max_gap_frames)
        n = frames or sequence_length(gt_path) or last
        check_frames(gt, n)
        check_frames(result, n)
        n = min(n, last)  # frames after the last row of both hold nothing to score
        if calibration:
            bad = np.flatnonzero(~((result.score >= 0) & (result.score <= 1)))
            if len(bad):
                raise OcctrackError(f"score (column 18) {result.score[bad[0]]:g} is not a "
                                    f"probability in [0, 1], which --calibration needs",
                                    result.path, int(result.line[bad[0]]))
        for cls, scored in scored_frames(gt, result, n, classes).items():
            results = sequence_results(scored.trackeval)
            entry = per_class[cls]
            entry["raw"].append(results)
            entry["sequences"][name] = {key: summary(results)[key] for key in KEYS}
            if calibration:
                entry["tables"].append(reliability(scored, result.score))
    out = {"protocol": "kitti", "classes": {}, "notes": notes}
    for cls, entry in per_class.items():
        combined = summary(combined_results(entry["raw"]))
        out["classes"][cls] = {"sequences": entry["sequences"],
                               "combined": {key: combined[key] for key in KEYS}}
        if calibration:
            out["classes"][cls]["calibration"] = pooled(entry["tables"])  # a Reliability
    return out
