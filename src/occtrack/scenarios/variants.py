"""Variants of a MOTChallenge sequence that a default must survive: another resolution,
another frame rate, a moving camera.

Each variant is derived from a real sequence folder (seqinfo.ini, det/det.txt, gt/gt.txt) by
transforming detections and ground truth alike, so every score stays comparable:

- `scaled`: boxes and image scaled by one factor (MOT17-04 at 640x360 is a factor of 1/3);
- `subsampled`: every k-th frame kept and renumbered, the frame rate divided by k;
- `panned`: a synthetic camera sway, every box of frame t moved by
  (a_x sin(2 pi t / T), a_y sin(4 pi t / T)) with amplitudes a fraction of the image size;
  a sway rather than a steady pan keeps the people in the picture.

A tracker whose settings are in units that transfer should score about the same on each.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from occtrack.io.atomic import atomic_write
from occtrack.io.mot import MotTable, read_mot, read_seqinfo

VARIANTS = ("640x360", "15fps", "10fps", "pan")


def scaled(table: MotTable, factor: float) -> MotTable:
    return MotTable(table.frame, table.id, table.box * factor, table.score, table.cls,
                    table.visibility, table.path)


def subsampled(table: MotTable, step: int) -> MotTable:
    keep = (table.frame - 1) % step == 0
    t = table.select(keep)
    return MotTable((t.frame - 1) // step + 1, t.id, t.box, t.score, t.cls, t.visibility,
                    t.path)


def panned(table: MotTable, fps: float, image_size: tuple[float, float],
           amplitude: float = 0.05, period: float = 4.0) -> MotTable:
    """Boxes of frame t moved by the sway at time (t - 1) / fps."""
    phase = 2.0 * np.pi * (table.frame - 1) / fps / period
    shift = np.stack([amplitude * image_size[0] * np.sin(phase),
                      amplitude * image_size[1] * np.sin(2.0 * phase)], axis=1)
    box = table.box.copy()
    box[:, :2] += shift
    return MotTable(table.frame, table.id, box, table.score, table.cls, table.visibility,
                    table.path)


def _write(path: Path, table: MotTable) -> None:
    order = np.lexsort((table.id, table.frame))
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, overwrite=True) as fh:
        for i in order:
            l, t, w, h = table.box[i]
            fh.write(f"{table.frame[i]},{table.id[i]},{l:.3f},{t:.3f},{w:.3f},{h:.3f},"
                     f"{table.score[i]:g},{table.cls[i]},{table.visibility[i]:g}\n")


def write_variant(sequence: str | Path, variant: str, out_root: str | Path) -> Path:
    """Write `variant` of the sequence folder as OUT_ROOT/NAME-VARIANT; returns that folder."""
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {', '.join(VARIANTS)}, not {variant!r}")
    info = read_seqinfo(sequence)
    det = read_mot(Path(sequence) / "det" / "det.txt", "det")
    gt = read_mot(Path(sequence) / "gt" / "gt.txt", "gt")
    width, height = float(info["width"]), float(info["height"])
    fps, length = float(info["fps"]), int(info["length"])
    if variant == "640x360":
        factor = 640.0 / width
        det, gt = scaled(det, factor), scaled(gt, factor)
        width, height = width * factor, height * factor
    elif variant in ("15fps", "10fps"):
        step = max(1, round(fps / float(variant[:2])))
        det, gt = subsampled(det, step), subsampled(gt, step)
        fps, length = fps / step, math.ceil(length / step)
    else:
        det = panned(det, fps, (width, height))
        gt = panned(gt, fps, (width, height))
    folder = Path(out_root) / f"{info['name']}-{variant}"
    _write(folder / "det" / "det.txt", det)
    _write(folder / "gt" / "gt.txt", gt)
    with atomic_write(folder / "seqinfo.ini", overwrite=True) as fh:
        fh.write(f"[Sequence]\nname={folder.name}\nframeRate={fps:g}\nseqLength={length}\n"
                 f"imWidth={round(width)}\nimHeight={round(height)}\n")
    return folder
