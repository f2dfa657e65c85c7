"""A simulated lidar scene written as files a user's own scanner could produce: scans.csv
(one row a beam), truth.csv (one row an object a scan) and sensor.csv (the sensor's pose a
scan), formats in `occtrack.io.scans`.

The three are written as the scans are simulated (a scene never sits in memory whole), each to
a temporary file renamed into place only when all are complete (`occtrack.io.atomic`); an
existing file is refused before any work unless `overwrite`. Fixed decimals (0.1 mm, 1 micro-
radian, 1 microsecond) make one seed's files the same byte for byte on every run.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.config.lidar import LidarSceneConfig
from occtrack.errors import OcctrackError
from occtrack.io import scans as fmt
from occtrack.io.atomic import atomic_write, check_output
from occtrack.scenarios.lidar.scene import (
    LidarScan,
    Occlusions,
    beam_angles,
    full_occlusions,
    simulate_scene,
)

FILES = ("scans.csv", "truth.csv", "sensor.csv")


@dataclass(frozen=True)
class SceneSummary:
    """What was written: scans, beams a scan, distinct people and vehicles, the spells of
    full occlusion."""

    scans: int
    beams: int
    objects: int
    occlusions: Occlusions


def settings_comment(config: LidarSceneConfig, seed: int) -> str:
    """Every setting and the seed as key=value words: the scene can be made again."""
    words = [f"{f.name}={getattr(config, f.name)}" for f in dataclasses.fields(config)]
    return " ".join([*words, f"seed={seed}"])


def headers(config: LidarSceneConfig, seed: int) -> tuple[str, str, str]:
    settings = settings_comment(config, seed)
    return (
        fmt.header(fmt.SCAN_COLUMNS, [
            "occtrack simulate lidar: one row a beam; time s, angle rad counter-clockwise "
            "from the sensor's heading, range m (inf: no return)", settings]),
        fmt.header(fmt.TRUTH_COLUMNS, [
            "occtrack simulate lidar: one row an object a scan, world frame; occluded = "
            "clear_beams > 0 and visible_beams == 0", settings]),
        fmt.header(fmt.POSE_COLUMNS, ["occtrack simulate lidar: the sensor's pose a scan, "
                                      "world frame", settings]),
    )


def check_folder(folder: str | Path, overwrite: bool) -> list[Path]:
    """The three outputs in `folder` (made if missing), each refused before any work if it
    exists and not `overwrite`."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise OcctrackError("is a file; give a folder for scans.csv, truth.csv and sensor.csv",
                            str(folder))
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / name for name in FILES]
    for path in paths:
        check_output(path, overwrite)
    return paths


def _rows(scan: LidarScan, angles: list[str]) -> tuple[str, str, str]:
    o = scan.objects
    s = o.shapes
    return (fmt.scan_rows(scan.time, angles, scan.range),
            fmt.truth_rows(scan.time, o.id, s.disc, s.centre, o.velocity, s.length, s.width,
                           s.heading, scan.clear, scan.visible),
            fmt.pose_row(scan.time, scan.pose))


def write_scene(folder: str | Path, config: LidarSceneConfig, scans: int, seed: int,
                overwrite: bool = False,
                wrap: Callable[[Iterator[LidarScan]], Iterable[LidarScan]] = iter,
                ) -> SceneSummary:
    """Simulate `scans` scans of seed `seed` into folder/scans.csv, truth.csv and sensor.csv.
    `wrap` wraps the scans as they come (a progress bar)."""
    paths = check_folder(folder, overwrite)
    angles = fmt.angle_text(beam_angles(config))
    times, ids, occluded = [], [], []
    with ExitStack() as stack:
        files = [stack.enter_context(atomic_write(p, overwrite)) for p in paths]
        for fh, text in zip(files, headers(config, seed), strict=True):
            fh.write(text)
        for scan in wrap(simulate_scene(config, scans, seed)):
            for fh, text in zip(files, _rows(scan, angles), strict=True):
                fh.write(text)
            times.append(np.full(len(scan.objects), scan.time))
            ids.append(scan.objects.id)
            occluded.append(scan.occluded)
    ids_ = np.concatenate(ids) if ids else np.zeros(0, np.int64)
    spells = full_occlusions(np.concatenate(times) if times else np.zeros(0), ids_,
                             np.concatenate(occluded) if occluded else np.zeros(0, bool),
                             config.period)
    return SceneSummary(scans, config.beams, len(np.unique(ids_)), spells)

