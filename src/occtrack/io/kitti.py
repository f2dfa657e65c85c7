"""KITTI tracking text files: labels (ground truth), detections and tracker results.

A row is `frame id type truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y [score]`,
space separated, frames 0-based; labels have 17 columns, detections and results an 18th, the
score (a file without it: score 1). `type` is one of `TYPES` (KITTI writes them capitalised;
matched without regard to case, as TrackEval matches them); DontCare rows (id -1) mark regions
where unmatched result boxes are not counted. The 3D columns (h w l in m, x y z the bottom
centre in camera coordinates, rotation_y) are -1 / -1000 / -10 where unknown, as a 2D detector
writes them.

Every row is checked and a bad one stops the read with the file, line and problem (as
`occtrack.io.mot` does): a missing column, a word where a number belongs, NaN or infinity, a
fractional frame or id, a negative frame, x2 < x1 or y2 < y1. A type KITTI does not know is
not an error: such rows are counted, and `unknown` says how many and where the first is.

The layout (`DIR/label_02/NNNN.txt`, `DIR/det_02/NAME/NNNN.txt`, `DIR/seqinfo/NNNN.ini`,
`DIR/evaluate_tracking.seqmap`) is KITTI's and TrackEval's; `find_seqinfo` finds a file's
sequence information in it.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError, opening
from occtrack.io.atomic import atomic_write
from occtrack.io.mot import MAX_FRAME, MAX_ID, MIN_ID, MotTable

TYPES = ("Car", "Van", "Truck", "Pedestrian", "Person", "Cyclist", "Tram", "Misc", "DontCare")
"""KITTI's object types, in the order of TrackEval's class ids 1..9 (`Person` is KITTI's
person sitting, also written `Person_sitting`)."""
DONTCARE = TYPES.index("DontCare")
ROUND_TYPES = (TYPES.index("Pedestrian"), TYPES.index("Person"))
"""The types whose body fills the elliptic cylinder inscribed in their 3D box, not the box:
people. A vehicle, a bicycle with its rider included, fills its box to the corners. Their
image box is the cylinder's projection (`kitti_geometry.project_cylinders`); checked on
KITTI's own labels, where the labelled 3D box of a walker projects 1.1 to 1.55 times as wide
as the labelled 2D box (median per sequence) and the cylinder 0.85 to 1.17 times; a car's box
and a cyclist's project within 3 % of theirs."""
_NAMES = {name.lower(): i for i, name in enumerate(TYPES)}
_NAMES.update({"person_sitting": TYPES.index("Person"), "car_2": TYPES.index("Car")})
UNKNOWN = -1
COLUMNS = 17
UNKNOWN_3D = (-1.0, -1.0, -1.0, -1000.0, -1000.0, -1000.0, -10.0)  # h w l x y z rotation_y


@dataclass(frozen=True)
class KittiTable:
    """Columns of a KITTI tracking file as plain arrays, one entry a row (every row read,
    unknown types included: `type` is then UNKNOWN)."""

    frame: np.ndarray  # (N,) int, 0-based as in the file
    id: np.ndarray  # (N,) int; -1 for detections and DontCare
    type: np.ndarray  # (N,) int index into TYPES, UNKNOWN (-1) for a type KITTI does not know
    truncated: np.ndarray  # (N,) float
    occluded: np.ndarray  # (N,) float
    alpha: np.ndarray  # (N,) float
    box: np.ndarray  # (N, 4) float: x1, y1, x2, y2 in px
    box3d: np.ndarray  # (N, 7) float: h, w, l, x, y, z, rotation_y
    score: np.ndarray  # (N,) float: the 18th column, 1 where absent
    path: str = ""
    line: np.ndarray | None = None  # (N,) int: 1-based line in `path`
    unknown_names: tuple[str, ...] = ()  # the type names not in TYPES, in order of appearance

    def __len__(self) -> int:
        return len(self.frame)

    @property
    def num_frames(self) -> int:
        """Frames 0..last, so the last frame + 1 (0 for an empty file)."""
        return int(self.frame.max()) + 1 if len(self) else 0

    def select(self, mask: np.ndarray) -> KittiTable:
        return KittiTable(self.frame[mask], self.id[mask], self.type[mask],
                          self.truncated[mask], self.occluded[mask], self.alpha[mask],
                          self.box[mask], self.box3d[mask], self.score[mask], self.path,
                          None if self.line is None else self.line[mask], self.unknown_names)

    def unknown(self) -> str | None:
        """A note on the rows of unknown type (count, names, first line), or None."""
        odd = self.type == UNKNOWN
        if not odd.any():
            return None
        first = "" if self.line is None else f", first at line {int(self.line[odd][0])}"
        return (f"{int(odd.sum())} rows of a type KITTI does not know "
                f"({', '.join(self.unknown_names)}{first})")


def type_index(name: str) -> int:
    """The index in TYPES of a KITTI type name (any case), or UNKNOWN."""
    return _NAMES.get(name.lower(), UNKNOWN)


def parse_classes(text: str) -> list[int]:
    """A comma list of KITTI type names (`--classes Car,Pedestrian`), checked: indices into
    TYPES, duplicates dropped, order kept."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    if not names:
        raise OcctrackError(f"--classes names no class; choose from {', '.join(TYPES[:-1])}")
    picked = []
    for name in names:
        index = type_index(name)
        if index in (UNKNOWN, DONTCARE):
            raise OcctrackError(f"--classes: unknown class {name!r}; choose from "
                                f"{', '.join(TYPES[:-1])}")
        picked.append(index)
    return list(dict.fromkeys(picked))


def looks_like_kitti(path: str | os.PathLike) -> bool:
    """Whether a text file is in KITTI's format: its first row's third field is a word (a type
    name) where a MOTChallenge row has a number. Unreadable files are left to the reader."""
    if not Path(path).is_file():  # a FIFO or device is read once, by the reader
        return False
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for raw in fh:
                parts = raw.strip().lstrip("\ufeff").split()
                if parts:
                    if "," in parts[0] or len(parts) < 3:
                        return False
                    try:
                        float(parts[2])
                    except ValueError:
                        return True
                    return False
    except OSError:
        return False
    return False


def _whole(text: str, what: str, low: int, high: int, path: str, line: int) -> int:
    try:
        number = int(text)
    except ValueError:
        try:
            value = float(text)
        except ValueError:
            raise OcctrackError(f"{what} is not a number: {text!r}", path, line) from None
        if not math.isfinite(value) or not value.is_integer():
            raise OcctrackError(f"{what} {text} is not a whole number", path, line) from None
        number = int(value)
    if not low <= number <= high:
        raise OcctrackError(f"{what} {text} is out of range: {what}s run from {low} to {high}"
                            + (" (KITTI frames are 0-based)" if what == "frame" else ""),
                            path, line)
    return number


def read_kitti(path: str | os.PathLike) -> KittiTable:
    """Every row of a KITTI tracking file (labels, detections or results), checked cell by
    cell. Rows may come in any frame order; blank lines are skipped."""
    path = str(path)
    try:
        with opening(path, "a KITTI tracking text file"), \
                open(path, encoding="utf-8", newline="") as fh:
            lines = fh.read().splitlines()
    except UnicodeDecodeError as err:
        raise OcctrackError(f"not a text file (byte {err.start} is not UTF-8)", path) from None
    frames, ids, types, numbers, reals = [], [], [], [], []
    unknown: dict[str, None] = {}
    for number, raw in enumerate(lines, start=1):
        parts = raw.strip().lstrip("\ufeff").split()
        if not parts:
            continue
        if len(parts) < COLUMNS:
            raise OcctrackError(
                f"expected {COLUMNS} columns (frame id type truncated occluded alpha x1 y1 x2 "
                f"y2 h w l x y z rotation_y) and an optional score, found {len(parts)}: "
                f"{raw.strip()[:60]!r}", path, number)
        frames.append(_whole(parts[0], "frame", 0, MAX_FRAME - 1, path, number))
        ids.append(_whole(parts[1], "id", MIN_ID, MAX_ID, path, number))
        index = type_index(parts[2])
        if index == UNKNOWN:
            try:
                float(parts[2])
            except ValueError:
                unknown.setdefault(parts[2])
            else:
                raise OcctrackError(f"column 3 should be a KITTI type name (Car, Pedestrian, "
                                    f"...), found the number {parts[2]}; is this a "
                                    f"MOTChallenge file?", path, number)
        types.append(index)
        values = []
        for col in range(3, min(len(parts), COLUMNS + 1)):
            try:
                value = float(parts[col])
            except ValueError:
                raise OcctrackError(f"column {col + 1} is not a number: {parts[col]!r}",
                                    path, number) from None
            if not math.isfinite(value):
                raise OcctrackError(f"column {col + 1} is {parts[col]}", path, number)
            values.append(value)
        if len(values) == COLUMNS - 3:
            values.append(1.0)
        x1, y1, x2, y2 = values[3:7]
        if x2 < x1 or y2 < y1:
            raise OcctrackError(f"negative box size: x1 y1 x2 y2 = {x1:g} {y1:g} {x2:g} {y2:g} "
                                f"(x2 must be at least x1, y2 at least y1)", path, number)
        numbers.append(number)
        reals.append(values)
    arr = np.array(reals, dtype=float).reshape(-1, COLUMNS - 2)
    return KittiTable(frame=np.array(frames, dtype=np.int64), id=np.array(ids, dtype=np.int64),
                      type=np.array(types, dtype=np.int64), truncated=arr[:, 0].copy(),
                      occluded=arr[:, 1].copy(), alpha=arr[:, 2].copy(), box=arr[:, 3:7].copy(),
                      box3d=arr[:, 7:14].copy(), score=arr[:, 14].copy(), path=path,
                      line=np.array(numbers, dtype=np.int64), unknown_names=tuple(unknown))


def detections_to_mot(table: KittiTable, classes: list[int] | None = None
                      ) -> tuple[MotTable, np.ndarray, str | None]:
    """The rows of a KITTI detection file to track: a MotTable (frames 1-based, boxes left,
    top, width, height, `cls` the KITTI type index), the KITTI row each of its rows came from,
    and a note on what was skipped (None if nothing). `classes` (indices into TYPES) keeps only
    those types; None keeps every known type but DontCare."""
    known = (table.type != UNKNOWN) & (table.type != DONTCARE)
    keep = known if classes is None else np.isin(table.type, classes)
    notes = []
    dontcare = table.type == DONTCARE
    if dontcare.any():
        notes.append(f"{int(dontcare.sum())} DontCare rows")
    if table.unknown():
        notes.append(table.unknown())
    other = ~keep & known
    if other.any():
        names = sorted({TYPES[t] for t in table.type[other]})
        notes.append(f"{int(other.sum())} rows of classes not asked for ({', '.join(names)})")
    rows = np.flatnonzero(keep)
    box = table.box[rows]
    mot = MotTable(frame=table.frame[rows] + 1, id=table.id[rows],
                   box=np.concatenate([box[:, :2], box[:, 2:] - box[:, :2]], axis=1),
                   score=table.score[rows].copy(), cls=table.type[rows].copy(),
                   visibility=np.full(len(rows), -1.0), path=table.path,
                   line=None if table.line is None else table.line[rows])
    note = f"{table.path}: skipped " + "; ".join(notes) if notes else None
    return mot, rows, note


def write_kitti(path: str | os.PathLike, frame: np.ndarray, ids: np.ndarray, types: np.ndarray,
                box: np.ndarray, score: np.ndarray, box3d: np.ndarray | None = None,
                alpha: np.ndarray | None = None, overwrite: bool = False) -> None:
    """Write a KITTI tracking result file: `frame id type -1 -1 alpha x1 y1 x2 y2 h w l x y z
    rotation_y score`, frames 0-based as given, sorted by frame then id, whole or not at all
    (`occtrack.io.atomic`); "-" writes to standard output. `box` is x1, y1, x2, y2; `box3d`
    (h w l x y z rotation_y) and `alpha` default to KITTI's unknowns (-1, -1000, -10).
    Refuses to replace an existing file unless `overwrite`."""
    n = len(frame)
    box3d = np.tile(UNKNOWN_3D, (n, 1)) if box3d is None else box3d
    alpha = np.full(n, -10.0) if alpha is None else alpha
    order = np.lexsort((ids, frame))
    with atomic_write(path, overwrite) as fh:
        for i in order:
            x1, y1, x2, y2 = box[i]
            h, w, l, x, y, z, ry = box3d[i]
            fh.write(f"{int(frame[i])} {int(ids[i])} {TYPES[int(types[i])]} -1 -1 "
                     f"{alpha[i]:.6f} {x1:.2f} {y1:.2f} {x2:.2f} {y2:.2f} {h:.6f} {w:.6f} "
                     f"{l:.6f} {x:.6f} {y:.6f} {z:.6f} {ry:.6f} {score[i]:.4f}\n")


def clip_to_image(box: np.ndarray, image_size: tuple[float, float]) -> np.ndarray:
    """Corners x1, y1, x2, y2 clipped to the image [0, width] x [0, height], as KITTI's labels
    are (a tracker's box runs past a border it cannot see; scored against a clipped label,
    the part outside only costs overlap)."""
    width, height = image_size
    return np.clip(box, 0.0, [width, height, width, height])


def sequence_name(path: str | os.PathLike) -> str:
    """A KITTI file's sequence name: its stem (`0000` for `label_02/0000.txt`)."""
    return Path(path).stem


def layout_root(path: str | os.PathLike) -> Path | None:
    """The KITTI folder a file sits in: DIR for DIR/label_02/NNNN.txt and
    DIR/det_02/NAME/NNNN.txt; None elsewhere."""
    file = Path(path).resolve()
    if file.parent.name == "label_02":
        return file.parent.parent
    if file.parent.parent.name == "det_02":
        return file.parent.parent.parent
    return None


def find_seqinfo(path: str | os.PathLike) -> Path | None:
    """`DIR/seqinfo/NNNN.ini` for a file in a KITTI layout (`DIR/label_02/NNNN.txt`,
    `DIR/det_02/NAME/NNNN.txt`), or None if there is none."""
    root = layout_root(path)
    if root is None:
        return None
    ini = root / "seqinfo" / f"{sequence_name(path)}.ini"
    return ini if ini.is_file() else None
