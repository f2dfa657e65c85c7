"""Synthetic MOTChallenge sequence folders for the tests of the commands that read them
(benchmark, report, sweep): seqinfo.ini, gt/gt.txt and det/det.txt from a simulated crowd."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occtrack.scenarios.pedestrians import Crowd, Scene, crowd_scene

SEQINFO = """[Sequence]
name={name}
imDir=img1
frameRate=10
seqLength={length}
imWidth=1280
imHeight=720
imExt=.jpg
"""


def write_rows(path: Path, table, gt: bool, shuffle: bool = False) -> None:
    """MOTChallenge rows of `table`: gt with consider flag, class 1 and visibility 1;
    detections with id -1 and their scores. `shuffle` writes the rows in a fixed random
    order, as real detection files come."""
    tail = (lambda i: "1,1,1") if gt else (lambda i: f"{table.score[i]:.3f},-1,-1")
    ids = table.id if gt else np.full(len(table), -1)
    order = np.random.default_rng(0).permutation(len(table)) if shuffle else range(len(table))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(
        f"{table.frame[i]},{ids[i]},{table.box[i, 0]:.2f},{table.box[i, 1]:.2f},"
        f"{table.box[i, 2]:.2f},{table.box[i, 3]:.2f},{tail(i)}\n" for i in order))


def write_sequence(folder: Path, name: str, *, people: int, frames: int, length: int,
                   seed: int, truth_as_detections: bool = False,
                   shuffle: bool = False) -> Scene:
    """A sequence folder of `length` frames (1280 x 720 at 10 fps) whose first `frames`
    hold a crowd of `people`; returns the simulated scene."""
    scene = crowd_scene(Crowd(people=people, frames=frames, image_size=(1280.0, 720.0),
                              fps=10.0), seed=seed)
    folder.mkdir(parents=True)
    (folder / "seqinfo.ini").write_text(SEQINFO.format(name=name, length=length))
    write_rows(folder / "gt" / "gt.txt", scene.truth, gt=True, shuffle=shuffle)
    write_rows(folder / "det" / "det.txt",
               scene.truth if truth_as_detections else scene.detections, gt=False,
               shuffle=shuffle)
    return scene
