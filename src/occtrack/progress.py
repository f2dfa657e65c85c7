"""Progress bars for long work: a bar on a terminal, silent with --quiet or when not a tty."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")


def progress(items: Iterable[T], total: int | None = None, desc: str = "",
             quiet: bool = False) -> Iterator[T]:
    from tqdm import tqdm

    disable = quiet or not sys.stderr.isatty()
    yield from tqdm(items, total=total, desc=desc, disable=disable, leave=False,
                    file=sys.stderr, dynamic_ncols=True)


def summary(frames: int, tracks: int, seconds: float, what: str = "frames") -> str:
    """The one-line closing summary every long command prints."""
    fps = frames / seconds if seconds > 0 else float("inf")
    return f"{frames} {what}, {tracks} tracks, {seconds:.2f} s, {fps:.1f} {what} per second"
