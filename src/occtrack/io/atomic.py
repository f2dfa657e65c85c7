"""Outputs are written whole or not at all.

Every file occtrack writes goes first to a temporary file in the destination's folder and is
renamed over the destination only once complete (`os.replace` is atomic within a folder), so a
run that fails or is interrupted midway (an error, Ctrl-C, a full disk) leaves the old file, or
none, never a partial one. The old file is never removed before its replacement is complete.
A FIFO or a device (`-o /dev/null`) is no file to replace: it is written into directly, as
standard output is.
"""

from __future__ import annotations

import os
import secrets
import shutil
import stat
import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import IO

from occtrack.errors import OcctrackError

STDOUT = "-"


def _same_file(a: Path, b: str | os.PathLike) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def check_output(path: str | os.PathLike, overwrite: bool = False,
                 inputs: Iterable[str | os.PathLike | None] = ()) -> Path | None:
    """Refuse an output before any work is done: one of the `inputs` (so writing it would
    destroy what is being read), a folder, an existing file without `overwrite`, a missing
    folder, or a folder one cannot write in (an OSError naming `path`: no permission, a
    read-only disk). Returns the path, or None for "-" (standard output)."""
    if str(path) == STDOUT:
        return None
    target = Path(path)
    for source in inputs:
        if source is not None and str(source) != STDOUT and _same_file(target, source):
            raise OcctrackError(f"is also an input ({source}); write the output to another file",
                                str(target))
    if target.is_dir():
        raise OcctrackError("is a folder; give a file name for the output", str(target))
    if is_special(target):  # written in place (`atomic_path`): nothing there is replaced
        return target
    if target.exists() and not overwrite:
        raise OcctrackError("exists already; pass --force to overwrite it", str(target))
    if not target.resolve().parent.is_dir():
        raise OcctrackError("folder does not exist", str(target.parent))
    _probe(target)
    return target


def is_special(target: Path) -> bool:
    """Whether `target` (through symlinks) is a FIFO or a device: a stream to write into, never
    a file to rename over (`--force -o /dev/null` as root would otherwise replace the system's
    /dev/null with a regular file)."""
    try:
        mode = os.stat(target).st_mode
    except OSError:
        return False
    return stat.S_ISFIFO(mode) or stat.S_ISCHR(mode) or stat.S_ISBLK(mode)


def _real(target: Path) -> Path:
    """Where the bytes go: through a symlink, to the file it names."""
    return Path(os.path.realpath(target)) if target.is_symlink() else target


def _as_output_error(err: OSError, target: str | os.PathLike) -> OSError:
    """`err` naming the output the user gave rather than a temporary file's name."""
    return OSError(err.errno, err.strerror, str(target))


def _probe(target: Path) -> None:
    """Create and remove a temporary file beside `target`, so that a folder one cannot write
    in (permissions, a read-only disk) stops the run before the work, not after it."""
    try:
        os.unlink(_temporary(_real(target)))
    except OSError as err:
        raise _as_output_error(err, target) from None


def _temporary(target: Path) -> Path:
    """A new empty file beside `target` with its suffix (writers such as matplotlib pick the
    format from it), hidden, with the permissions a new file would get."""
    stem = target.name[:-len(target.suffix)] if target.suffix else target.name
    for _ in range(100):
        tmp = target.with_name(f".{stem}.{secrets.token_hex(4)}.partial{target.suffix}")
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"no free temporary name beside {target}")


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _commit(tmp: Path, target: Path, overwrite: bool) -> None:
    if overwrite:
        if target.exists():
            with suppress(OSError):
                shutil.copymode(target, tmp)
        os.replace(tmp, target)
    else:
        # A hard link fails if the target appeared meanwhile, where a rename would clobber it.
        try:
            os.link(tmp, target)
        except FileExistsError:
            raise OcctrackError("exists already; pass --force to overwrite it",
                                str(target)) from None
        except OSError:
            if target.exists():
                raise OcctrackError("exists already; pass --force to overwrite it",
                                    str(target)) from None
            os.replace(tmp, target)
        else:
            with suppress(OSError):
                os.unlink(tmp)
    with suppress(OSError):
        _fsync(target.parent)


@contextmanager
def atomic_path(path: str | os.PathLike, overwrite: bool = False) -> Iterator[Path]:
    """A temporary file name to write in full; on success it replaces `path`, on any failure
    (including KeyboardInterrupt) it is removed and `path` is left as it was. For writers that
    want a file name (matplotlib); `atomic_write` gives an open file."""
    checked = check_output(path, overwrite)
    if checked is None:
        raise OcctrackError("cannot write this output to standard output; give a file name")
    if is_special(checked):  # a pipe or a device: written into directly, as standard output
        yield checked
        return
    target = _real(checked)
    try:
        tmp = _temporary(target)
    except OSError as err:
        raise _as_output_error(err, path) from None
    try:
        yield tmp
        _fsync(tmp)
        _commit(tmp, target, overwrite)
    except OSError as err:
        with suppress(OSError):
            tmp.unlink()
        if err.filename in (None, str(tmp)):
            raise _as_output_error(err, path) from err
        raise
    except BaseException:
        with suppress(OSError):
            tmp.unlink()
        raise


@contextmanager
def atomic_write(path: str | os.PathLike, overwrite: bool = False, mode: str = "w",
                 encoding: str | None = "utf-8") -> Iterator[IO]:
    """An open file whose content replaces `path` only once the block completes; "-" writes
    to standard output instead."""
    if str(path) == STDOUT:
        stream = sys.stdout.buffer if "b" in mode else sys.stdout
        yield stream
        stream.flush()
        return
    with atomic_path(path, overwrite) as tmp:
        with open(tmp, mode, encoding=None if "b" in mode else encoding) as fh:
            yield fh
