"""Progress bars for long work: a bar on a terminal, silent with --quiet or when not a tty.

No thread is started and no lock is shared, bar or no bar: a silent run does not touch tqdm,
and a bar runs without tqdm's monitor thread (which only retunes how often a bar redraws;
with miniters=1 the bar reads the clock at every item instead) and with a lock of this process
(tqdm's default also takes a multiprocessing lock, shared with every process forked from this
one). A library call such as `Tracker.run` leaves nothing running behind it, and a forked
worker killed while drawing cannot leave the other processes waiting for its lock (as seen
under mutmut, whose forked runs hung on it)."""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")


def progress(items: Iterable[T], total: int | None = None, desc: str = "",
             quiet: bool = False) -> Iterator[T]:
    if quiet or not sys.stderr.isatty():
        yield from items
        return
    from tqdm import tqdm

    class Bar(tqdm):
        monitor_interval = 0

    Bar.set_lock(threading.RLock())
    yield from Bar(items, total=total, desc=desc, leave=False, file=sys.stderr,
                   dynamic_ncols=True, miniters=1)


def summary(frames: int, tracks: int, seconds: float, what: str = "frames") -> str:
    """The one-line closing summary every long command prints."""
    fps = frames / seconds if seconds > 0 else float("inf")
    return f"{frames} {what}, {tracks} tracks, {seconds:.2f} s, {fps:.1f} {what} per second"
