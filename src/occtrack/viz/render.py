"""Tracks drawn on the real frames: a video file or a folder of pictures (`occtrack render`).

Each track gets a colour of its own (by id), its id on a label, and a trail through the bottom
centres of its last boxes (where a person stands). A track reported without a detection this
frame (coasting on the filter's estimate) is drawn dashed; one whose miss is put down to
occlusion is labelled "occluded" too. Frames are read and written with imageio (its PyAV
plugin for video) and drawn with Pillow: the `viz` extra.

Frames and rows are matched by number: frame f of a MOTChallenge file is the f-th frame of a
video, and in a folder the picture whose name is the number f (MOT's img1/000001.jpg), or the
f-th picture in name order when the names are not numbers.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.extras import require

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp")
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".gif")

# Tableau 20 without its greys: distinct on dark and light scenes
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#bcbd22", "#17becf", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896", "#c5b0d5",
           "#c49c94", "#f7b6d2", "#dbdb8d", "#9edae5")


@dataclass(frozen=True)
class Overlay:
    """What to draw, one row per box: frame (N,), id (N,), box (N, 4) left, top, width,
    height, coasting (N,) and occluded (N,)."""

    frame: np.ndarray
    id: np.ndarray
    box: np.ndarray
    coasting: np.ndarray
    occluded: np.ndarray

    def by_frame(self) -> dict[int, np.ndarray]:
        rows: dict[int, list[int]] = defaultdict(list)
        for i, f in enumerate(self.frame.tolist()):
            rows[f].append(i)
        return {f: np.array(r, dtype=np.int64) for f, r in rows.items()}


def colour(track_id: int) -> tuple[int, int, int]:
    code = PALETTE[int(track_id) % len(PALETTE)]
    return int(code[1:3], 16), int(code[3:5], 16), int(code[5:7], 16)


# -- reading frames ---------------------------------------------------------------------------


def image_files(folder: str | os.PathLike) -> list[tuple[int, Path]]:
    """(frame number, path) of every picture in `folder`, in frame order."""
    root = Path(folder)
    if not root.is_dir():
        raise OcctrackError("no such folder of frames", str(root))
    files = sorted(p for p in root.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES
                   and not p.name.startswith("."))
    if not files:
        raise OcctrackError(f"no pictures here ({', '.join(IMAGE_SUFFIXES)})", str(root))
    if all(re.fullmatch(r"\d+", p.stem) for p in files):
        numbered = sorted((int(p.stem), p) for p in files)
        if len({n for n, _ in numbered}) == len(numbered):
            return numbered
    return [(k, p) for k, p in enumerate(files, start=1)]


def read_image(path: Path) -> np.ndarray:
    iio = require("imageio.v3", "reading frames")
    try:
        image = np.asarray(iio.imread(path))
    except Exception as err:  # imageio raises many kinds for a bad picture
        raise OcctrackError(f"cannot read this picture: {err}", str(path)) from None
    return _rgb(image, path)


def _rgb(image: np.ndarray, where: object) -> np.ndarray:
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise OcctrackError(f"not a colour or grey picture (shape {image.shape})", str(where))
    if image.dtype != np.uint8:
        top = 65535.0 if image.dtype == np.uint16 else max(float(image.max()), 1.0)
        image = np.clip(image.astype(float) / top * 255.0, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(image[:, :, :3])


def video_frames(path: str | os.PathLike) -> tuple[Iterator[tuple[int, np.ndarray]], dict]:
    """(frame number, image) of every frame of a video, and its metadata (fps, ...)."""
    iio = require("imageio.v3", "reading video")
    require("av", "reading video")
    if not Path(path).is_file():
        raise OcctrackError("no such video file", str(path))
    try:
        meta = dict(iio.immeta(path, plugin="pyav"))
    except Exception as err:  # PyAV raises its own kinds for a file it cannot decode
        raise OcctrackError(f"cannot read this video: {err}", str(path)) from None

    def frames() -> Iterator[tuple[int, np.ndarray]]:
        try:
            for k, image in enumerate(iio.imiter(path, plugin="pyav"), start=1):
                yield k, _rgb(np.asarray(image), path)
        except OcctrackError:
            raise
        except Exception as err:
            raise OcctrackError(f"cannot read this video: {err}", str(path)) from None

    return frames(), meta


def first_frame_size(images: str | None, video: str | None) -> tuple[tuple[int, int], dict]:
    """(width, height) of the first frame, and the video's metadata ({} for pictures)."""
    if images is not None:
        image = read_image(image_files(images)[0][1])
        return (image.shape[1], image.shape[0]), {}
    frames, meta = video_frames(video)
    try:
        _, image = next(frames)
    except StopIteration:
        raise OcctrackError("the video has no frames", str(video)) from None
    finally:
        frames.close()
    return (image.shape[1], image.shape[0]), meta


# -- drawing ----------------------------------------------------------------------------------


def _dashed_line(draw, a, b, fill, width: int, dash: float) -> None:
    (x0, y0), (x1, y1) = a, b
    length = float(np.hypot(x1 - x0, y1 - y0))
    if length == 0:
        return
    steps = max(int(length // dash), 1)
    for k in range(0, steps, 2):
        t0, t1 = k / steps, min((k + 1) / steps, 1.0)
        draw.line([(x0 + (x1 - x0) * t0, y0 + (y1 - y0) * t0),
                   (x0 + (x1 - x0) * t1, y0 + (y1 - y0) * t1)], fill=fill, width=width)


def _rectangle(draw, box, fill, width: int, dashed: bool) -> None:
    left, top, w, h = box
    corners = [(left, top), (left + w, top), (left + w, top + h), (left, top + h)]
    if not dashed:
        draw.rectangle([left, top, left + w, top + h], outline=fill, width=width)
        return
    dash = max(3.0 * width, 6.0)
    for a, b in zip(corners, corners[1:] + corners[:1], strict=True):
        _dashed_line(draw, a, b, fill, width, dash)


class Painter:
    """Draws one frame's tracks with their trails: the bottom centres of each shown track's
    boxes over the last `trail` frames of the overlay (whether or not those were drawn)."""

    def __init__(self, overlay: Overlay, height: int, trail: int = 30, scale: float = 1.0):
        self.overlay = overlay
        self.trail = trail
        self.scale = scale
        self.width = max(2, round(height * scale / 360))
        self.font_size = max(12, round(height * scale / 54))
        self._font = None
        order = np.lexsort((overlay.frame, overlay.id))
        self._order = order
        ids = overlay.id[order]
        starts = np.flatnonzero(np.diff(ids, prepend=ids[:1] - 1)) if len(ids) else ids
        self._span = {int(ids[a]): (a, b) for a, b in zip(starts, np.append(starts[1:], len(ids)),
                                                           strict=True)}
        box = overlay.box[order]
        self._feet = np.stack([box[:, 0] + box[:, 2] / 2.0, box[:, 1] + box[:, 3]], axis=1)

    def font(self):
        if self._font is None:
            ImageFont = require("PIL.ImageFont", "drawing labels")
            try:
                self._font = ImageFont.load_default(size=self.font_size)
            except TypeError:  # Pillow < 10.1: one small bitmap font
                self._font = ImageFont.load_default()
        return self._font

    def trail_of(self, track_id: int, frame: int) -> np.ndarray:
        """Bottom centres (k, 2) of the track's boxes in frames frame - trail + 1 .. frame."""
        a, b = self._span[track_id]
        frames = self.overlay.frame[self._order[a:b]]
        lo, hi = np.searchsorted(frames, [frame - self.trail + 1, frame + 1])
        return self._feet[a + lo:a + hi]

    def draw(self, image: np.ndarray, frame: int, rows: np.ndarray) -> np.ndarray:
        Image = require("PIL.Image", "drawing frames")
        ImageDraw = require("PIL.ImageDraw", "drawing frames")
        picture = Image.fromarray(image)
        s = self.scale
        if s != 1.0:
            size = (max(1, round(picture.width * s)), max(1, round(picture.height * s)))
            picture = picture.resize(size, Image.LANCZOS)
        draw = ImageDraw.Draw(picture)
        overlay = self.overlay
        if self.trail > 1:
            for i in rows:
                track_id = int(overlay.id[i])
                points = self.trail_of(track_id, frame) * s
                if len(points) > 1:
                    draw.line([tuple(p) for p in points], fill=colour(track_id),
                              width=max(1, self.width - 1), joint="curve")
        font = self.font()
        for i in rows:
            track_id = int(overlay.id[i])
            fill = colour(track_id)
            box = overlay.box[i] * s
            _rectangle(draw, box, fill, self.width, bool(overlay.coasting[i]))
            text = f"{track_id}" + (" occluded" if overlay.occluded[i] else "")
            x, y = float(box[0]), float(box[1])
            l_, t_, r_, b_ = draw.textbbox((0, 0), text, font=font)
            pad = max(1, self.width)
            y_label = y - (b_ - t_) - 2 * pad if y - (b_ - t_) - 2 * pad >= 0 else y
            draw.rectangle([x, y_label, x + (r_ - l_) + 2 * pad, y_label + (b_ - t_) + 2 * pad],
                           fill=fill)
            draw.text((x + pad - l_, y_label + pad - t_), text, fill=(255, 255, 255), font=font)
        return np.asarray(picture)


# -- writing ----------------------------------------------------------------------------------


def is_video_path(path: str | os.PathLike) -> bool:
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


def is_picture_path(path: str | os.PathLike) -> bool:
    return Path(path).suffix.lower() in IMAGE_SUFFIXES


class FolderWriter:
    """Frames as numbered JPEG (or PNG) pictures in a new folder, which replaces the old one
    only once every frame is written."""

    def __init__(self, folder: str | os.PathLike, overwrite: bool, suffix: str = ".jpg"):
        self.target = Path(folder)
        if self.target.exists() and not overwrite:
            raise OcctrackError("exists already; pass --force to replace it", str(self.target))
        if self.target.exists() and not self.target.is_dir():
            raise OcctrackError("is a file; give a folder (or a video file name ending in "
                                f"{', '.join(VIDEO_SUFFIXES)})", str(self.target))
        if not self.target.resolve().parent.is_dir():
            raise OcctrackError("folder does not exist", str(self.target.parent))
        self.tmp = self.target.with_name(f".{self.target.name}.{secrets.token_hex(4)}.partial")
        self.tmp.mkdir()
        self.suffix = suffix
        self.count = 0

    def write(self, frame: int, image: np.ndarray) -> None:
        iio = require("imageio.v3", "writing frames")
        extra = {"quality": 92} if self.suffix == ".jpg" else {}
        iio.imwrite(self.tmp / f"{frame:06d}{self.suffix}", image, **extra)
        self.count += 1

    def close(self, ok: bool) -> None:
        if not ok:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return
        if self.target.exists():
            old = self.target.with_name(f".{self.target.name}.{secrets.token_hex(4)}.old")
            os.replace(self.target, old)
            os.replace(self.tmp, self.target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(self.tmp, self.target)


class VideoWriter:
    """Frames into one video file (H.264 in MP4 and the like through PyAV, GIF through
    Pillow); the format follows the file's suffix. Give it the temporary name of
    `occtrack.io.atomic.atomic_path`, so that the video appears whole or not at all."""

    def __init__(self, path: str | os.PathLike, fps: float):
        self.path = Path(path)
        self.fps = fps
        self.writer = None
        self.count = 0

    def write(self, frame: int, image: np.ndarray) -> None:
        iio = require("imageio.v3", "writing video")
        if self.path.suffix.lower() == ".gif":
            if self.writer is None:
                self.writer = iio.imopen(self.path, "w", plugin="pillow")
                self._gif: list[np.ndarray] = []
            self._gif.append(image)
        else:
            if self.writer is None:
                require("av", "writing video")
                self.writer = iio.imopen(self.path, "w", plugin="pyav")
                codec = "libvpx-vp9" if self.path.suffix.lower() == ".webm" else "libx264"
                self.writer.init_video_stream(codec, fps=self.fps)
            h, w = image.shape[:2]
            self.writer.write_frame(image[:h - h % 2, :w - w % 2])  # yuv420p: even sizes
        self.count += 1

    def close(self, ok: bool) -> None:
        if self.writer is None:
            return
        try:
            if ok and self.path.suffix.lower() == ".gif":
                self.writer.write(np.stack(self._gif), duration=1000.0 / self.fps, loop=0)
        finally:
            self.writer.close()
            self.writer = None


class PictureWriter:
    """One frame (the last one handed to it) as one picture, at the given (temporary) path."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.image: np.ndarray | None = None
        self.count = 0

    def write(self, frame: int, image: np.ndarray) -> None:
        self.image = image
        self.count = 1

    def close(self, ok: bool) -> None:
        if ok and self.image is not None:
            iio = require("imageio.v3", "writing pictures")
            extension = self.path.suffix.lower()
            iio.imwrite(self.path, self.image, extension=extension,
                        **({"quality": 92} if extension in (".jpg", ".jpeg") else {}))


def render(overlay: Overlay, frames: Iterator[tuple[int, np.ndarray]], writer,
           trail: int = 30, first: int = 1, last: int | None = None,
           scale: float = 1.0) -> int:
    """Draw `overlay` on every frame from `first` to `last` and hand them to `writer`;
    returns the number of frames written. The writer is closed (kept or discarded)."""
    by_frame = overlay.by_frame()
    painter = None
    ok = False
    empty = np.zeros(0, dtype=np.int64)
    try:
        for number, image in frames:
            if number < first:
                continue
            if last is not None and number > last:
                break
            if painter is None:
                painter = Painter(overlay, image.shape[0], trail, scale)
            writer.write(number, painter.draw(image, number, by_frame.get(number, empty)))
        if writer.count == 0:
            raise OcctrackError("no frames in the range asked for; check --frames")
        ok = True
    finally:
        writer.close(ok)
    return writer.count
