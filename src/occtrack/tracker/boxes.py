"""Box formats at the API's edge, and checks of what a caller hands the tracker.

The tracker works in left, top, width, height ("ltwh", MOTChallenge's columns); detectors
give corners ("xyxy": YOLO, supervision, torchvision) or centres ("cxcywh": YOLO's normalised
labels, DETR). `Tracker.update` takes and returns any of them.
"""

from __future__ import annotations

import numbers
from typing import Literal

import numpy as np
import numpy.typing as npt

from occtrack.io.mot import MAX_COORDINATE
from occtrack.tracker._tracker import _checked_ltwh

BoxFormat = Literal["xyxy", "ltwh", "cxcywh"]
BOX_FORMATS: tuple[str, ...] = ("xyxy", "ltwh", "cxcywh")
_MEANING = {"xyxy": "x1, y1, x2, y2 (corners)", "ltwh": "left, top, width, height",
            "cxcywh": "centre x, centre y, width, height"}


def check_format(box_format: str) -> str:
    if not isinstance(box_format, str) or box_format not in BOX_FORMATS:
        raise ValueError(f"box_format must be one of {', '.join(map(repr, BOX_FORMATS))}, "
                         f"not {box_format!r}")
    return box_format


def as_array(values: npt.ArrayLike, what: str, shape: str) -> np.ndarray:
    """`values` as a float array, or a ValueError that says what was expected (a string, a
    path or a list of strings is not numbers)."""
    if isinstance(values, str | bytes):
        raise ValueError(f"{what} must be an array of numbers {shape}, not the string "
                         f"{values[:40]!r}")
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{what} must be an array of numbers {shape}, not "
                         f"{type(values).__name__} ({err})") from None
    return arr


def to_ltwh(boxes: npt.ArrayLike, box_format: str) -> np.ndarray:
    """(M, 4) boxes in `box_format` -> a new (M, 4) float array left, top, width, height.
    Raises ValueError on a bad shape, a NaN or infinity, or corners in the wrong order."""
    check_format(box_format)
    arr = as_array(boxes, "boxes", f"of shape (M, 4) in {box_format}")
    if arr.size == 0:
        arr = arr.reshape(0, 4)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"boxes must have shape (M, 4) ({_MEANING[box_format]}), not "
                         f"{arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError("boxes contain NaN or infinity")
    beyond = np.abs(arr) > MAX_COORDINATE
    if beyond.any():
        i = int(np.flatnonzero(beyond.any(axis=1))[0])
        raise ValueError(f"box {i} {arr[i].tolist()} has a coordinate beyond "
                         f"{MAX_COORDINATE:g} px: no image is that large")
    out = arr.copy()
    if box_format == "xyxy":
        out[:, 2:] = arr[:, 2:] - arr[:, :2]
        if (out[:, 2:] < 0).any():
            i = int(np.flatnonzero((out[:, 2:] < 0).any(axis=1))[0])
            raise ValueError(f"box {i} {arr[i].tolist()} has x2 < x1 or y2 < y1; xyxy boxes "
                             f"are corners (pass box_format='ltwh' for left, top, width, "
                             f"height)")
    elif box_format == "cxcywh":
        out[:, :2] = arr[:, :2] - arr[:, 2:] / 2.0
    if (out[:, 2:] < 0).any():
        raise ValueError("boxes have a negative width or height")
    return out


def from_ltwh(boxes: np.ndarray, box_format: str) -> np.ndarray:
    """(n, 4) left, top, width, height -> a new (n, 4) array in `box_format`."""
    check_format(box_format)
    out = np.array(boxes, dtype=float).reshape(-1, 4)
    if box_format == "xyxy":
        out[:, 2:] += out[:, :2]
    elif box_format == "cxcywh":
        out[:, :2] += out[:, 2:] / 2.0
    return out


def check_scores(scores: npt.ArrayLike | None, m: int) -> np.ndarray:
    """(M,) finite scores, ones when None."""
    if scores is None:
        return np.ones(m)
    arr = as_array(scores, "scores", "of shape (M,)")
    if arr.shape != (m,) or not np.isfinite(arr).all():
        raise ValueError(f"scores must be {m} finite numbers, one per box, not an array of "
                         f"shape {arr.shape}")
    return arr


def check_classes(classes: npt.ArrayLike | None, m: int) -> np.ndarray | None:
    """(M,) integer classes (whole floats such as YOLO's 0.0 accepted), or None."""
    if classes is None:
        return None
    if isinstance(classes, np.ndarray) and classes.dtype.kind in "iu":
        arr = classes  # (an integer array as it is: as a float, a large id would round)
    else:
        arr = as_array(classes, "classes", "of shape (M,)")
    if arr.shape != (m,):
        raise ValueError(f"classes must be {m} whole numbers, one per box, not an array of "
                         f"shape {arr.shape}")
    if arr.dtype.kind in "iu":  # (integers are whole: only their range is checked)
        if m and not (-2**62 < arr.min() and arr.max() < 2**62):
            raise ValueError("classes must be whole numbers (class ids)")
        return arr.astype(np.int64)
    if not (np.isfinite(arr).all() and (arr == np.round(arr)).all()
            and (np.abs(arr) < 2**62).all()):
        raise ValueError("classes must be whole numbers (class ids)")
    return arr.astype(np.int64)


def check_time(value: object, what: str) -> float:
    """A finite real number of seconds."""
    if isinstance(value, bool | np.bool_):
        raise ValueError(f"{what} must be a number of seconds, not {value!r}")
    if not isinstance(value, numbers.Real):
        try:  # numpy and torch scalars
            value = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ValueError(f"{what} must be a number of seconds, not {value!r}") from None
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{what} must be a finite number of seconds, not {value}")
    return value


def checked_frame(boxes: object, scores: object) -> np.ndarray | None:
    """The fast path of `Tracker.step`'s checks, for what a detector loop hands it: float64
    arrays (M, 4) of boxes left, top, width, height and (M,) scores, all finite, no size
    negative; then a copy of the boxes with sizes below 1 px raised to 1. None for anything
    else: the full checks (`to_ltwh`, `check_scores`) then run and say what is wrong."""
    if (type(boxes) is np.ndarray and boxes.dtype == np.float64 and boxes.ndim == 2
            and boxes.shape[1] == 4 and type(scores) is np.ndarray
            and scores.dtype == np.float64 and scores.shape == (len(boxes),)):
        ok, out = _checked_ltwh(np.ascontiguousarray(boxes), np.ascontiguousarray(scores))
        if ok and (not len(out) or np.abs(out).max() <= MAX_COORDINATE):
            return out
    return None
