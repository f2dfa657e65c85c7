"""What every peer wrapper shares: the checks of a run's input and the result table it returns
(the rows of the confirmed tracks, sorted by frame and id, as a MotTable)."""

from __future__ import annotations

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable


def check_run(num_frames: int, fps: float) -> None:
    """A sequence length of 0 or more frames and a positive frame rate."""
    if num_frames < 0:
        raise OcctrackError(f"number of frames must be 0 or more, got {num_frames}")
    if not fps > 0:
        raise OcctrackError(f"frame rate must be positive, got {fps}")


def check_length(det: MotTable, num_frames: int) -> None:
    """No detection past the sequence's last frame."""
    if len(det) and det.num_frames > num_frames:
        raise OcctrackError(f"detections reach frame {det.num_frames}, beyond the "
                            f"{num_frames} frames of the sequence", det.path or None)


def result_table(frame: np.ndarray, ids: np.ndarray, box: np.ndarray,
                 score: np.ndarray) -> MotTable:
    """A peer's rows (frame, id, left-top-width-height box, score) as a MotTable in frame and
    id order."""
    order = np.lexsort((ids, frame))
    n = len(order)
    return MotTable(frame=frame[order].astype(np.int64), id=ids[order].astype(np.int64),
                    box=box[order].astype(float), score=score[order].astype(float),
                    cls=np.full(n, -1, dtype=np.int64), visibility=np.full(n, -1.0))


def empty_table() -> MotTable:
    """A peer's result with no row."""
    return result_table(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 4)),
                        np.zeros(0))
