"""The official MOTChallenge (MOT17) protocol, run by TrackEval itself.

TrackEval's `MotChallenge2DBox` dataset does the official preprocessing and its `CLEAR`,
`Identity` and `HOTA` metrics do the scoring, so occtrack's numbers are TrackEval's numbers:

- Preprocessing, per frame: result boxes are matched to all ground-truth boxes, any class, by
  Hungarian assignment on IoU >= 0.5; result boxes matched to a distractor (class 2 person on
  vehicle, 7 static person, 8 distractor, 12 reflection) are removed. Then only ground truth with
  consider flag 1 and class 1 (pedestrian) is kept.
- CLEAR and Identity: a match needs IoU >= 0.5; MOTP is the mean IoU of matches (higher is
  better); mostly tracked / lost are ground-truth tracks matched in > 80 % / < 20 % of their
  frames. HOTA is averaged over the localisation thresholds 0.05, 0.10, ..., 0.95.

The only thing not TrackEval's is reading the files (occtrack.io.mot reads them as TrackEval
does, and checks every row). The dataset class insists on a folder of files when it is built;
it is built over empty placeholder files in a temporary folder and then handed the arrays
already read (`_load_raw_file`), which spares writing and re-reading the data. Each result row's
index rides through the preprocessing in the confidence column, which none of these metrics
reads, so the rows that survive are known exactly. TrackEval's printing is swallowed.

trackeval 1.3.0 runs unchanged on numpy 2 (it uses no removed numpy aliases).
"""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path

import numpy as np
from trackeval.datasets import MotChallenge2DBox
from trackeval.metrics import CLEAR, HOTA, Count, Identity
from trackeval.utils import TrackEvalException, write_detailed_results, write_summary_results

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable

_SEQ = "seq"
_TRACKER = "result"
_QUIET = {"PRINT_CONFIG": False}


class _ArrayDataset(MotChallenge2DBox):
    """`MotChallenge2DBox` whose raw data come from arrays instead of its folder layout."""

    def __init__(self, gt_raw: dict, tracker_raw: dict, num_frames: int):
        with tempfile.TemporaryDirectory(prefix="occtrack-trackeval-") as folder:
            (Path(folder) / _SEQ / "gt").mkdir(parents=True)
            (Path(folder) / _SEQ / "gt" / "gt.txt").touch()
            (Path(folder) / _TRACKER / "data").mkdir(parents=True)
            (Path(folder) / _TRACKER / "data" / f"{_SEQ}.txt").touch()
            super().__init__({"GT_FOLDER": folder, "TRACKERS_FOLDER": folder,
                              "OUTPUT_FOLDER": folder, "TRACKERS_TO_EVAL": [_TRACKER],
                              "SEQ_INFO": {_SEQ: num_frames}, "SKIP_SPLIT_FOL": True,
                              "BENCHMARK": "MOT17", "DO_PREPROC": True, **_QUIET})
        self._raw = {True: gt_raw, False: tracker_raw}

    def _load_raw_file(self, tracker, seq, is_gt):
        return self._raw[is_gt]


def _per_frame(table: MotTable, num_frames: int):
    """Row indices per frame and ids relabelled 0..n-1 in the same order (TrackEval relabels
    the same way later, so no number changes; it only keeps TrackEval's id tables small)."""
    _, ids = np.unique(table.id, return_inverse=True)
    return table.frame_slices(num_frames), ids.reshape(-1)


def preprocess(gt: MotTable, result: MotTable, num_frames: int
               ) -> tuple[dict, list[np.ndarray], list[np.ndarray]]:
    """TrackEval's preprocessed sequence (the dict its metrics take), and per frame the rows of
    `gt` and of `result` it keeps, in the order of its similarity matrices."""
    gt_rows, gt_ids = _per_frame(gt, num_frames)
    tr_rows, tr_ids = _per_frame(result, num_frames)
    zero_marked = gt.score.astype(int)
    gt_raw = {
        "gt_ids": [gt_ids[r] for r in gt_rows],
        "gt_classes": [gt.cls[r] for r in gt_rows],
        "gt_dets": [gt.box[r] for r in gt_rows],
        "gt_crowd_ignore_regions": [np.empty((0, 4)) for _ in gt_rows],
        "gt_extras": [{"zero_marked": zero_marked[r]} for r in gt_rows],
        "num_timesteps": num_frames, "seq": _SEQ,
    }
    tracker_raw = {
        "tracker_ids": [tr_ids[r] for r in tr_rows],
        "tracker_classes": [result.cls[r] for r in tr_rows],
        "tracker_dets": [result.box[r] for r in tr_rows],
        "tracker_confidences": [r.astype(float) for r in tr_rows],
        "num_timesteps": num_frames, "seq": _SEQ,
    }
    with _trackeval_errors():
        dataset = _ArrayDataset(gt_raw, tracker_raw, num_frames)
        raw = dataset.get_raw_seq_data(_TRACKER, _SEQ)
        data = dataset.get_preprocessed_seq_data(raw, "pedestrian")
    keep_gt = (zero_marked != 0) & (gt.cls == 1)
    truth_rows = [r[keep_gt[r]] for r in gt_rows]
    estimate_rows = [c.astype(np.int64) for c in data["tracker_confidences"]]
    assert all(len(a) == len(b) for a, b in zip(truth_rows, data["gt_ids"], strict=True))
    return data, truth_rows, estimate_rows


def scores(data: dict) -> dict:
    """TrackEval's CLEAR, Identity and HOTA on a preprocessed sequence, under occtrack's keys.
    `hota` is the mean over TrackEval's 19 localisation thresholds, as its summary reports."""
    values = summary(sequence_results(data))
    return {key: values[key] for key in ("mota", "motp", "idf1", "hota", "mostly_tracked",
                                         "mostly_lost", "fp", "fn", "id_switches")}


def _metrics() -> dict:
    """TrackEval's metrics in the order its run_mot_challenge.py runs them (Count is always
    run, and gives the Dets, GT_Dets, IDs and GT_IDs columns of its files)."""
    return {"HOTA": HOTA(), "CLEAR": CLEAR(dict(_QUIET)), "Identity": Identity(dict(_QUIET)),
            "Count": Count()}


CLASS = "pedestrian"
SUMMARY_FILE = f"{CLASS}_summary.txt"
DETAILED_FILE = f"{CLASS}_detailed.csv"


def output_files(per_sequence: dict[str, dict]) -> dict[str, str]:
    """The files TrackEval writes for one tracker (`pedestrian_summary.txt`: every summary
    field of COMBINED_SEQ, space separated, HOTA DetA AssA ... LocA ... IDF1 IDR IDP ... Frag;
    `pedestrian_detailed.csv`: every field, each HOTA field at each of its 19 thresholds too,
    a row per sequence and COMBINED), made by TrackEval's own writers from
    `sequence_results` keyed by sequence name. Returns {file name: text}."""
    combined = combined_results(list(per_sequence.values()))
    summaries, details = [], []
    with _trackeval_errors():
        for name, metric in _metrics().items():
            table = {seq: res[name] for seq, res in per_sequence.items()}
            table["COMBINED_SEQ"] = combined[name]
            summaries.append(metric.summary_results(table))
            details.append(metric.detailed_results(table))
    with tempfile.TemporaryDirectory(prefix="occtrack-trackeval-") as folder:
        write_summary_results(summaries, CLASS, folder)
        write_detailed_results(details, CLASS, folder)
        texts = {}
        for name in (SUMMARY_FILE, DETAILED_FILE):
            with open(Path(folder) / name, encoding="utf-8", newline="") as fh:
                texts[name] = fh.read()  # as written: csv's \r\n line ends kept
        return texts


def sequence_results(data: dict) -> dict:
    """TrackEval's own per-sequence results ({"CLEAR": ..., "Identity": ..., "HOTA": ...}),
    kept whole so that several sequences can be combined the way TrackEval combines them."""
    with _trackeval_errors():
        return {name: metric.eval_sequence(data) for name, metric in _metrics().items()}


def combined_results(per_sequence: list[dict]) -> dict:
    """TrackEval's COMBINED_SEQ over several `sequence_results`: counts summed, HOTA's
    association and localisation averaged with its true-positive weights, as its summary
    does over a benchmark."""
    if not per_sequence:
        raise OcctrackError("no sequences to combine")
    with _trackeval_errors():
        return {name: metric.combine_sequences({str(i): res[name]
                                                for i, res in enumerate(per_sequence)})
                for name, metric in _metrics().items()}


def summary(results: dict) -> dict:
    """The headline numbers of `sequence_results` or `combined_results`: occtrack's keys plus
    HOTA's parts (DetA, AssA, LocA), each HOTA number the mean over its 19 thresholds."""
    clear, identity, hota = results["CLEAR"], results["Identity"], results["HOTA"]
    return {
        "mota": float(clear["MOTA"]), "motp": float(clear["MOTP"]),
        "idf1": float(identity["IDF1"]), "hota": float(np.mean(hota["HOTA"])),
        "deta": float(np.mean(hota["DetA"])), "assa": float(np.mean(hota["AssA"])),
        "loca": float(np.mean(hota["LocA"])),
        "mostly_tracked": int(clear["MT"]), "mostly_lost": int(clear["ML"]),
        "fp": int(clear["CLR_FP"]), "fn": int(clear["CLR_FN"]),
        "id_switches": int(clear["IDSW"]),
    }


@contextlib.contextmanager
def _trackeval_errors():
    """TrackEval prints progress and raises its own exception type; keep it quiet and turn its
    complaints into the one error type users see."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            yield
    except TrackEvalException as err:
        raise OcctrackError(f"TrackEval: {err}") from None
