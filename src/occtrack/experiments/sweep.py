"""Sweeps: many sequences, seeds and settings, each cell one task, on Dask or in this process.

A spec (TOML) names the trackers, the seeds, the work and the settings:

    trackers = ["none", "measurement-wise", "object-wise"]
    seeds = [0, 1, 2]                     # or K: seeds 1..K

    [work]
    kind = "mot"                          # MOTChallenge sequence folders ...
    sequences = ["../shared/data/mot17"]  # folders, or folders of sequence folders
    detections = "simulated"              # det/det.txt ("det"), or seeded from gt

    # kind = "highway"                    # ... or the highway simulation (Table III)
    # steps = 1000
    # sensors = ["object-wise", "measurement-wise"]

    # kind = "lidar"                      # ... or the beam likelihood of paper section V
    # ranges = [10.0, 20.0]               # the object's range on the beam, m
    # samples = 100000                    # simulated beams per case

    [base]                                # settings every cell gets
    max_labels = 96

    [grid]                                # every combination of these values
    edge_noise = [0.05, 0.069, 0.1]
    clutter_rate = [2.0, 5.0]

    [random]                              # optional: `samples` random draws (x the grid)
    samples = 8
    seed = 0
    velocity_time = {log_uniform = [0.5, 20.0]}
    confirm_hits = {choice = [2, 3]}

    # [search]                            # or, instead of [grid] and [random]: Optuna
    # kind = "optuna"                     # (TPE sampler, seeded), one study per tracker
    # trials = 32
    # metric = "hota"                     # a metric column; its mean over the trial's cells
    # direction = "maximize"
    # seed = 0
    # batch = 4                           # trials asked at once (run as parallel tasks)
    # edge_noise = {log_uniform = [0.01, 0.1]}

Settings are fields of `occtrack.config.TrackerConfig` (kind "mot") or of
`occtrack.config.HighwayTrackerConfig` (kind "highway"; `simulation.NAME` and
`simulation.road.NAME` set the simulation, which the tracker then matches as in
`occtrack simulate highway`) or of the lidar's
`BeamModel` (kind "lidar": p_d, sigma, clutter_rate, max_range; its one "tracker" is
"separable", and a cell checks the derived L(z | x) against seeded simulated beams, as
`occtrack lidar` does, at five ranges about the object). A cell is one
(work item, tracker, settings point, seed): a sequence or a simulated sensor, tracked and
scored. Its key is a hash of everything that decides its result (the settings, the seed, the
text of the spec's settings file; a sequence by its name, not by its files' content: after a
detection file changes, write to a new table), so a rerun of the same or a larger spec skips
the cells already in the table.

Each task returns one row: the cell's identity, every setting it was given (as `setting.NAME`
columns and as canonical JSON in `settings`), the metrics (kind mot: TrackEval's HOTA, IDF1,
MOTA, ... under the mot17 protocol; kind highway: GOSPA per step and per car and its split),
the tracker's own seconds, the whole task's seconds and its CPU seconds. Rows are gathered
into one Parquet table, rewritten atomically (`occtrack.io.atomic`) every few seconds and at
the end, so an interrupted sweep keeps every finished cell. A failed task becomes a failure
record with its settings and error; the other tasks finish, and failed cells are not stored (a
rerun retries them).

Tasks are deterministic functions of their cell: the table does not depend on the engine (this
process, a LocalCluster or a remote Dask scheduler) or on the order tasks finish in; rows are
written in the order of the plan.

A [search] asks Optuna's seeded TPE sampler for `batch` trials at a time (one study per
tracker), runs every cell of those trials (work items x seeds) as tasks on the same engine,
and tells each trial the mean of `metric` over its cells, in trial order; so the trials, like
the table, do not depend on the engine. A rerun replays the study: the cells already in the
table are read back instead of run, so a larger `trials` goes on where the last run stopped.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import time
import traceback
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from occtrack.errors import OcctrackError
from occtrack.experiments.sweep_spec import (  # noqa: F401 (the spec's names, re-exported)
    DETECTIONS,
    DIRECTIONS,
    DISTRIBUTIONS,
    HEADLINE,
    HIGHWAY_METRICS,
    IDENTITY,
    KINDS,
    LIDAR_METRICS,
    LIDAR_TRACKERS,
    MOT_METRICS,
    SEARCH_KINDS,
    SETTING_PREFIX,
    TIMING,
    Cell,
    Search,
    Spec,
    _beam_model,
    _checked,
    _config_values,
    _highway_configs,
    _show,
    _split_highway,
    load_spec,
    plan,
)

FLUSH_SECONDS = 5.0


# ----------------------------------------------------------------------------------------------
# One task


@dataclass(frozen=True)
class Failure:
    """A task that raised: the cell, the one-line error and the traceback."""

    cell: Cell
    error: str
    traceback: str = ""


_SIMULATED: dict = {}


def _sequence(folder: str):
    from occtrack.experiments.benchmark import cached_sequence

    return cached_sequence(folder)


def _detections(cell: Cell, seq):
    if cell.detections == "det":
        return seq.det
    from occtrack.scenarios.detector import simulate_detections

    key = (cell.source, cell.seed)
    if key not in _SIMULATED:
        if len(_SIMULATED) >= 8:
            _SIMULATED.pop(next(iter(_SIMULATED)))
        _SIMULATED[key] = simulate_detections(seq.gt, cell.seed, image_size=(seq.width,
                                              seq.height), num_frames=seq.length)
    return _SIMULATED[key]


def _run_mot(cell: Cell) -> dict:
    import numpy as np

    from occtrack.config import TrackerConfig
    from occtrack.io.mot import MotTable
    from occtrack.metrics.protocols import scored_frames
    from occtrack.metrics.trackeval_mot17 import sequence_results, summary
    from occtrack.tracker import Tracker

    seq = _sequence(cell.source)
    det = _detections(cell, seq)
    values = {**_config_values(Path(cell.config) if cell.config else None),
              "image_size": (seq.width, seq.height), "fps": seq.fps,
              **cell.values, "occlusion": cell.tracker}
    config = TrackerConfig.from_dict(values, cell.config or "sweep settings")
    start = time.perf_counter()
    out = Tracker(config).run(det, seq.length)
    seconds = time.perf_counter() - start
    n = len(out.frame)
    result = MotTable(out.frame, out.id, out.box, out.confidence, np.full(n, -1),
                      np.full(n, -1.0), "<occtrack>")
    scores = summary(sequence_results(scored_frames(seq.gt, result, "mot17",
                                                    seq.length).trackeval))
    metrics = {key: scores[key] for key in MOT_METRICS if key in scores}
    metrics["tracks"] = int(len(np.unique(result.id)))
    metrics["frames"] = int(seq.length)
    return {**metrics, "seconds": seconds}


def _run_highway(cell: Cell) -> dict:
    from occtrack.experiments.highway import evaluate

    sim, road, tracker = _split_highway(cell.values, "sweep settings")
    simulation, tracking = _highway_configs(Path(cell.config) if cell.config else None, sim,
                                            road, tracker, cell.config or "sweep settings")
    score, seconds = evaluate(simulation, tracking, cell.work, cell.tracker, cell.steps,
                              cell.seed)
    return {"gospa": score.per_step, "gospa_per_car": score.per_object,
            "localisation": score.localisation, "missed": score.missed, "false": score.false,
            "steps": score.steps, "car_steps": score.car_steps, "n_missed": score.n_missed,
            "n_false": score.n_false, "tracks": score.tracks, "seconds": seconds}


def _run_lidar(cell: Cell) -> dict:
    """The derived beam likelihood ratio L against `cell.steps` simulated beams with and
    without the object (as `occtrack lidar` checks it), at five ranges: per range bin, with
    n_o beams with the object and n_e without landing in it, z = (n_o - L n_e) /
    sqrt(L n_e (1 + L)), the Poisson standard score of the derivation (0 where no beam
    landed)."""
    import numpy as np

    from occtrack.scenarios.lidar import binned_ratio, probe_bins, simulate_beams

    model = _beam_model(cell.values, "sweep settings")
    x, s = float(cell.source), model.sigma
    rng = np.random.default_rng(cell.seed)
    start = time.perf_counter()
    probes, half, edges = probe_bins(x, s)
    with_object = np.histogram(simulate_beams(x, model, cell.steps, rng), edges)[0][::2]
    without = np.histogram(simulate_beams(None, model, cell.steps, rng), edges)[0][::2]
    derived = binned_ratio(probes, half, x, model)
    spread = np.sqrt(derived * without * (1 + derived))
    z = np.divide(with_object - derived * without, spread, out=np.zeros(len(probes)),
                  where=spread > 0)
    names = ("l_hidden", "l_before", "l_hit", "l_after", "l_passed")
    return {"max_z": float(np.abs(z).max()), **dict(zip(names, derived.tolist(), strict=True)),
            "l_none": 1.0 - model.p_d, "samples": cell.steps,
            "seconds": time.perf_counter() - start}


def run_cell(cell: Cell) -> dict:
    """Run one cell and return its row; raises whatever the work raises."""
    start, cpu = time.perf_counter(), time.process_time()
    metrics = {"mot": _run_mot, "highway": _run_highway, "lidar": _run_lidar}[cell.kind](cell)
    row = {"cell": cell.key, "kind": cell.kind, "work": cell.work, "tracker": cell.tracker,
           "seed": cell.seed, "settings": cell.settings}
    row.update({SETTING_PREFIX + name: value for name, value in cell.values.items()})
    row.update(metrics)
    row["task_seconds"] = time.perf_counter() - start
    row["cpu_seconds"] = time.process_time() - cpu
    return row


def run_task(cell: Cell) -> dict | Failure:
    """`run_cell`, with a failure returned as a Failure (text only, so it travels from any
    worker) instead of raised."""
    try:
        return run_cell(cell)
    except Exception as err:  # noqa: BLE001 - every failure is reported with its cell
        what = str(err) if isinstance(err, OcctrackError | OSError) else (
            f"{type(err).__name__}: {err}")
        return Failure(cell, what, traceback.format_exc())


# ----------------------------------------------------------------------------------------------
# Engines: each yields (cell, row or Failure) as tasks finish


def warm(kind: str) -> None:
    """Import the modules a task of `kind` uses (a worker's first task would otherwise pay)."""
    if kind == "benchmark":
        import occtrack.experiments.benchmark  # noqa: F401
    if kind == "lidar":
        import occtrack.models.beam  # noqa: F401
    elif kind in ("mot", "benchmark"):
        import occtrack.metrics.protocols  # noqa: F401
        import occtrack.metrics.trackeval_mot17  # noqa: F401
        import occtrack.tracker  # noqa: F401
    else:
        import occtrack.experiments.highway  # noqa: F401


def run_sequential(cells: list[Cell]) -> Iterator[tuple[Cell, dict | Failure]]:
    for cell in cells:
        yield cell, run_task(cell)


@dataclass
class DaskEngine:
    """Tasks on Dask distributed: a LocalCluster of `workers` single-threaded processes,
    started and stopped here, or the scheduler at `scheduler` (tcp://HOST:PORT)."""

    scheduler: str | None = None
    workers: int | None = None
    timeout: float = 20.0  # seconds to reach a scheduler
    startup_seconds: float = 0.0
    describe: str = ""
    _client: object = field(default=None, repr=False)
    _cluster: object = field(default=None, repr=False)

    def __enter__(self) -> DaskEngine:
        try:
            import logging

            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise OcctrackError("Dask is not installed: pip install \"occtrack[sweep]\" (or "
                                "\"dask[distributed]\" pyarrow), or run with --sequential")\
                from None
        start = time.perf_counter()
        if self.scheduler:
            try:
                self._client = Client(self.scheduler, timeout=f"{self.timeout}s")
            except OSError as err:
                raise OcctrackError(f"cannot reach the Dask scheduler at {self.scheduler}: "
                                    f"{err}; start one (dask scheduler) or drop --scheduler")\
                    from None
            info = self._client.scheduler_info()
            n = len(info.get("workers", {}))
            self.describe = f"Dask scheduler {self.scheduler} ({n} workers)"
        else:
            import dask

            n = self.workers or available_cores()
            # the workers' statistical profiler samples every thread's stack every 10 ms,
            # which costs the tasks about a sixth of their CPU here, and nobody reads it; and
            # Dask's MALLOC_TRIM_THRESHOLD_ (memory handed back to the system at once) makes
            # the trackers' many short-lived arrays cost 10-50 % more CPU
            environ = {k: v for k, v in
                       dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
                       if k != "MALLOC_TRIM_THRESHOLD_"}
            with dask.config.set({"distributed.worker.profile.enabled": False,
                                  "distributed.nanny.pre-spawn-environ": environ}):
                self._cluster = LocalCluster(n_workers=n, threads_per_worker=1,
                                             processes=True, dashboard_address=":0",
                                             silence_logs=logging.ERROR)
            self._client = Client(self._cluster)
            self.describe = f"Dask LocalCluster, {n} single-threaded worker processes"
        self.startup_seconds = time.perf_counter() - start
        return self

    @property
    def started(self) -> bool:
        return self._client is not None

    def warm(self, kind: str) -> None:
        """Import what the tasks of `kind` need on every worker at once, before the clock of
        the tasks starts (counted in `startup_seconds`)."""
        start = time.perf_counter()
        try:
            self._client.run(warm, kind)
        except Exception as err:  # noqa: BLE001 - whatever the workers raised
            what = f"{type(err).__name__}: {err}"
            raise OcctrackError(f"the Dask workers cannot run occtrack's tasks ({what}); "
                                f"install this occtrack where they run") from None
        self.startup_seconds += time.perf_counter() - start

    def __exit__(self, *exc) -> None:
        client, cluster = self._client, self._cluster
        self._client = self._cluster = None
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()

    def run(self, cells: list[Cell]) -> Iterator[tuple[Cell, dict | Failure]]:
        for cell, row, err in self.map(run_task, cells):
            # run_task returns its own failures: an error here is the worker itself dying
            # (memory, a crash)
            yield cell, (Failure(cell, f"{type(err).__name__}: {err}") if err else row)

    def map(self, fn: Callable, items: list) -> Iterator[tuple[object, object, BaseException
                                                                | None]]:
        """fn(item) for every item, each one task, yielded as (item, result, None) or (item,
        None, what it raised) as they finish; the others go on after a failure."""
        from dask.distributed import as_completed

        client = self._client
        futures = {client.submit(fn, item, pure=False): i for i, item in enumerate(items)}
        try:
            for future in as_completed(futures):
                item = items[futures[future]]
                if future.status == "error":
                    yield item, None, future.exception()
                else:
                    yield item, future.result(), None
                future.release()
        finally:
            client.cancel([f for f in futures if not f.done()])


def dask_available() -> bool:
    """Whether Dask distributed can be imported (the `sweep` extra)."""
    import importlib.util

    return all(importlib.util.find_spec(name) is not None for name in ("dask", "distributed"))


def available_cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


# ----------------------------------------------------------------------------------------------
# The table


def require_parquet() -> None:
    """OcctrackError unless pyarrow (pandas' Parquet engine) is installed."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise OcctrackError("the sweep's Parquet table needs pyarrow: pip install "
                            "\"occtrack[sweep]\" (or pyarrow)") from None


def read_table(path: str | os.PathLike):
    """The rows already in the table at `path` (an empty frame when there is none)."""
    import pandas as pd

    require_parquet()

    target = Path(path)
    if not target.exists():
        return pd.DataFrame()
    try:
        table = pd.read_parquet(target)
    except Exception as err:  # noqa: BLE001 - pyarrow raises several types for a bad file
        raise OcctrackError(f"not a Parquet table a sweep wrote ({type(err).__name__}: {err});"
                            f" move it away or write to another -o", str(target)) from None
    if "cell" not in table.columns:
        raise OcctrackError("a Parquet table without a 'cell' column is not a sweep's table; "
                            "write to another -o", str(target))
    return table


def write_table(path: str | os.PathLike, old, rows: list[dict], order: dict[str, int]):
    """Old rows and new rows as one table, written atomically: rows of this plan in plan
    order, older rows the plan does not name first, as they were. Returns the table."""
    import pandas as pd

    new = pd.DataFrame(rows)
    frames = [f for f in (old, new) if len(f)]
    table = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    if len(table):
        table = table.drop_duplicates("cell", keep="last")
        position = table["cell"].map(order).fillna(-1)
        table = table.iloc[position.argsort(kind="stable")].reset_index(drop=True)
        table = table[_column_order(table.columns)]
    from occtrack.io.atomic import atomic_path

    with atomic_path(path, overwrite=True) as tmp:
        table.to_parquet(tmp, index=False)
    return table


def _column_order(columns) -> list[str]:
    columns = list(columns)
    first = [c for c in IDENTITY if c in columns]
    settings = sorted(c for c in columns if c.startswith(SETTING_PREFIX))
    timing = [c for c in TIMING if c in columns]
    metrics = [c for c in columns if c not in first and c not in settings and c not in timing]
    return first + settings + metrics + timing


# ----------------------------------------------------------------------------------------------
# The sweep


@dataclass
class Outcome:
    """What a sweep did: the whole table, the cells of this plan, how many ran and were
    skipped, the failures, the seconds the tasks took (wall) and the engine's start-up; for a
    search, a line per study on its best trial."""

    table: object
    cells: list[Cell]
    ran: int
    skipped: int
    failures: list[Failure]
    seconds: float
    startup_seconds: float = 0.0
    engine: str = ""
    notes: list[str] = field(default_factory=list)


class _Store:
    """The table being filled: the rows already in it, the new ones, rewritten every
    `flush_seconds` and at the end; rows in the order of `order` (cell key -> index)."""

    def __init__(self, output, flush_seconds: float):
        self.output = output
        self.old = read_table(output)
        self.done = set(self.old["cell"]) if len(self.old) else set()
        self.rows: list[dict] = []
        self.order: dict[str, int] = {}
        self.flush_seconds = flush_seconds
        self.last = time.perf_counter()
        self.table = self.old

    def add(self, row: dict) -> None:
        self.rows.append(row)
        if time.perf_counter() - self.last >= self.flush_seconds:
            self.write()

    def write(self) -> None:
        self.table = write_table(self.output, self.old, self.rows, self.order)
        self.last = time.perf_counter()

    def close(self, completed: bool = True) -> None:
        """Write the rows; a run that ended early with none (an unreachable scheduler)
        leaves no table behind, where a completed one with none writes the empty table."""
        if self.rows or (completed and not Path(self.output).exists()):
            self.write()


def sweep(spec: Spec, output: str | os.PathLike, engine: DaskEngine | None = None,
          quiet: bool = True, on_result: Callable[[Cell, dict | Failure], None] | None = None,
          flush_seconds: float = FLUSH_SECONDS) -> Outcome:
    """Run every cell of `spec` not yet in the table at `output` (a [search]: the cells of
    its trials), on `engine` (None: in this process), writing the table as results come
    in."""
    from occtrack.io.atomic import check_output
    from occtrack.progress import progress

    check_output(output, overwrite=True, inputs=(spec.path,))
    store = _Store(output, flush_seconds)
    failures: list[Failure] = []
    skipped = 0
    warmed = False
    with contextlib.ExitStack() as stack:

        def execute(cells: list[Cell]) -> dict[str, dict | Failure]:
            """Run the cells not in the table yet; their rows or failures by cell key."""
            nonlocal skipped, warmed
            store.order.update({cell.key: cell.index for cell in cells})
            todo = list({cell.key: cell for cell in reversed(cells)
                         if cell.key not in store.done}.values())[::-1]
            skipped += len(cells) - len(todo)
            if not todo:  # every cell is in the table already: no engine to start
                return {}
            if engine is not None and not warmed:
                if not engine.started:  # else the caller started it and stops it
                    stack.enter_context(engine)
                engine.warm(spec.kind)
                warmed = True
            out: dict[str, dict | Failure] = {}
            results: Iterable = run_sequential(todo) if engine is None else engine.run(todo)
            for cell, result in progress(results, len(todo), "sweep", quiet):
                out[cell.key] = result
                if isinstance(result, Failure):
                    failures.append(result)
                else:
                    store.add(result)
                    store.done.add(cell.key)
                if on_result is not None:
                    on_result(cell, result)
            return out

        start = time.perf_counter()
        notes: list[str] = []
        completed = False
        try:
            if spec.search is None:
                cells = plan(spec)
                execute(cells)
            else:
                cells, notes = _run_search(spec, execute, store)
            completed = True
        finally:
            seconds = time.perf_counter() - start
            store.close(completed)
    failures.sort(key=lambda f: f.cell.index)
    return Outcome(table=store.table, cells=cells, ran=len(store.rows), skipped=skipped,
                   failures=failures, seconds=seconds,
                   startup_seconds=engine.startup_seconds if engine else 0.0,
                   engine=(engine.describe or "no engine (nothing to run)") if engine
                   else "this process, one task at a time", notes=notes)


def _distribution(law: dict):
    import optuna

    (how, args), = law.items()
    if how == "choice":
        return optuna.distributions.CategoricalDistribution(args)
    if how == "int_uniform":
        return optuna.distributions.IntDistribution(args[0], args[1])
    return optuna.distributions.FloatDistribution(float(args[0]), float(args[1]),
                                                  log=how == "log_uniform")


def _run_search(spec: Spec, execute: Callable, store: _Store) -> tuple[list[Cell], list[str]]:
    """Ask each tracker's study for `batch` trials at a time, run their cells, tell each trial
    the mean of the metric over its cells (a failed cell fails the trial), until `trials`
    trials; the cells in trial order and a line per study on its best trial."""
    try:
        import optuna
    except ImportError:
        raise OcctrackError("[search] kind = \"optuna\" needs Optuna: pip install "
                            "\"occtrack[sweep]\" (or optuna)", str(spec.path)) from None
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    search = spec.search
    distributions = {name: _distribution(law) for name, law in search.laws.items()}
    studies = {tracker: optuna.create_study(
        direction=search.direction, sampler=optuna.samplers.TPESampler(seed=search.seed))
        for tracker in spec.trackers}
    known: dict[str, float | None] = {}  # cell key -> metric (None: failed)
    if len(store.old) and search.metric in store.old.columns:
        known.update(zip(store.old["cell"], store.old[search.metric].astype(float),
                         strict=True))
    cells: list[Cell] = []
    points: dict[tuple[str, int], dict] = {}
    while len(points) < search.trials * len(spec.trackers):
        asked = len(points) // len(spec.trackers)
        batch = []
        for tracker in spec.trackers:
            for _ in range(min(search.batch, search.trials - asked)):
                trial = studies[tracker].ask(distributions)
                point = _checked(spec, {**search.base, **trial.params}, str(spec.path))
                points[tracker, trial.number] = point
                one = dataclasses.replace(spec, trackers=(tracker,), points=(point,),
                                          search=None)
                mine = [dataclasses.replace(cell, index=len(cells) + i)
                        for i, cell in enumerate(plan(one))]
                cells += mine
                batch.append((tracker, trial, mine))
        results = execute([cell for _, _, mine in batch for cell in mine])
        known.update({key: None if isinstance(result, Failure) else float(result[search.metric])
                      for key, result in results.items()})
        for tracker, trial, mine in batch:
            values = [known[cell.key] for cell in mine]
            if any(v is None for v in values):
                studies[tracker].tell(trial, state=optuna.trial.TrialState.FAIL)
            else:
                studies[tracker].tell(trial, sum(values) / len(values))
    notes = []
    for tracker, study in studies.items():
        done = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
        if not done:
            notes.append(f"{tracker}: no trial finished")
            continue
        best = study.best_trial
        settings = ", ".join(f"{k}={_show(v)}" for k, v in points[tracker, best.number].items())
        notes.append(f"{tracker}: best {search.metric} {best.value:.4f} (trial {best.number} "
                     f"of {len(study.trials)}, {search.direction}): {settings}")
    return cells, notes


# ----------------------------------------------------------------------------------------------
# The summary


def _mean_stderr(values) -> tuple[float, float]:
    import numpy as np

    v = np.asarray(values, dtype=float)
    if len(v) == 0:
        return float("nan"), float("nan")
    stderr = float(v.std(ddof=1) / np.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(v.mean()), stderr


def _cellfmt(mean: float, stderr: float) -> str:
    if math.isnan(mean):
        return "-"
    return f"{mean:.3f}" + ("" if math.isnan(stderr) else f" +- {stderr:.3f}")


def summarise(table, cells: list[Cell]) -> str:
    """Means and standard errors over seeds of the headline metrics, per work item, tracker
    and settings point, for the cells of this plan; then, with more than one work item, the
    mean over work items (the standard error over seeds of each seed's mean)."""
    if not len(table) or not cells:
        return "no finished cell to summarise"
    keys = {cell.key for cell in cells}
    rows = table[table["cell"].isin(keys)]
    if not len(rows):
        return "no finished cell of this spec to summarise"
    kind = cells[0].kind
    headline = [(k, title) for k, title in HEADLINE[kind] if k in rows.columns]
    seeds = sorted({cell.seed for cell in cells})
    point_order = list(dict.fromkeys(cell.settings for cell in cells))
    point_name = {s: f"p{i}" for i, s in enumerate(point_order)}
    lines = []
    if len(point_order) > 1:
        lines.append("settings points:")
        for settings in point_order:
            values = json.loads(settings)
            text = ", ".join(f"{k}={_show(v)}" for k, v in values.items()) or "(defaults)"
            lines.append(f"  {point_name[settings]:<5}{text}")
        lines.append("")
    seed_text = (f"seed {seeds[0]}" if len(seeds) == 1 else
                 f"mean +- standard error over {len(seeds)} seeds")
    lines.append(f"{kind} sweep: {seed_text}")
    work_title = {"mot": "sequence", "lidar": "object"}.get(kind, "simulated")
    header = f"  {work_title:<18}{'tracker':<20}{'point':<7}{'n':>3}" + "".join(
        f"{title:>18}" for _, title in headline)
    lines.append(header)
    works = list(dict.fromkeys(cell.work for cell in cells))
    trackers = list(dict.fromkeys(cell.tracker for cell in cells))
    for work in works:
        for tracker in trackers:
            for settings in point_order:
                sel = rows[(rows["work"] == work) & (rows["tracker"] == tracker)
                           & (rows["settings"] == settings)]
                if not len(sel):
                    continue
                stats = [_mean_stderr(sel[k]) for k, _ in headline]
                lines.append(f"  {work:<18}{tracker:<20}{point_name[settings]:<7}"
                             f"{len(sel):>3}" + "".join(f"{_cellfmt(*s):>18}" for s in stats))
    if len(works) > 1:
        lines += ["", f"mean over the {len(works)} "
                  + {"mot": "sequences", "lidar": "ranges"}.get(kind, "simulations")
                  + ("" if len(seeds) == 1 else ", +- standard error over seeds of each "
                                                "seed's mean"),
                  f"  {'tracker':<20}{'point':<7}{'n':>3}"
                  + "".join(f"{title:>18}" for _, title in headline)]
        for tracker in trackers:
            for settings in point_order:
                sel = rows[(rows["tracker"] == tracker) & (rows["settings"] == settings)]
                if not len(sel):
                    continue
                complete = sel.groupby("seed").filter(lambda g: g["work"].nunique()
                                                      == len(works))
                per_seed = complete.groupby("seed")[[k for k, _ in headline]].mean()
                stats = [_mean_stderr(per_seed[k]) for k, _ in headline]
                lines.append(f"  {tracker:<20}{point_name[settings]:<7}{len(per_seed):>3}"
                             + "".join(f"{_cellfmt(*s):>18}" for s in stats))
    return "\n".join(lines)


def format_failures(failures: list[Failure]) -> str:
    lines = [f"{len(failures)} task(s) failed (not stored; a rerun retries them):"]
    for failure in failures:
        lines.append(f"  {failure.cell.describe()}: {failure.error}")
    return "\n".join(lines)
