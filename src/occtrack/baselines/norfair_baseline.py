"""norfair (Tryolabs' SORT-style tracker) on MOTChallenge detections, as a baseline.

norfair 2.3 pins numpy < 2 while occtrack runs on numpy 2, so norfair never enters occtrack's
environment: on first use it is installed (pinned to NORFAIR_VERSION) into a virtual
environment of its own, `~/.cache/occtrack/norfair-venv` (or `$OCCTRACK_CACHE/norfair-venv`,
or `$XDG_CACHE_HOME/occtrack/norfair-venv`), which later runs reuse; `OCCTRACK_NORFAIR_PYTHON`
may name any interpreter that already imports norfair. The tracking itself runs in that
interpreter as a subprocess (`_norfair_runner.py`), with arrays passed through .npz files.

Settings (NorfairConfig) are those of norfair's own MOT17 demo,
`demos/motmetrics4norfair/src/motmetrics4norfair.py`: IoU distance on the box corners, match
when 1 - IoU < 0.9, point score threshold 0.5, hit counter max 8 (initialisation delay 4),
pointwise hit counter max 3 and filterpy's Kalman filter. The demo's camera-motion estimator is
left out: it needs the images, and MOT17-04's camera is static. norfair has no randomness, so a
run is repeatable.

With `frame_step` k > 1 norfair sees every k-th frame (and the last), told the gap through its
`period` argument, and boxes in the frames between are linearly interpolated for objects
present at both ends, the way occtrack's trackers report at the full frame rate.

norfair's Kalman filter runs on the two corners independently, so a coasting estimate of a
shrinking box can come out with crossed corners (width or height <= 0, a few rows in a
sequence); such rows are not reported, as a MOTChallenge file cannot hold them.
"""

from __future__ import annotations

import fcntl
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.atomic import check_output
from occtrack.io.mot import MotTable, read_mot, write_mot

NORFAIR_VERSION = "2.3.0"
RUNNER = Path(__file__).with_name("_norfair_runner.py")
FILTERS = ("filterpy", "optimized")


@dataclass(frozen=True)
class NorfairConfig:
    """Arguments of `norfair.Tracker` (names as norfair spells them) and the Kalman filter.

    distance_threshold: a detection may match an object when 1 - IoU is below it.
    detection_threshold: box corners scoring below it do not update an object.
    hit_counter_max: frames an object survives without a match (its hit counter's ceiling).
    initialization_delay: matches before an object is reported; None means
        hit_counter_max // 2, norfair's default.
    pointwise_hit_counter_max, past_detections_length: norfair's per-point bookkeeping.
    filter: "filterpy" (FilterPyKalmanFilterFactory, the MOT17 demo's) or "optimized".
    """

    distance_function: str = "iou"
    distance_threshold: float = 0.9
    detection_threshold: float = 0.5
    hit_counter_max: int = 8
    initialization_delay: int | None = None
    pointwise_hit_counter_max: int = 3
    past_detections_length: int = 4
    filter: str = "filterpy"

    def __post_init__(self) -> None:
        if self.filter not in FILTERS:
            raise OcctrackError(f"norfair filter must be one of {FILTERS}, not {self.filter!r}")
        if self.hit_counter_max < 1:
            raise OcctrackError("norfair hit_counter_max must be >= 1")
        delay = self.initialization_delay
        if delay is not None and not 0 <= delay < self.hit_counter_max:
            raise OcctrackError("norfair initialization_delay must lie in [0, hit_counter_max)")


def venv_dir() -> Path:
    """Where norfair's own environment lives."""
    if os.environ.get("OCCTRACK_CACHE"):
        root = Path(os.environ["OCCTRACK_CACHE"])
    else:
        root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "occtrack"
    return root / "norfair-venv"


def _python_in(venv: Path) -> Path:
    return venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")


def _imports_norfair(python: Path | str) -> bool:
    try:
        done = subprocess.run([str(python), "-c", "import norfair"], capture_output=True,
                              timeout=120, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.returncode == 0


def find_norfair_python() -> Path | None:
    """An interpreter that imports norfair, without installing anything; None if there is
    none yet."""
    named = os.environ.get("OCCTRACK_NORFAIR_PYTHON")
    if named:
        return Path(named) if _imports_norfair(named) else None
    venv = venv_dir()
    ready = venv / "occtrack-ready"
    python = _python_in(venv)
    if ready.is_file() and ready.read_text().strip() == NORFAIR_VERSION and python.exists():
        return python
    return None


def norfair_python(quiet: bool = False) -> Path:
    """An interpreter that imports norfair, creating norfair's environment on first use
    (python -m venv, then pip install norfair==NORFAIR_VERSION; needs the package index once).
    A lock keeps concurrent first uses from building it twice."""
    found = find_norfair_python()
    if found is not None:
        return found
    named = os.environ.get("OCCTRACK_NORFAIR_PYTHON")
    if named:
        raise OcctrackError(f"OCCTRACK_NORFAIR_PYTHON={named} cannot import norfair")
    venv = venv_dir()
    venv.parent.mkdir(parents=True, exist_ok=True)
    with open(venv.parent / "norfair-venv.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        found = find_norfair_python()
        if found is not None:
            return found
        if not quiet:
            print(f"installing norfair {NORFAIR_VERSION} into {venv} (first use only)",
                  file=sys.stderr)
        steps = [[sys.executable, "-m", "venv", "--clear", str(venv)],
                 [str(_python_in(venv)), "-m", "pip", "install", "--quiet",
                  "--disable-pip-version-check", f"norfair=={NORFAIR_VERSION}"]]
        for step in steps:
            done = subprocess.run(step, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
                raise OcctrackError(f"could not set up norfair's environment ({' '.join(step)}"
                                    f"): {' | '.join(tail)}", str(venv))
        python = _python_in(venv)
        if not _imports_norfair(python):
            raise OcctrackError("norfair installed but does not import", str(venv))
        (venv / "occtrack-ready").write_text(NORFAIR_VERSION + "\n")
        return python


def track_norfair(det: MotTable, frame_step: int = 1, config: NorfairConfig | None = None,
                  num_frames: int | None = None, quiet: bool = False) -> MotTable:
    """Track detections with norfair; the tracks as a MotTable (score 1, by frame then id),
    without the rows whose corners crossed.

    Frames 1..num_frames (default: the last frame of `det`) are tracked every `frame_step`
    frames plus the last; the frames between are interpolated.
    """
    cfg = config or NorfairConfig()
    if frame_step < 1:
        raise OcctrackError(f"frame_step must be >= 1, got {frame_step}")
    n = det.num_frames if num_frames is None else int(num_frames)
    if n < 1:
        return _table(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 4)))
    if len(det) and det.num_frames > n:
        raise OcctrackError(f"detections reach frame {det.num_frames}, beyond the "
                            f"{n} frames asked for", det.path or None)
    frames = np.unique(np.r_[np.arange(1, n + 1, frame_step), n])
    order = np.argsort(det.frame, kind="stable")
    settings = {k: v for k, v in asdict(cfg).items() if v is not None}
    python = norfair_python(quiet=quiet)
    with tempfile.TemporaryDirectory(prefix="occtrack-norfair-") as tmp:
        inp, conf, out = (Path(tmp) / name for name in ("in.npz", "config.json", "out.npz"))
        np.savez(inp, frame=det.frame[order].astype(np.int64), box=det.box[order],
                 score=det.score[order], frames=frames.astype(np.int64))
        conf.write_text(json.dumps(settings))
        env = {**os.environ, "PYTHONHASHSEED": "0", "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        done = subprocess.run([str(python), str(RUNNER), str(inp), str(conf), str(out)],
                              capture_output=True, text=True, env=env, check=False)
        if done.returncode != 0:
            tail = done.stderr.strip().splitlines()[-3:]
            raise OcctrackError(f"norfair failed: {' | '.join(tail)}")
        with np.load(out, allow_pickle=False) as result:
            frame, ids, box = result["frame"], result["id"], result["box"]
    if frame_step > 1:
        frame, ids, box = interpolate(frame, ids, box, frames)
    proper = (box[:, 2] > 0) & (box[:, 3] > 0)
    return _table(frame[proper], ids[proper], box[proper])


def interpolate(frame: np.ndarray, ids: np.ndarray, box: np.ndarray,
                tracked: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Add boxes at the frames between consecutive tracked frames, linearly interpolated, for
    each id reported at both ends."""
    order = np.lexsort((frame, ids))
    frame, ids, box = frame[order], ids[order], box[order]
    slot = np.searchsorted(tracked, frame)
    pair = (ids[1:] == ids[:-1]) & (slot[1:] == slot[:-1] + 1)
    a = np.flatnonzero(pair)
    gap = frame[a + 1] - frame[a]
    step = np.concatenate([np.arange(1, g) for g in gap]) if len(a) else np.zeros(0, int)
    left = np.repeat(a, gap - 1)
    t = (step / np.repeat(gap, gap - 1))[:, None]
    new_box = (1 - t) * box[left] + t * box[left + 1]
    return (np.r_[frame, frame[left] + step], np.r_[ids, ids[left]],
            np.concatenate([box, new_box]))


def _table(frame: np.ndarray, ids: np.ndarray, box: np.ndarray) -> MotTable:
    order = np.lexsort((ids, frame))
    n = len(order)
    return MotTable(frame=frame[order].astype(np.int64), id=ids[order].astype(np.int64),
                    box=box[order].reshape(n, 4), score=np.ones(n),
                    cls=np.full(n, -1, dtype=np.int64), visibility=np.full(n, -1.0))


def run_norfair(det_file: str | os.PathLike, result_file: str | os.PathLike,
                frame_step: int = 1, config: NorfairConfig | None = None,
                num_frames: int | None = None, overwrite: bool = False,
                quiet: bool = False) -> MotTable:
    """Read a detection file, track it with norfair and write a MOTChallenge result file
    (refusing to replace one unless `overwrite`). Returns the tracks written."""
    check_output(result_file, overwrite, [det_file])
    det = read_mot(det_file, "det")
    tracks = track_norfair(det, frame_step, config, num_frames, quiet)
    write_mot(result_file, tracks.frame, tracks.id, tracks.box, tracks.score,
              overwrite=overwrite)
    return tracks
