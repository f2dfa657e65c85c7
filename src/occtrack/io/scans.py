"""Lidar scan files and their ground truth, as a user's own 2-D scanner could write them.

scans.csv, one row a beam, rows in time order, the beams of one scan sharing its time:

    time,angle,range
    0.000000,-3.137229,4.2831
    0.000000,-3.128502,inf

time in seconds, angle in radians counter-clockwise from the sensor's heading, range in metres,
`inf` where the beam returned nothing (as ROS's REP 117 has a LaserScan report "no return").
Lines starting with `#` are comments; `key=value` words in them are kept as the file's settings
(the simulator writes its sensor's there). `nan` and negative ranges are errors, as is a time
earlier than the row before: a bad row stops the read with the file, line and problem.

truth.csv, one row an object a scan (world frame; `sensor.csv` gives the sensor's pose):

    time,id,shape,x,y,vx,vy,length,width,heading,clear_beams,visible_beams,occluded

shape `disc` (length = width = its diameter) or `rect`; clear_beams: beams that would reach
the object were it alone; visible_beams: beams whose first surface it is; occluded: 1 when
clear_beams > 0 and visible_beams == 0 (fully occluded). sensor.csv: `time,x,y,heading`.

tracks.csv (`occtrack track-scans`, `write_tracks`; read by `read_tracks`), one row a
reported object a scan, world frame:

    time,id,x,y,vx,vy,existence,confidence,occluded

time s (the scan's), id a whole number >= 0 kept by the object and seen at most once a scan,
x, y m, vx, vy m/s, existence and confidence in [0, 1], occluded 0 or 1.

ground_truth_people_tracks.csv of the leg-tracker benchmark (Leigh et al., ICRA 2015;
`read_people`; see occtrack.metrics.leg_benchmark), one row a hand-clicked person:

    bag_time,id,x,y,z

bag_time the ROS bag's record time of the annotation, s (not a scan's time: the benchmark
scores it against the last scan recorded at or before it), id a whole number >= 0, x, y, z m
in the laser's frame. Times must not go back; `nan` is an error.

Reading is vectorised (numpy parses every cell at once); only when that fails are the rows
walked one by one to name the first bad cell.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from occtrack.errors import OcctrackError, opening
from occtrack.io.atomic import atomic_write

SCAN_COLUMNS = ("time", "angle", "range")
TRUTH_COLUMNS = ("time", "id", "shape", "x", "y", "vx", "vy", "length", "width", "heading",
                 "clear_beams", "visible_beams", "occluded")
POSE_COLUMNS = ("time", "x", "y", "heading")
TRACK_COLUMNS = ("time", "id", "x", "y", "vx", "vy", "existence", "confidence", "occluded")
PEOPLE_COLUMNS = ("bag_time", "id", "x", "y", "z")
SHAPES = ("disc", "rect")


# -- writing --------------------------------------------------------------------------------------

def header(columns: tuple[str, ...], comments: list[str]) -> str:
    """Comment lines, then the column names."""
    return "".join(f"# {c}\n" for c in comments) + ",".join(columns) + "\n"


def scan_rows(time: float, angle_text: list[str], ranges: np.ndarray) -> str:
    """One scan's rows; `angle_text` the beams' angles already formatted (they repeat)."""
    t = f"{time:.6f}"
    return "".join(f"{t},{a},{r:.4f}\n" for a, r in zip(angle_text, ranges.tolist(),
                                                      strict=True))


def angle_text(angle: np.ndarray) -> list[str]:
    return [f"{a:.6f}" for a in angle.tolist()]


def truth_rows(time: float, ids: np.ndarray, disc: np.ndarray, centre: np.ndarray,
               velocity: np.ndarray, length: np.ndarray, width: np.ndarray,
               heading: np.ndarray, clear: np.ndarray, visible: np.ndarray) -> str:
    """One scan's truth rows, an object each."""
    t = f"{time:.6f}"
    rows = zip(ids.tolist(), disc.tolist(), centre.tolist(), velocity.tolist(), length.tolist(),
               width.tolist(), heading.tolist(), clear.tolist(), visible.tolist(), strict=True)
    return "".join(
        f"{t},{i},{'disc' if d else 'rect'},{x:.4f},{y:.4f},{vx:.4f},{vy:.4f},{ln:.4f},"
        f"{w:.4f},{h:.6f},{c},{v},{int(c > 0 and v == 0)}\n"
        for i, d, (x, y), (vx, vy), ln, w, h, c, v in rows)


def pose_row(time: float, pose: np.ndarray) -> str:
    x, y, h = pose.tolist()
    return f"{time:.6f},{x:.4f},{y:.4f},{h:.6f}\n"


def write_tracks(path: str | os.PathLike, result, overwrite: bool = False) -> None:
    """A scan tracker's result (`occtrack.tracker.ScanTrackResult`) as a tracks file, the
    column names first, one row a reported object a scan in the order given: time to the
    microsecond, positions and velocities to 0.1 mm (/s), existence and confidence to six
    decimals, occluded 0 or 1, so one input gives the same file byte for byte. Written whole
    or not at all (`occtrack.io.atomic`); "-" writes to standard output."""
    rows = zip(result.time.tolist(), result.id.tolist(), result.position.tolist(),
               result.velocity.tolist(), result.existence.tolist(),
               result.confidence.tolist(), result.occluded.tolist(), strict=True)
    with atomic_write(path, overwrite) as fh:
        fh.write(",".join(TRACK_COLUMNS) + "\n")
        fh.writelines(f"{t:.6f},{int(i)},{x:.4f},{y:.4f},{vx:.4f},{vy:.4f},{r:.6f},{c:.6f},"
                      f"{int(h)}\n"
                      for t, i, (x, y), (vx, vy), r, c, h in rows)


# -- reading --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Scans:
    """Every beam of a scan file as flat arrays, grouped by scan: scan i holds rows
    start[i]:start[i + 1], taken at time[i]. range is inf where nothing returned."""

    time: np.ndarray  # (S,) s
    start: np.ndarray  # (S + 1,) row offsets
    angle: np.ndarray  # (N,) rad
    range: np.ndarray  # (N,) m
    settings: dict[str, str] = field(default_factory=dict)
    path: str = ""

    def __len__(self) -> int:
        return len(self.time)

    def __getitem__(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Scan i's angles and ranges."""
        rows = slice(self.start[i], self.start[i + 1])
        return self.angle[rows], self.range[rows]

    def __iter__(self):
        """(time, angle, range) a scan."""
        for i in range(len(self)):
            yield (float(self.time[i]), *self[i])


@dataclass(frozen=True)
class Truth:
    """A truth file's rows as arrays: time, id, disc (bool), centre (N, 2), velocity (N, 2),
    length, width, heading, clear, visible, occluded (bool)."""

    time: np.ndarray
    id: np.ndarray
    disc: np.ndarray
    centre: np.ndarray
    velocity: np.ndarray
    length: np.ndarray
    width: np.ndarray
    heading: np.ndarray
    clear: np.ndarray
    visible: np.ndarray
    occluded: np.ndarray
    path: str = ""

    def __len__(self) -> int:
        return len(self.time)


@dataclass(frozen=True)
class Tracks:
    """A scan tracker's rows, one an object a scan, as arrays: time, id, position (N, 2),
    velocity (N, 2), existence, confidence, occluded (bool); `path` the tracks file they were
    read from ("" for a run's own: `occtrack.tracker.ScanTrackResult` is this class)."""

    time: np.ndarray
    id: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    occluded: np.ndarray
    path: str = ""

    def __len__(self) -> int:
        return len(self.time)


@dataclass(frozen=True)
class People:
    """The leg-tracker benchmark's annotated people as arrays: time (the bag's record time),
    id, position (N, 2) and z (N,)."""

    time: np.ndarray
    id: np.ndarray
    position: np.ndarray
    z: np.ndarray
    path: str = ""

    def __len__(self) -> int:
        return len(self.time)


@dataclass(frozen=True)
class _Table:
    """A CSV file's cells by column, the file line of each row and the comments' settings."""

    cells: dict[str, list[str]]
    line: np.ndarray
    settings: dict[str, str]
    path: str

    def fail(self, row: int, problem: str) -> OcctrackError:
        return OcctrackError(problem, self.path, int(self.line[row]))


def _lines(path: str, expected: str) -> list[str]:
    try:
        with opening(path, expected), open(path, encoding="utf-8", newline="") as fh:
            return fh.read().splitlines()
    except UnicodeDecodeError as err:
        raise OcctrackError(f"not a text file (byte {err.start} is not UTF-8)", path) from None


def _settings(comment: str) -> dict[str, str]:
    return dict(w.split("=", 1) for w in comment.lstrip("#").split() if "=" in w)


def _table(path: str, columns: tuple[str, ...], expected: str) -> _Table:
    """Rows split into cells, each with the right number of columns; comments, blank lines
    and one line of column names skipped. Per line only C-level string methods run: a scan
    file has a million rows."""
    lines = [line.strip() for line in _lines(path, expected)]
    if lines:
        lines[0] = lines[0].lstrip("\ufeff")
    settings: dict[str, str] = {}
    for line in (line for line in lines if line.startswith("#")):
        settings.update(_settings(line))
    rows = [i for i, line in enumerate(lines) if line and line[0] != "#"]
    if rows and [p.strip() for p in lines[rows[0]].split(",")] == list(columns):
        rows = rows[1:]
    commas = np.fromiter((lines[i].count(",") for i in rows), np.int64, len(rows))
    wrong = np.flatnonzero(commas != len(columns) - 1)
    if len(wrong):
        line = lines[rows[wrong[0]]]
        raise OcctrackError(f"expected {len(columns)} columns ({', '.join(columns)}), "
                            f"found {commas[wrong[0]] + 1}: {line[:60]!r}", path,
                            rows[wrong[0]] + 1)
    flat = ",".join(lines[i] for i in rows).split(",") if rows else []
    cells = {name: flat[k::len(columns)] for k, name in enumerate(columns)}
    return _Table(cells, np.array(rows, dtype=np.int64) + 1, settings, path)


def _numbers(table: _Table, name: str) -> np.ndarray:
    """A column as floats; the first cell that is not a number is an error."""
    cells = table.cells[name]
    try:
        return np.array(cells, dtype=float).reshape(len(cells))
    except ValueError:
        for row, text in enumerate(cells):
            try:
                float(text)
            except ValueError:
                raise table.fail(row, f"{name} is not a number: {text!r}") from None
        raise  # pragma: no cover - numpy refused what float() reads


def _first(table: _Table, bad: np.ndarray, problem) -> None:
    """An error for the first row flagged in `bad`; `problem(row)` words it."""
    rows = np.flatnonzero(bad)
    if len(rows):
        raise table.fail(rows[0], problem(rows[0]))


def _finite(table: _Table, name: str) -> np.ndarray:
    values = _numbers(table, name)
    _first(table, ~np.isfinite(values), lambda r: f"{name} is {table.cells[name][r]}; "
                                                  f"it must be a finite number")
    return values


def _time(table: _Table, name: str = "time") -> np.ndarray:
    t = _finite(table, name)
    back = np.r_[False, t[1:] < t[:-1]]
    _first(table, back, lambda r: f"{name} {table.cells[name][r]} is earlier than the row "
                                  f"before ({table.cells[name][r - 1]}): rows must be in "
                                  f"time order")
    return t


def _whole(table: _Table, name: str, low: int) -> np.ndarray:
    values = _finite(table, name)
    _first(table, (values != np.round(values)) | (values < low),
           lambda r: f"{name} {table.cells[name][r]} is not a whole number >= {low}")
    return values.astype(np.int64)


def read_scans(path: str | os.PathLike) -> Scans:
    """A scan file (see the module docstring), checked row by row."""
    table = _table(str(path), SCAN_COLUMNS, "a lidar scan file (time,angle,range rows)")
    time = _time(table)
    angle = _finite(table, "angle")
    rng = _numbers(table, "range")
    _first(table, np.isnan(rng), lambda r: f"range is {table.cells['range'][r]}; write inf "
                                           f"for a beam with no return")
    _first(table, rng < 0, lambda r: f"range {table.cells['range'][r]} is negative")
    new = np.flatnonzero(np.r_[True, time[1:] != time[:-1]]) if len(time) else np.zeros(0, int)
    return Scans(time[new], np.r_[new, len(time)].astype(np.int64), angle, rng,
                 table.settings, str(path))


def row_line(path: str | os.PathLike, columns: tuple[str, ...], row: int) -> int:
    """The file line (1-based) of data row `row` (0-based, comments, blank lines and the
    column names not counted) of a file read with `columns`: for an error found after the
    read. Reads the file again, so call it on the way to an error only."""
    return int(_table(str(path), columns, "a CSV file").line[row])


def read_truth(path: str | os.PathLike) -> Truth:
    """A truth file (see the module docstring), checked row by row."""
    table = _table(str(path), TRUTH_COLUMNS, "a lidar truth file")
    shape = [cell.strip() for cell in table.cells["shape"]]
    _first(table, ~np.isin(shape, SHAPES),
           lambda r: f"shape {shape[r]!r} is not one of {', '.join(SHAPES)}")
    length, width = _finite(table, "length"), _finite(table, "width")
    _first(table, (length <= 0) | (width <= 0), lambda r: "length and width must be positive")
    occluded = _whole(table, "occluded", 0)
    _first(table, occluded > 1, lambda r: "occluded must be 0 or 1")
    xy = np.c_[_finite(table, "x"), _finite(table, "y")]
    v = np.c_[_finite(table, "vx"), _finite(table, "vy")]
    return Truth(_time(table), _whole(table, "id", 0), np.array(shape) == "disc", xy, v,
                 length, width, _finite(table, "heading"), _whole(table, "clear_beams", 0),
                 _whole(table, "visible_beams", 0), occluded.astype(bool), str(path))


def read_poses(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """A sensor file: times (S,) and poses (S, 3) x, y, heading."""
    table = _table(str(path), POSE_COLUMNS, "a lidar sensor pose file")
    pose = np.c_[_finite(table, "x"), _finite(table, "y"), _finite(table, "heading")]
    return _time(table), pose.reshape(-1, 3)


def read_tracks(path: str | os.PathLike) -> Tracks:
    """A tracks file (see the module docstring), checked row by row: besides the cells, an id
    seen twice at one time is an error naming the second row's line."""
    table = _table(str(path), TRACK_COLUMNS, "a tracks file (occtrack track-scans' output)")
    time, ids = _time(table), _whole(table, "id", 0)
    xy = np.c_[_finite(table, "x"), _finite(table, "y")].reshape(-1, 2)
    v = np.c_[_finite(table, "vx"), _finite(table, "vy")].reshape(-1, 2)
    share = {}
    for name in ("existence", "confidence"):
        share[name] = _finite(table, name)
        _first(table, (share[name] < 0) | (share[name] > 1),
               lambda r, name=name: f"{name} {table.cells[name][r]} is not in [0, 1]")
    occluded = _whole(table, "occluded", 0)
    _first(table, occluded > 1, lambda r: "occluded must be 0 or 1")
    order = np.lexsort((np.arange(len(time)), ids, time))
    again = np.zeros(len(time), bool)
    again[order[1:]] = (np.diff(time[order]) == 0) & (np.diff(ids[order]) == 0)
    _first(table, again, lambda r: f"id {ids[r]} appears twice at time "
                                   f"{table.cells['time'][r]}: a tracks file reports an object "
                                   f"once a scan")
    return Tracks(time, ids, xy, v, share["existence"], share["confidence"],
                  occluded.astype(bool), str(path))


def read_people(path: str | os.PathLike) -> People:
    """The leg-tracker benchmark's annotation file, `bag_time,id,x,y,z` (see the module
    docstring), checked row by row."""
    table = _table(str(path), PEOPLE_COLUMNS,
                   "a people annotation file (bag_time,id,x,y,z rows)")
    time = _time(table, "bag_time")
    xy = np.c_[_finite(table, "x"), _finite(table, "y")].reshape(-1, 2)
    return People(time, _whole(table, "id", 0), xy, _finite(table, "z"), str(path))


def check_beam_order(scans: Scans) -> None:
    """OcctrackError naming the file and line of the first beam whose angle is not above the
    one before it in its scan (a tracker takes a scan's beams in increasing angle)."""
    bad = np.r_[False, np.diff(scans.angle) <= 0]
    bad[scans.start[:-1]] = False  # a scan's first beam follows the last scan's last
    rows = np.flatnonzero(bad)
    if len(rows):
        r = int(rows[0])
        raise OcctrackError(f"angle {scans.angle[r]:g} is not above the beam before it "
                            f"({scans.angle[r - 1]:g}) in the scan at time "
                            f"{scans.time[np.searchsorted(scans.start, r, 'right') - 1]:g}: a "
                            f"scan's beams must be in increasing angle order", scans.path,
                            row_line(scans.path, SCAN_COLUMNS, r))


def match_poses(scans: Scans, path: str | os.PathLike, times: np.ndarray,
                tolerance: float = 1e-6) -> None:
    """OcctrackError naming the pose file `path` and its first line whose time is not the
    time of the scan at the same place (to within `tolerance` s), or the first scan it has no
    pose for: a pose file (`read_poses`) gives one pose a scan, in the scans' order."""
    n = min(len(times), len(scans))
    off = np.flatnonzero(np.abs(times[:n] - scans.time[:n]) > tolerance)
    if len(off):
        k = int(off[0])
        raise OcctrackError(f"time {times[k]:.6f} is not the time of scan {k + 1} of "
                            f"{scans.path} ({scans.time[k]:.6f}); a pose file gives one pose a "
                            f"scan, at the scan's time", str(path),
                            row_line(path, POSE_COLUMNS, k))
    if len(times) > n:
        last = f", the last at {scans.time[-1]:.6f}" if len(scans) else ""
        raise OcctrackError(f"time {times[n]:.6f} has no scan: {scans.path} holds "
                            f"{len(scans)} scans{last}; a pose file gives one pose a scan",
                            str(path), row_line(path, POSE_COLUMNS, n))
    if len(scans) > n:
        raise OcctrackError(f"no pose for scan {n + 1} of {scans.path} (time "
                            f"{scans.time[n]:.6f}): {n} poses for {len(scans)} scans; a pose "
                            f"file gives one pose a scan", str(path))
