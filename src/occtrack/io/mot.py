"""MOTChallenge text files: detections, ground truth and tracker results.

Rows are `frame, id, left, top, width, height, score_or_flag, class, visibility[, ...]`.
Files are read the way TrackEval reads them (comma or whitespace separated, CRLF accepted,
float ids and frames truncated to integers, extra columns ignored), but every row is checked and
a bad one stops the read with the file, line and problem: nothing is dropped silently.
"""

from __future__ import annotations

import configparser
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError

KINDS = ("det", "gt", "result")


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

    def __len__(self) -> int:
        return len(self.frame)

    @property
    def num_frames(self) -> int:
        return int(self.frame.max()) if len(self) else 0

    def select(self, mask: np.ndarray) -> MotTable:
        return MotTable(self.frame[mask], self.id[mask], self.box[mask], self.score[mask],
                        self.cls[mask], self.visibility[mask], self.path)

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


def read_mot(path: str | os.PathLike, kind: str = "det") -> MotTable:
    """Read a MOTChallenge file: "det", "gt" or "result". Rows may come in any frame order
    (the MOT17 detection files do not keep it); every row is kept, and `frame_slices`
    groups them by frame with a stable sort."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}")
    p = str(path)
    try:
        with open(p, encoding="utf-8", newline="") as fh:
            lines = fh.read().splitlines()
    except FileNotFoundError:
        raise OcctrackError("no such file", p) from None
    except IsADirectoryError:
        raise OcctrackError("is a directory, expected a MOTChallenge text file", p) from None
    except UnicodeDecodeError:
        raise OcctrackError("not a text file", p) from None

    rows: list[tuple] = []
    for number, raw in enumerate(lines, start=1):
        line = raw.strip().lstrip("\ufeff")
        if not line:
            continue
        parts = _split(line)
        if len(parts) < 6:
            raise OcctrackError(f"expected at least 6 columns (frame, id, left, top, width, "
                                f"height), found {len(parts)}: {line[:60]!r}", p, number)
        values = []
        for col, text in enumerate(parts[:9]):
            try:
                v = float(text)
            except ValueError:
                raise OcctrackError(f"column {col + 1} is not a number: {text!r}",
                                    p, number) from None
            if math.isnan(v) or math.isinf(v):
                raise OcctrackError(f"column {col + 1} is {text}", p, number)
            values.append(v)
        frame = int(values[0])
        if frame < 1:
            raise OcctrackError(f"frame {values[0]:g} is below 1 (frames are 1-based)", p, number)
        if values[4] < 0 or values[5] < 0:
            raise OcctrackError(f"negative box size {values[4]:g} x {values[5]:g}", p, number)
        score = values[6] if len(values) > 6 else 1.0
        cls = int(values[7]) if len(values) > 7 else -1
        vis = values[8] if len(values) > 8 else -1.0
        rows.append((frame, int(values[1]), values[2], values[3], values[4], values[5],
                     score, cls, vis))

    if kind == "gt":
        _check_unique_ids(rows, p)
    arr = np.array(rows, dtype=float).reshape(-1, 9)
    return MotTable(frame=arr[:, 0].astype(np.int64), id=arr[:, 1].astype(np.int64),
                    box=arr[:, 2:6].copy(), score=arr[:, 6].copy(),
                    cls=arr[:, 7].astype(np.int64), visibility=arr[:, 8].copy(), path=p)


def _check_unique_ids(rows: list[tuple], path: str) -> None:
    seen: dict[tuple[int, int], int] = {}
    for index, row in enumerate(rows):
        key = (row[0], row[1])
        if key in seen:
            raise OcctrackError(f"id {row[1]} appears twice in frame {row[0]} "
                                f"(rows {seen[key] + 1} and {index + 1})", path)
        seen[key] = index


def write_mot(path: str | os.PathLike, frame: np.ndarray, ids: np.ndarray, box: np.ndarray,
              score: np.ndarray | None = None, overwrite: bool = False) -> None:
    """Write a result file `frame,id,left,top,width,height,score,-1,-1,-1`, sorted by frame
    then id. Refuses to replace an existing file unless `overwrite`."""
    p = Path(path)
    if p.exists() and not overwrite:
        raise OcctrackError("exists already; pass --force to overwrite it", str(p))
    if p.parent and not p.parent.exists():
        raise OcctrackError("folder does not exist", str(p.parent))
    score = np.ones(len(frame)) if score is None else score
    order = np.lexsort((ids, frame))
    with open(p, "w", encoding="utf-8") as fh:
        for i in order:
            l, t, w, h = box[i]
            fh.write(f"{int(frame[i])},{int(ids[i])},{l:.2f},{t:.2f},{w:.2f},{h:.2f},"
                     f"{score[i]:.4f},-1,-1,-1\n")


def read_seqinfo(folder: str | os.PathLike) -> dict[str, int | str]:
    """`seqinfo.ini` of a MOTChallenge sequence folder: name, imWidth, imHeight, seqLength,
    frameRate."""
    ini = Path(folder) / "seqinfo.ini"
    parser = configparser.ConfigParser()
    try:
        with open(ini, encoding="utf-8") as fh:
            parser.read_file(fh)
        s = parser["Sequence"]
        return {"name": s.get("name", Path(folder).name), "width": int(s["imWidth"]),
                "height": int(s["imHeight"]), "length": int(s["seqLength"]),
                "fps": int(float(s.get("frameRate", "30")))}
    except FileNotFoundError:
        raise OcctrackError("no seqinfo.ini here", str(ini)) from None
    except (KeyError, ValueError, configparser.Error) as err:
        raise OcctrackError(f"malformed seqinfo.ini: {err}", str(ini)) from None


def find_seqinfo(mot_file: str | os.PathLike) -> Path | None:
    """The sequence folder of a file at SEQ/det/det.txt or SEQ/gt/gt.txt, if it has a
    seqinfo.ini."""
    seq = Path(mot_file).resolve().parent.parent
    return seq if (seq / "seqinfo.ini").is_file() else None
