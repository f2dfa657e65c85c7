"""The progress bar: every item passes through, drawn on a terminal only, and no thread is
left running (a quiet library call included)."""

import io
import threading

import pytest

from occtrack.progress import progress, summary


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize("tty", [True, False], ids=["terminal", "pipe"])
@pytest.mark.parametrize("quiet", [False, True], ids=["bar", "quiet"])
def test_items_pass_through_and_no_thread_starts(monkeypatch, tty, quiet):
    stderr = Terminal() if tty else io.StringIO()
    monkeypatch.setattr("sys.stderr", stderr)
    before = {t.ident for t in threading.enumerate()}
    seen, started = [], []
    for item in progress(range(5), 5, "working", quiet):
        seen.append(item)
        started.append({t.name for t in threading.enumerate() if t.ident not in before})
    assert seen == list(range(5))
    assert started == [set()] * 5
    assert {t.ident for t in threading.enumerate()} <= before
    assert ("working" in stderr.getvalue()) == (tty and not quiet)


def test_summary_line():
    assert summary(100, 7, 2.0) == "100 frames, 7 tracks, 2.00 s, 50.0 frames per second"
    assert summary(0, 0, 0.0, "steps") == "0 steps, 0 tracks, 0.00 s, inf steps per second"
