"""MOTChallenge text files: detections, ground truth and tracker results.

Rows are `frame, id, left, top, width, height, score_or_flag, class, visibility[, ...]`.
Files are read the way TrackEval reads them (comma or whitespace separated, CRLF accepted,
extra columns ignored), but every row is checked and a bad one stops the read with the file,
line and problem: nothing is dropped or altered silently. Frames and ids (and the class of
ground truth and results) are whole numbers, written "3" or "3.0" as TrackEval accepts; a
fractional one such as 2.5 is an error, not truncated. Frames run from 1 to 2**31 - 1 and ids
fit in 32 bits, so no later arithmetic on them can overflow. The class column of a detection
file is unused and kept only when it is a whole number (else -1).
"""

from __future__ import annotations

import configparser
import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError, opening
from occtrack.io.atomic import atomic_write

KINDS = ("det", "gt", "result")
MAX_COORDINATE = 1e6
"""px: a box coordinate or size beyond this is no box of any image (`MAX_IMAGE_SIDE` is
1e5); the filter's arithmetic is safe for everything within it. Files and the tracker's API
(`occtrack.tracker.boxes`) both check it."""
MAX_FRAME = 2**31 - 1
MIN_ID, MAX_ID = -(2**31), 2**31 - 1


@dataclass(frozen=True)
class MotTable:
    """Columns of a MOTChallenge file as plain arrays, one entry a row."""

    frame: np.ndarray  # (N,) int, 1-based
    id: np.ndarray  # (N,) int; -1 in detection files
    box: np.ndarray  # (N, 4) float: left, top, width, height
    score: np.ndarray  # (N,) float: detection score, gt consider flag, or result confidence
    cls: np.ndarray  # (N,) int: gt class, -1 where absent
    visibility: np.ndarray  # (N,) float: gt visibility, -1 where absent
    path: str = ""
    line: np.ndarray | None = None  # (N,) int: 1-based line in `path`; None if not from a file

    def __len__(self) -> int:
        return len(self.frame)

    @property
    def num_frames(self) -> int:
        return int(self.frame.max()) if len(self) else 0

    def select(self, mask: np.ndarray) -> MotTable:
        return MotTable(self.frame[mask], self.id[mask], self.box[mask], self.score[mask],
                        self.cls[mask], self.visibility[mask], self.path,
                        None if self.line is None else self.line[mask])

    def frame_slices(self, num_frames: int | None = None) -> list[np.ndarray]:
        """Row indices of each frame 1..num_frames (index f-1), empty where a frame has none."""
        n = self.num_frames if num_frames is None else num_frames
        order = np.argsort(self.frame, kind="stable")
        bounds = np.searchsorted(self.frame[order], np.arange(1, n + 2))
        return [order[bounds[f]:bounds[f + 1]] for f in range(n)]


def _split(line: str) -> list[str]:
    if "," not in line:
        return line.split()
    parts = [part.strip() for part in line.split(",")]
    while parts and parts[-1] == "":
        parts.pop()
    return parts


def _whole(text: str, value: float, what: str, low: int, high: int, path: str,
           line: int) -> int:
    """An integer column: "3" or "3.0" (TrackEval reads both), nothing fractional, in range."""
    try:
        number = int(text)
    except ValueError:
        if not value.is_integer():
            raise OcctrackError(f"{what} {text} is not a whole number", path, line) from None
        number = int(value)
    if number < low and what == "frame":
        raise OcctrackError(f"frame {text} is below 1 (frames are 1-based)", path, line)
    if not low <= number <= high:
        raise OcctrackError(f"{what} {text} is out of range: {what}s run from {low} to {high}",
                            path, line)
    return number


CHUNK = 1 << 16  # rows parsed into Python lists before they are moved into the arrays


def _line_bound(path: str) -> int | None:
    """At least the number of lines of a regular file (None for a pipe or a device, which
    cannot be read twice): newlines, plus lone carriage returns, plus one. Counted in 16 MB
    blocks, so the arrays can be allocated once, at their final size."""
    if not os.path.isfile(path):
        return None
    count = 1
    with open(path, "rb") as fh:
        while block := fh.read(1 << 24):
            count += block.count(b"\n") + block.count(b"\r") - block.count(b"\r\n")
    return count


class _Columns:
    """The parsed columns, filled chunk by chunk: into arrays allocated once at `capacity`
    rows when the line count is known (a regular file), else grown by doubling. Memory is the
    table's own, 80 bytes a row, never the file's text or a Python object a cell (which took
    16 times the file's size)."""

    def __init__(self, capacity: int | None):
        self.size = 0
        self.columns = self._empty(capacity or CHUNK)

    @staticmethod
    def _empty(rows: int) -> dict[str, np.ndarray]:
        out = {name: np.empty(rows, dtype=np.int64) for name in ("frame", "id", "cls", "line")}
        out["box"] = np.empty((rows, 4), dtype=float)
        out["score"] = np.empty(rows, dtype=float)
        out["visibility"] = np.empty(rows, dtype=float)
        return out

    def add(self, whole: np.ndarray, real: np.ndarray) -> None:
        """Append n rows: (n, 4) frame, id, class, line and (n, 6) box, score, visibility."""
        n = len(whole)
        if not n:
            return
        room = len(self.columns["frame"])
        if self.size + n > room:  # a pipe (unknown length), or lines the count did not see
            grown = self._empty(max(2 * room, self.size + n))
            for name, column in self.columns.items():
                grown[name][:self.size] = column[:self.size]
            self.columns = grown
        rows = slice(self.size, self.size + n)
        c = self.columns
        c["frame"][rows], c["id"][rows] = whole[:, 0], whole[:, 1]
        c["cls"][rows], c["line"][rows] = whole[:, 2], whole[:, 3]
        c["box"][rows], c["score"][rows], c["visibility"][rows] = (real[:, :4], real[:, 4],
                                                                    real[:, 5])
        self.size += n

    def table(self, path: str) -> MotTable:
        c = {name: column[:self.size] for name, column in self.columns.items()}
        return MotTable(path=path, **c)


def _read(path: str, kind: str) -> MotTable:
    """Every row of a MOTChallenge file, checked cell by cell but not for meaning. The file is
    streamed line by line (lines end in LF, CRLF or CR), so memory follows the rows kept."""
    strict_class = kind != "det"
    try:
        with (opening(path, "a MOTChallenge text file"),
              open(path, encoding="utf-8", newline="") as fh):
            columns = _Columns(_line_bound(path))
            lines: list[str] = []
            numbers: list[int] = []
            for number, raw in enumerate(fh, start=1):
                line = raw.strip().lstrip("\ufeff")
                if not line:
                    continue
                lines.append(line)
                numbers.append(number)
                if len(lines) == CHUNK:
                    columns.add(*_chunk(lines, numbers, path, strict_class))
                    lines, numbers = [], []
            columns.add(*_chunk(lines, numbers, path, strict_class))
    except UnicodeDecodeError as err:
        raise OcctrackError(f"not a text file (byte {err.start} is not UTF-8)", path) from None
    return columns.table(path)


def _chunk(lines: list[str], numbers: list[int], path: str,
           strict_class: bool) -> tuple[np.ndarray, np.ndarray]:
    """Rows of a chunk as (n, 4) whole numbers (frame, id, class, line) and (n, 6) reals (box,
    score, visibility). numpy's C parser reads a chunk whose rows all have one layout and
    pass every check (the files trackers write); any other chunk is read row by row by
    `_row`, which accepts what TrackEval accepts and names the first bad line."""
    if not lines:
        return np.zeros((0, 4), dtype=np.int64), np.zeros((0, 6))
    fast = _fast_chunk(lines, numbers, strict_class)
    if fast is not None:
        return fast
    reals: list[tuple] = []
    whole = [_row(line, number, path, strict_class, reals)
             for line, number in zip(lines, numbers, strict=True)]
    return np.array(whole, dtype=np.int64), np.array(reals, dtype=float)


def _fast_chunk(lines: list[str], numbers: list[int],
                strict_class: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """`_chunk` by numpy.loadtxt, or None when a row needs `_row`'s reading or its message."""
    comma = "," in lines[0]
    if any(("," in line) != comma or line.endswith(",") for line in lines):
        return None
    try:
        values = np.loadtxt(lines, delimiter="," if comma else None, ndmin=2, dtype=float,
                            comments=None)
    except ValueError:  # ragged rows, a cell that is not a number
        return None
    n, width = values.shape
    if width < 6 or not np.isfinite(values[:, :9]).all():
        return None
    frame, ident = values[:, 0], values[:, 1]
    whole_ok = ((frame == np.floor(frame)) & (frame >= 1) & (frame <= MAX_FRAME)
                & (ident == np.floor(ident)) & (ident >= MIN_ID) & (ident <= MAX_ID))
    cls = np.full(n, -1.0)
    if width > 7:
        c = values[:, 7]
        integral = (c == np.floor(c)) & (c >= MIN_ID) & (c <= MAX_ID)
        if strict_class:
            whole_ok &= integral
        cls = np.where(integral, c, -1.0)
    if not whole_ok.all():
        return None
    whole = np.empty((n, 4), dtype=np.int64)
    whole[:, 0], whole[:, 1], whole[:, 2] = frame, ident, cls
    whole[:, 3] = numbers
    reals = np.empty((n, 6))
    reals[:, :4] = values[:, 2:6]
    reals[:, 4] = values[:, 6] if width > 6 else 1.0
    reals[:, 5] = values[:, 8] if width > 8 else -1.0
    return whole, reals


def _row(line: str, number: int, path: str, strict_class: bool, reals: list) -> tuple:
    """One row's whole-number columns (frame, id, class, line number); its real columns (box,
    score, visibility) are appended to `reals`."""
    parts = _split(line)
    if len(parts) < 6:
        raise OcctrackError(f"expected at least 6 columns (frame, id, left, top, width, "
                            f"height), found {len(parts)}: {line[:60]!r}", path, number)
    values = []
    for col, text in enumerate(parts[:9]):
        try:
            v = float(text)
        except ValueError:
            raise OcctrackError(f"column {col + 1} is not a number: {text!r}",
                                path, number) from None
        if math.isnan(v) or math.isinf(v):
            raise OcctrackError(f"column {col + 1} is {text}", path, number)
        values.append(v)
    frame = _whole(parts[0], values[0], "frame", 1, MAX_FRAME, path, number)
    ident = _whole(parts[1], values[1], "id", MIN_ID, MAX_ID, path, number)
    cls = -1
    if len(values) > 7:
        if strict_class:
            cls = _whole(parts[7], values[7], "class", MIN_ID, MAX_ID, path, number)
        elif values[7].is_integer() and MIN_ID <= values[7] <= MAX_ID:
            cls = int(values[7])
    reals.append((*values[2:6], values[6] if len(values) > 6 else 1.0,
                  values[8] if len(values) > 8 else -1.0))
    return frame, ident, cls, number


def read_mot(path: str | os.PathLike, kind: str = "det",
             max_gap_frames: int | None = None) -> MotTable:
    """Read a MOTChallenge file: "det", "gt" or "result". Rows may come in any frame order
    (the MOT17 detection files do not keep it); every row is kept, and `frame_slices`
    groups them by frame with a stable sort. `max_gap_frames` (None: no limit) bounds the run
    of empty frames before a row, so a stray huge frame number is an error, not a long loop."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}")
    table = _read(str(path), kind)
    negative = np.flatnonzero((table.box[:, 2] < 0) | (table.box[:, 3] < 0))
    if len(negative):
        i = negative[0]
        raise OcctrackError(f"negative box size {table.box[i, 2]:g} x {table.box[i, 3]:g}",
                            table.path, int(table.line[i]))
    if kind == "gt":
        twice = first_duplicate(table.frame, table.id)
        if twice is not None:
            a, b = table.line[list(twice)]
            raise OcctrackError(f"id {table.id[twice[0]]} appears twice in frame "
                                f"{table.frame[twice[0]]} (lines {a} and {b})", table.path, b)
    if max_gap_frames is not None:
        check_gaps(table, max_gap_frames)
    return table


def read_detections(path: str | os.PathLike, image_size: tuple[float, float], *,
                    score_range: tuple[float, float] | None = None, lenient: bool = False,
                    max_gap_frames: int | None = None,
                    num_frames: int | None = None) -> tuple[MotTable, str | None]:
    """A detection file to track, and a warning (None if there is nothing to say).

    A box wholly outside the image is real detector output (a detector run on a padded or
    resized frame reports them): it is skipped, and the warning gives the count and the first
    line. A row with a zero or negative size, or a score outside [0, 1] (after `score_range`
    (lo, hi) maps lo..hi linearly onto 0..1), is an error naming its line, unless `lenient`:
    then such boxes are skipped and such scores clipped, with their counts in the warning.
    A row that repeats another of its frame exactly is merged into it, with a count."""
    return check_detections(_read(str(path), "det"), image_size, score_range=score_range,
                            lenient=lenient, max_gap_frames=max_gap_frames,
                            num_frames=num_frames)


def check_detections(table: MotTable, image_size: tuple[float, float], *,
                     score_range: tuple[float, float] | None = None, lenient: bool = False,
                     max_gap_frames: int | None = None,
                     num_frames: int | None = None) -> tuple[MotTable, str | None]:
    """`read_detections`' checks on a table already read (from any format)."""
    width, height = image_size
    left, top, w, h = table.box.T
    bad_size = (w <= 0) | (h <= 0)
    for column in (left, top, w, h):  # one column at a time: no (N, 4) temporary
        bad_size |= np.abs(column) > MAX_COORDINATE
    outside = ~bad_size & ((left + w <= 0) | (top + h <= 0) | (left >= width) | (top >= height))
    score = table.score
    if score_range is not None:
        low, high = score_range
        score = (score - low) / (high - low)
    off = (score < 0) | (score > 1)
    size = f"{width:g}x{height:g}"
    if not lenient and (bad_size | off).any():
        i = int(np.argmax(bad_size | off))
        l_, t_, w_, h_ = table.box[i]
        if bad_size[i] and np.abs(table.box[i]).max() > MAX_COORDINATE:
            problem = (f"box at ({l_:g}, {t_:g}) of size {w_:g} x {h_:g} has a coordinate "
                       f"beyond {MAX_COORDINATE:g} px: no image is that large; pass --lenient "
                       f"to skip such rows")
        elif bad_size[i]:
            problem = (f"box size {w_:g} x {h_:g}: width and height must be positive; pass "
                       f"--lenient to skip such rows")
        elif score_range is None:
            problem = (f"score {table.score[i]:g} is outside [0, 1] (this file's scores run "
                       f"from {table.score.min():g} to {table.score.max():g}); pass "
                       f"--score-range LO,HI to map the detector's scores onto [0, 1], or "
                       f"--lenient to clip them")
        else:
            problem = (f"score {table.score[i]:g} is outside --score-range {low:g},{high:g} "
                       f"(this file's scores run from {table.score.min():g} to "
                       f"{table.score.max():g}); widen the range, or pass --lenient to clip")
        raise OcctrackError(problem, table.path, int(table.line[i]))

    notes = []
    skip = bad_size | outside
    if outside.any():
        notes.append(f"skipped {int(outside.sum())} boxes wholly outside the {size} image "
                     f"(first at line {table.line[outside][0]}; check the image size if "
                     f"that is many)")
    if bad_size.any():
        notes.append(f"skipped {int(bad_size.sum())} rows with a zero or negative size or a "
                     f"coordinate beyond {MAX_COORDINATE:g} px (first at line "
                     f"{table.line[bad_size][0]})")
    clipped = off & ~skip
    if clipped.any():
        notes.append(f"clipped {int(clipped.sum())} scores to [0, 1] (first at line "
                     f"{table.line[clipped][0]})")
    if off.any() or score_range is not None:
        table = dataclasses.replace(table, score=np.clip(score, 0.0, 1.0))
    if skip.any():  # (else no copy: a long file's table is the largest thing in memory)
        table = table.select(~skip)
    del left, top, w, h, bad_size, outside, score, off, skip, clipped
    twins = exact_duplicates(table)
    if twins.any():
        first = int(np.flatnonzero(twins)[0])
        notes.append(f"merged {int(twins.sum())} rows that repeat another row of their frame "
                     f"exactly (first at line {table.line[first]}; a file concatenated "
                     f"twice?)")
        table = table.select(~twins)
    if max_gap_frames is not None:
        check_gaps(table, max_gap_frames, num_frames)
    return table, (f"{table.path}: " + "; ".join(notes)) if notes else None


def exact_duplicates(table: MotTable) -> np.ndarray:
    """(N,) bool: the rows that repeat an earlier row of the same frame exactly (frame, box,
    score and class): one detection written twice, which a tracker would take for two
    objects in the same place."""
    n = len(table)
    twins = np.zeros(n, dtype=bool)
    if n < 2:
        return twins
    # Whole frames at a time, a block of about CHUNK rows, so that a long file needs a few
    # bytes a row here rather than copies of the table.
    by_frame = np.argsort(table.frame, kind="stable")
    ends = np.searchsorted(table.frame[by_frame], table.frame[by_frame[
        np.arange(CHUNK, n, CHUNK)]], side="right")
    for rows in np.split(by_frame, np.unique(ends)):
        if len(rows) < 2:
            continue
        keys = [table.frame[rows], *table.box[rows].T, table.score[rows], table.cls[rows]]
        order = np.lexsort(keys[::-1])  # stable: of equal rows, the earliest comes first
        same = np.ones(len(rows) - 1, dtype=bool)
        for key in keys:
            column = key[order]
            same &= column[1:] == column[:-1]
        twins[rows[order[1:][same]]] = True
    return twins


def check_gaps(table: MotTable, max_gap_frames: int, num_frames: int | None = None,
               flag: str | None = "--max-gap-frames") -> None:
    """Refuse more than `max_gap_frames` empty frames in a row: before the first row, between
    rows, or after the last up to `num_frames`. A tracker steps through every frame, so one
    stray frame number of 10^9 would otherwise mean a billion steps. `flag` is the option
    that raises the bound, named in the message (None: the command has none)."""
    frames = np.unique(table.frame)
    if not len(frames):
        return
    limit = f"more than the {max_gap_frames} allowed; check the frame numbers" + (
        f", or raise {flag} if the gap is real" if flag else "")

    def first_line(frame: int) -> int | None:
        return None if table.line is None else int(table.line[table.frame == frame].min())

    if frames[0] - 1 > max_gap_frames:
        raise OcctrackError(f"the first row is in frame {frames[0]}, after {frames[0] - 1} "
                            f"empty frames: {limit}", table.path or None, first_line(frames[0]))
    gaps = np.flatnonzero(np.diff(frames) - 1 > max_gap_frames)
    if len(gaps):
        a, b = frames[gaps[0]], frames[gaps[0] + 1]
        raise OcctrackError(f"frame {b} follows frame {a} after {b - a - 1} empty frames: "
                            f"{limit}", table.path or None, first_line(b))
    if num_frames is not None and num_frames - frames[-1] > max_gap_frames:
        raise OcctrackError(f"the last row is in frame {frames[-1]} but the sequence has "
                            f"{num_frames} frames (seqinfo.ini): {num_frames - frames[-1]} empty "
                            f"frames at the end, {limit}", table.path or None)


def first_duplicate(frame: np.ndarray, ids: np.ndarray) -> tuple[int, int] | None:
    """Indices of two rows with the same frame and id (the earliest such pair in frame and id
    order), or None. Sorts the pairs instead of combining them into one number, so no id or
    frame, however large, can overflow into another's key."""
    if len(frame) < 2:
        return None
    order = np.lexsort((np.arange(len(frame)), ids, frame))
    f, i = frame[order], ids[order]
    same = np.flatnonzero((f[1:] == f[:-1]) & (i[1:] == i[:-1]))
    if not len(same):
        return None
    return int(order[same[0]]), int(order[same[0] + 1])


def write_mot(path: str | os.PathLike, frame: np.ndarray, ids: np.ndarray, box: np.ndarray,
              score: np.ndarray | None = None, overwrite: bool = False) -> None:
    """Write a result file `frame,id,left,top,width,height,score,-1,-1,-1`, sorted by frame
    then id, whole or not at all (`occtrack.io.atomic`); "-" writes to standard output.
    Refuses to replace an existing file unless `overwrite`."""
    score = np.ones(len(frame)) if score is None else score
    order = np.lexsort((ids, frame))
    with atomic_write(path, overwrite) as fh:
        for chunk in range(0, len(order), CHUNK):
            rows = order[chunk:chunk + CHUNK]
            fh.write(mot_rows(frame[rows], ids[rows], box[rows], score[rows]))


def mot_rows(frame: np.ndarray, ids: np.ndarray, box: np.ndarray, score: np.ndarray) -> str:
    """Result rows `frame,id,left,top,width,height,score,-1,-1,-1` as text, in the order given."""
    return "".join(f"{int(f)},{int(i)},{b[0]:.2f},{b[1]:.2f},{b[2]:.2f},{b[3]:.2f},{s:.4f},"
                   f"-1,-1,-1\n" for f, i, b, s in zip(frame, ids, box, score, strict=True))


def read_seqinfo(folder: str | os.PathLike) -> dict[str, int | str]:
    """`seqinfo.ini` of a MOTChallenge sequence folder (or an .ini file itself, as KITTI's
    `seqinfo/NNNN.ini`) as {"name", "width", "height", "length", "fps"}, read from its name,
    imWidth, imHeight, seqLength and frameRate."""
    ini = Path(folder)
    if not (ini.suffix == ".ini" and ini.is_file()):
        ini = ini / "seqinfo.ini"
    parser = configparser.ConfigParser()
    try:
        with open(ini, encoding="utf-8") as fh:
            parser.read_file(fh)
        s = parser["Sequence"]
        default = ini.parent.name if ini.name == "seqinfo.ini" else ini.stem
        info = {"name": s.get("name", default), "width": int(s["imWidth"]),
                "height": int(s["imHeight"]), "length": int(s["seqLength"]),
                "fps": int(float(s.get("frameRate", "30")))}
    except FileNotFoundError:
        raise OcctrackError("no seqinfo.ini here", str(ini)) from None
    except (KeyError, ValueError, OverflowError, configparser.Error) as err:
        raise OcctrackError(f"malformed seqinfo.ini: {err}", str(ini)) from None
    for key in ("width", "height", "length", "fps"):
        if not 1 <= info[key] <= MAX_FRAME:
            raise OcctrackError(f"malformed seqinfo.ini: {key} {info[key]} is not a positive "
                                f"whole number below 2**31", str(ini))
    return info


def find_seqinfo(mot_file: str | os.PathLike) -> Path | None:
    """The sequence folder of a file at SEQ/det/det.txt or SEQ/gt/gt.txt, if it has a
    seqinfo.ini."""
    seq = Path(mot_file).resolve().parent.parent
    return seq if (seq / "seqinfo.ini").is_file() else None
