"""The one error type users see: it names the file, the line and the problem."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class OcctrackError(Exception):
    """Bad input or configuration. The CLI prints it as one line and exits with status 1."""

    def __init__(self, message: str, path: str | None = None, line: int | None = None):
        self.message = message
        self.path = path
        self.line = line
        super().__init__(str(self))

    def __str__(self) -> str:
        where = ""
        if self.path is not None:
            where = f"{self.path}:{self.line}: " if self.line is not None else f"{self.path}: "
        return where + self.message


@contextmanager
def opening(path: str, expected: str) -> Iterator[None]:
    """A missing file or a folder where `expected` (say "a TOML file") was wanted, met while
    reading `path`, as one OcctrackError naming it; other errors pass through."""
    try:
        yield
    except FileNotFoundError:
        raise OcctrackError("no such file", path) from None
    except IsADirectoryError:
        raise OcctrackError(f"is a directory, expected {expected}", path) from None
