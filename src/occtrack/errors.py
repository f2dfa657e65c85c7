"""The one error type users see: it names the file, the line and the problem."""

from __future__ import annotations


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
