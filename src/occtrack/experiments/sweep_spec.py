"""The spec of a sweep (`occtrack sweep SPEC.toml`): its TOML read and checked, and the plan of
cells it makes. The format and what a cell is: `occtrack.experiments.sweep`, which runs them.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from occtrack._compat import tomllib
from occtrack.errors import OcctrackError

KINDS = ("mot", "highway", "lidar")
DETECTIONS = ("det", "simulated")
SETTING_PREFIX = "setting."
IDENTITY = ("cell", "kind", "work", "tracker", "seed", "settings")
TIMING = ("seconds", "task_seconds", "cpu_seconds")
"""Columns that measure time: they differ from run to run, everything else does not."""
MOT_METRICS = ("hota", "idf1", "mota", "motp", "deta", "assa", "loca", "mostly_tracked",
               "mostly_lost", "fp", "fn", "id_switches", "tracks", "frames")
HIGHWAY_METRICS = ("gospa", "gospa_per_car", "localisation", "missed", "false", "steps",
                   "car_steps", "n_missed", "n_false", "tracks")
LIDAR_METRICS = ("max_z", "l_hidden", "l_before", "l_hit", "l_after", "l_passed", "l_none",
                 "samples")
"""kind lidar: the beam likelihood ratio L(z | x) derived (paper section V) at five returns z:
x / 2 (the object hidden behind the return: L about 1), x - 3 sigma, x (the hit), x + 2 sigma,
x + 6 sigma (the beam passed where the object would be: L about 1 - P_D), and with no return
(`l_none`); `max_z`, the largest Poisson standard score of the simulated beams against it."""
LIDAR_TRACKERS = ("separable",)
HEADLINE = {"mot": (("hota", "HOTA"), ("idf1", "IDF1"), ("mota", "MOTA")),
            "highway": (("gospa", "GOSPA/step"), ("gospa_per_car", "GOSPA/car")),
            "lidar": (("max_z", "max |z|"), ("l_hit", "L hit"), ("l_passed", "L passed"))}
DISTRIBUTIONS = ("uniform", "log_uniform", "int_uniform", "choice")
SEARCH_KINDS = ("optuna",)
DIRECTIONS = ("maximize", "minimize")


# ----------------------------------------------------------------------------------------------
# The spec


@dataclass(frozen=True)
class Spec:
    """A parsed sweep spec; `points` are the settings points (grid x random draws), each
    already merged over `base`."""

    path: Path
    kind: str
    trackers: tuple[str, ...]
    seeds: tuple[int, ...]
    points: tuple[dict, ...]
    sequences: tuple[Path, ...] = ()
    detections: str = "det"
    steps: int = 0
    sensors: tuple[str, ...] = ()
    config: Path | None = None
    search: Search | None = None
    ranges: tuple[float, ...] = ()  # lidar: the object's range on the beam, m


@dataclass(frozen=True)
class Search:
    """A [search] table: Optuna over the settings in `laws` (as [random] writes them)."""

    kind: str
    trials: int
    metric: str
    direction: str
    seed: int
    batch: int
    laws: dict
    base: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Cell:
    """One task: everything its result depends on. `settings` is a canonical JSON object."""

    index: int
    key: str
    kind: str
    work: str
    tracker: str
    seed: int
    settings: str
    source: str = ""  # the sequence folder (mot)
    detections: str = "det"
    steps: int = 0
    config: str = ""  # a settings file every cell starts from (its text is in the key)

    @property
    def values(self) -> dict:
        return json.loads(self.settings)

    def describe(self) -> str:
        what = f"{self.work} / {self.tracker} / seed {self.seed}"
        values = self.values
        if values:
            what += " / " + ", ".join(f"{k}={_show(v)}" for k, v in values.items())
        return what


def _show(value) -> str:
    return json.dumps(value) if isinstance(value, str | list) else f"{value}"


def load_spec(path: str | os.PathLike) -> Spec:
    """Read and check a spec file; OcctrackError naming the file on any fault."""
    path = Path(path)
    source = str(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise OcctrackError("no such file", source) from None
    except IsADirectoryError:
        raise OcctrackError("is a directory, expected a sweep spec (TOML)", source) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise OcctrackError(f"not valid TOML: {err}", source) from None
    unknown = sorted(set(data) - {"work", "trackers", "seeds", "base", "grid", "random",
                                  "search"})
    if unknown:
        raise OcctrackError(f"unknown key {unknown[0]!r}; a spec holds [work], trackers, "
                            f"seeds, [base], [grid], [random] and [search]", source)
    work = _table(data, "work", source)
    kind = work.get("kind")
    if kind not in KINDS:
        raise OcctrackError(f"[work] kind must be one of {', '.join(KINDS)}, not {kind!r}",
                            source)
    allowed = {"mot": {"kind", "sequences", "detections", "config"},
               "highway": {"kind", "steps", "sensors", "config"},
               "lidar": {"kind", "ranges", "samples"}}[kind]
    extra = sorted(set(work) - allowed)
    misplaced = [k for k in extra if k in ("trackers", "seeds")]
    if misplaced:
        raise OcctrackError(f"{misplaced[0]} belongs at the top of the spec, above [work] (in "
                            f"TOML a key after [work] is part of it)", source)
    if extra:
        raise OcctrackError(f"[work] key {extra[0]!r} is not used with kind = {kind!r} "
                            f"(it takes {', '.join(sorted(allowed))})", source)
    folder = path.resolve().parent
    config = None
    if "config" in work:
        if not isinstance(work["config"], str):
            raise OcctrackError("[work] config must be the path of a settings file", source)
        config = (folder / work["config"]).resolve()
        if not config.is_file():
            raise OcctrackError(f"[work] config {work['config']!r}: no such file", source)
        if kind == "highway":
            from occtrack.config.highway import load_highway

            load_highway(config)
        else:
            from occtrack.config import TrackerConfig

            TrackerConfig.from_toml(config)

    base = _table(data, "base", source)
    grid = _table(data, "grid", source)
    for name, values in grid.items():
        if not isinstance(values, list) or not values:
            raise OcctrackError(f"[grid] {name} must be a non-empty list of values", source)
    names = list(grid)
    grid_points = [dict(zip(names, combo, strict=True))
                   for combo in itertools.product(*(grid[n] for n in names))]
    random_points = _random_points(_table(data, "random", source), source)
    points = [{**base, **g, **r} for g in grid_points for r in random_points]
    search = None
    if "search" in data:
        if grid or data.get("random"):
            raise OcctrackError("[search] replaces [grid] and [random]: give one or the other "
                                "([base] holds the settings every trial shares)", source)
        search = _search(_table(data, "search", source), kind, base, source)

    spec_kwargs: dict = {}
    if kind == "mot":
        from occtrack.experiments.benchmark import MODELS, find_sequences

        trackers = _names(data.get("trackers", ["measurement-wise"]), MODELS, "trackers", source)
        sequences = work.get("sequences")
        if not isinstance(sequences, list) or not sequences or not all(
                isinstance(s, str) for s in sequences):
            raise OcctrackError("[work] sequences must be a non-empty list of folders",
                                source)
        found: list[Path] = []
        for entry in sequences:
            target = (folder / entry).resolve()
            try:
                found += find_sequences(target)
            except OcctrackError as err:
                raise OcctrackError(f"[work] sequences: {err}", source) from None
        detections = work.get("detections", "det")
        if detections not in DETECTIONS:
            raise OcctrackError(f"[work] detections must be one of {', '.join(DETECTIONS)}, "
                                f"not {detections!r}", source)
        default_seeds = [0]
        spec_kwargs.update(sequences=tuple(dict.fromkeys(found)), detections=detections)
    elif kind == "lidar":
        trackers = _names(data.get("trackers", list(LIDAR_TRACKERS)), LIDAR_TRACKERS,
                          "trackers", source)
        ranges = work.get("ranges", [20.0])
        if not isinstance(ranges, list) or not ranges or not all(
                isinstance(r, int | float) and not isinstance(r, bool) and r > 0
                for r in ranges):
            raise OcctrackError("[work] ranges must be a non-empty list of object ranges "
                                "> 0 (m)", source)
        samples = work.get("samples", 100_000)
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1000:
            raise OcctrackError(f"[work] samples must be a whole number >= 1000, not "
                                f"{samples!r}", source)
        default_seeds = [0]
        spec_kwargs.update(ranges=tuple(dict.fromkeys(float(r) for r in ranges)),
                           steps=samples)
    else:
        from occtrack.config.highway import SENSOR_MODES
        from occtrack.occlusion.highway import TRACKER_NAMES

        trackers = _names(data.get("trackers", list(TRACKER_NAMES)), TRACKER_NAMES, "trackers",
                          source)
        sensors = _names(work.get("sensors", list(SENSOR_MODES)), SENSOR_MODES,
                         "[work] sensors", source)
        steps = work.get("steps", 1000)
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise OcctrackError(f"[work] steps must be a whole number >= 1, not {steps!r}",
                                source)
        default_seeds = [1]
        spec_kwargs.update(sensors=tuple(sensors), steps=steps)
    seeds = _seeds(data.get("seeds", default_seeds), source)
    if kind == "mot" and spec_kwargs["detections"] == "det" and len(seeds) > 1:
        raise OcctrackError("seeds only matter with simulated detections: with detections = "
                            "\"det\" give one seed (or none)", source)
    spec = Spec(path=path, kind=kind, trackers=tuple(trackers), seeds=tuple(seeds),
                points=tuple(points), config=config, search=search, **spec_kwargs)
    if search is not None:
        # every setting checked at both ends of its range before any task runs
        for end in (0, -1):
            _checked(spec, {**base, **_law_end(search.laws, end)}, source)
        return dataclasses.replace(spec, points=())
    return dataclasses.replace(spec, points=tuple(_checked(spec, p, source) for p in points))


def _table(data: dict, name: str, source: str) -> dict:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise OcctrackError(f"{name} must be a table ([{name}])", source)
    return value


def _names(value, known, what: str, source: str) -> list[str]:
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise OcctrackError(f"{what} must be a non-empty list of names from "
                            f"{', '.join(known)}", source)
    bad = [v for v in value if v not in known]
    if bad:
        raise OcctrackError(f"{what}: unknown name {bad[0]!r}; choose from {', '.join(known)}",
                            source)
    return list(dict.fromkeys(value))


def _seeds(value, source: str) -> list[int]:
    if isinstance(value, int) and not isinstance(value, bool):
        if value < 1:
            raise OcctrackError(f"seeds = K must be at least 1 (seeds 1..K), not {value}",
                                source)
        return list(range(1, value + 1))
    if (not isinstance(value, list) or not value
            or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
                       for v in value)):
        raise OcctrackError("seeds must be a whole number K (seeds 1..K) or a non-empty list "
                            "of whole numbers >= 0", source)
    return list(dict.fromkeys(value))


def _random_points(table: dict, source: str) -> list[dict]:
    """`samples` draws of the [random] settings (seeded); [{}] without a [random] table."""
    if not table:
        return [{}]
    import numpy as np

    samples, seed = table.get("samples"), table.get("seed", 0)
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise OcctrackError("[random] samples must be a whole number >= 1", source)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise OcctrackError("[random] seed must be a whole number >= 0", source)
    laws = _laws({k: v for k, v in table.items() if k not in ("samples", "seed")}, "random",
                 source)
    rng = np.random.default_rng(seed)
    points = []
    for _ in range(samples):
        point = {}
        for name, law in laws.items():
            (how, args), = law.items()
            if how == "choice":
                point[name] = args[int(rng.integers(len(args)))]
            elif how == "uniform":
                point[name] = float(rng.uniform(args[0], args[1]))
            elif how == "log_uniform":
                point[name] = float(math.exp(rng.uniform(math.log(args[0]),
                                                         math.log(args[1]))))
            else:
                point[name] = int(rng.integers(args[0], args[1] + 1))
        points.append(point)
    return points


def _laws(laws: dict, table: str, source: str) -> dict:
    """The settings' distributions of a [random] or [search] table, checked."""
    if not laws:
        raise OcctrackError(f"[{table}] names no setting to draw", source)
    for name, law in laws.items():
        if not (isinstance(law, dict) and len(law) == 1 and next(iter(law)) in DISTRIBUTIONS):
            raise OcctrackError(f"[{table}] {name} must be one of "
                                + ", ".join(f"{{{d} = [...]}}" for d in DISTRIBUTIONS), source)
        (how, args), = law.items()
        if how == "choice":
            if not isinstance(args, list) or not args:
                raise OcctrackError(f"[{table}] {name}: choice needs a non-empty list", source)
            continue
        if not (isinstance(args, list) and len(args) == 2 and all(
                isinstance(a, int | float) and not isinstance(a, bool) for a in args)
                and args[0] <= args[1]):
            raise OcctrackError(f"[{table}] {name}: {how} needs [low, high] with low <= high",
                                source)
        if how == "log_uniform" and args[0] <= 0:
            raise OcctrackError(f"[{table}] {name}: log_uniform needs low > 0", source)
        if how == "int_uniform" and not all(isinstance(a, int) for a in args):
            raise OcctrackError(f"[{table}] {name}: int_uniform needs whole numbers", source)
    return laws


def _law_end(laws: dict, end: int) -> dict:
    """Each setting at one end of its range (end 0: low / first choice, -1: high / last)."""
    return {name: args[end] for name, law in laws.items() for args in law.values()}


def _search(table: dict, kind: str, base: dict, source: str) -> Search:
    """The [search] table, checked (its settings are checked against the schema later)."""
    fields = {"kind", "trials", "metric", "direction", "seed", "batch"}
    how = table.get("kind")
    if how not in SEARCH_KINDS:
        raise OcctrackError(f"[search] kind must be one of {', '.join(SEARCH_KINDS)}, not "
                            f"{how!r}", source)
    whole = {}
    for name, default in (("trials", None), ("seed", 0), ("batch", 4)):
        value = table.get(name, default)
        low = 0 if name == "seed" else 1
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise OcctrackError(f"[search] {name} must be a whole number >= {low}", source)
        whole[name] = value
    metrics = {"mot": MOT_METRICS, "highway": HIGHWAY_METRICS, "lidar": LIDAR_METRICS}[kind]
    metric = table.get("metric")
    if metric not in metrics:
        raise OcctrackError(f"[search] metric must be one of {', '.join(metrics)} (kind "
                            f"{kind!r}), not {metric!r}", source)
    direction = table.get("direction")
    if direction not in DIRECTIONS:
        raise OcctrackError(f"[search] direction must be \"maximize\" or \"minimize\", not "
                            f"{direction!r}", source)
    laws = _laws({k: v for k, v in table.items() if k not in fields}, "search", source)
    return Search(how, whole["trials"], metric, direction, whole["seed"], whole["batch"], laws,
                  base)


def _checked(spec: Spec, point: dict, source: str) -> dict:
    """The point's settings, typed as their fields (so equal settings give equal keys), or
    OcctrackError naming the bad one, before any task runs."""
    if spec.kind == "mot":
        from occtrack.config import TrackerConfig

        if "occlusion" in point:
            raise OcctrackError("occlusion is chosen by trackers = [...], not by a setting",
                                source)
        base = _config_values(spec.config)
        config = TrackerConfig.from_dict({**base, **point}, source)
        return {name: _plain(getattr(config, name)) for name in point}
    if spec.kind == "lidar":
        model = _beam_model(point, source)
        far = [x for x in spec.ranges if x >= model.max_range]
        if far:
            raise OcctrackError(f"[work] ranges: {far[0]:g} m is not inside the sensor's "
                                f"max_range {model.max_range:g} m", source)
        return {name: float(getattr(model, name)) for name in point}
    sim, road, tracker = _split_highway(point, source)
    simulation, tracking = _highway_configs(spec.config, sim, road, tracker, source)
    typed = {}
    for name in point:
        if name.startswith("simulation.road."):
            typed[name] = getattr(simulation.road, name.rsplit(".", 1)[1])
        elif name.startswith("simulation."):
            typed[name] = getattr(simulation, name.split(".", 1)[1])
        else:
            typed[name] = getattr(tracking, name)
    return {name: _plain(value) for name, value in typed.items()}


def _beam_model(point: dict, source: str):
    """The lidar's BeamModel with a point's settings (its fields: p_d, sigma, clutter_rate,
    max_range), or OcctrackError naming the bad one."""
    from occtrack.models.beam import BeamModel

    names = {f.name for f in dataclasses.fields(BeamModel)}
    bad = sorted(set(point) - names)
    if bad:
        raise OcctrackError(f"unknown lidar setting {bad[0]!r}; the settings are "
                            f"{', '.join(sorted(names))}", source)
    try:
        return BeamModel(**{k: float(v) for k, v in point.items()})
    except (TypeError, ValueError) as err:
        raise OcctrackError(f"lidar settings: {err}", source) from None


def _plain(value):
    """A setting as JSON holds it: tuples as lists, numbers as they are."""
    return list(value) if isinstance(value, tuple) else value


def _config_values(path: Path | None) -> dict:
    if path is None:
        return {}
    from occtrack.config import load_toml

    return load_toml(path)


def _split_highway(point: dict, source: str) -> tuple[dict, dict, dict]:
    sim, road, tracker = {}, {}, {}
    for name, value in point.items():
        if name.startswith("simulation.road."):
            road[name.rsplit(".", 1)[1]] = value
        elif name.startswith("simulation."):
            sim[name.split(".", 1)[1]] = value
        else:
            tracker[name] = value
    return sim, road, tracker


def _highway_configs(path: Path | None, sim: dict, road: dict, tracker: dict, source: str):
    """The highway's SimulationConfig and HighwayTrackerConfig from the spec's settings file
    (if any, as for `occtrack simulate highway --config`) and a point's settings, which win;
    the tracker matches the simulation's model unless set (`occtrack.config.highway`)."""
    from occtrack.config.highway import (
        HighwayTrackerConfig,
        RoadConfig,
        SimulationConfig,
        highway_from_dict,
    )

    data: dict = {}
    if path is not None:
        from occtrack.config import load_toml

        data = load_toml(path)
    known = {"simulation.": SimulationConfig, "simulation.road.": RoadConfig,
             "": HighwayTrackerConfig}
    for prefix, values in (("simulation.", sim), ("simulation.road.", road), ("", tracker)):
        names = {f.name for f in dataclasses.fields(known[prefix])} - {"road"}
        bad = sorted(set(values) - names)
        if bad:
            raise OcctrackError(f"unknown highway setting {prefix + bad[0]!r}; highway settings "
                                f"are the tracker's fields, simulation.NAME and "
                                f"simulation.road.NAME", source)
    file_sim = data.get("simulation", {})
    file_road = file_sim.get("road", {}) if isinstance(file_sim, dict) else {}
    merged = {**data, "tracker": _merged(data.get("tracker", {}), tracker),
              "simulation": _merged(file_sim, {**sim, "road": _merged(file_road, road)})}
    return highway_from_dict(merged, source)


def _merged(table, overrides: dict):
    """A settings table with a point's settings over it (a table that is not one is left for
    the schema to refuse)."""
    return {**table, **overrides} if isinstance(table, dict) else table


# ----------------------------------------------------------------------------------------------
# The plan


def plan(spec: Spec) -> list[Cell]:
    """Every cell of the spec, in a fixed order: work item, tracker, point, seed."""
    config_text = ""
    if spec.config is not None:
        config_text = spec.config.read_text(encoding="utf-8")
    config_hash = hashlib.sha256(config_text.encode()).hexdigest()[:16] if config_text else ""
    cells: list[Cell] = []
    if spec.kind == "mot":
        from occtrack.io.mot import read_seqinfo

        works = []
        for folder in spec.sequences:
            works.append((str(read_seqinfo(folder)["name"]), str(folder)))
        names = [name for name, _ in works]
        if len(set(names)) < len(names):
            raise OcctrackError("two sequence folders share a name in seqinfo.ini",
                                str(spec.path))
    elif spec.kind == "lidar":
        works = [(f"x={x:g}m", repr(x)) for x in spec.ranges]
    else:
        works = [(sensor, "") for sensor in spec.sensors]
    for (work, source), tracker, point, seed in itertools.product(
            works, spec.trackers, spec.points, spec.seeds):
        settings = json.dumps(point, sort_keys=True)
        identity = {"kind": spec.kind, "work": work, "tracker": tracker, "seed": seed,
                    "settings": json.loads(settings), "config": config_hash}
        if spec.kind == "mot":
            identity["detections"] = spec.detections
            identity["protocol"] = "mot17"
        else:
            identity["steps"] = spec.steps  # lidar: simulated beams per case
        key = hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:20]
        cells.append(Cell(index=len(cells), key=key, kind=spec.kind, work=work,
                          tracker=tracker, seed=seed, settings=settings, source=source,
                          detections=spec.detections, steps=spec.steps,
                          config=str(spec.config) if spec.config else ""))
    return cells
