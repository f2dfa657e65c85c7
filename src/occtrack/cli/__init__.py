"""The `occtrack` command: one console script, one module per subcommand.

Each module in COMMANDS defines NAME, HELP (one line), DESCRIPTION (optional),
`configure(parser)` and `run(args) -> int`. Adding a subcommand is adding a module and its name
here; nothing else changes.

Startup stays instant because of two rules. A subcommand module imports at its top only light
modules (the standard library, `occtrack.errors`, `occtrack.cli.arguments`, and text such as
`occtrack.metrics.protocol_text`): never numpy, scipy, matplotlib, TrackEval, motmetrics or the
tracker, which `run(args)` imports when it runs (`occtrack --help` imports every subcommand
module to list them). And `configure(parser)` is called only for the subcommand being run, so
it may import what its options need, though that slows that subcommand's `--help`.
tests/test_cli_errors.py checks both for the commands that exist.

Every failure the user can fix ends in one line on stderr naming the file and what to do, with
the exit status in EXIT_STATUS; `--debug` shows the traceback instead.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import signal
import sys
import warnings
from contextlib import contextmanager

from occtrack import __version__
from occtrack._compat import tomllib
from occtrack.errors import OcctrackError

COMMANDS = (
    "benchmark",
    "bev",
    "calibrate",
    "demo",
    "eval",
    "eval_scans",
    "foursquare",
    "lidar",
    "render",
    "report",
    "reproduce",
    "simulate",
    "simulate_detections",
    "sweep",
    "track",
    "track_scans",
)

BAD_INPUT, USAGE, INTERRUPTED = 1, 2, 130
TERMINATED = 128  # + the signal, as a shell reports it: 143 after SIGTERM, 129 after SIGHUP


class Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP) delivered as an exception, so that every `finally` and
    `except BaseException` on the way out runs: the temporary file of an output being written
    (`occtrack.io.atomic`) is removed, as after Ctrl-C. Left to the default action, SIGTERM
    ends the process at once and leaves that hidden `.partial` file beside the target."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@contextmanager
def _warnings_as_lines(prog: str):
    """The library's warnings ("occtrack: ...", e.g. a gap past max_gap) as one line each on
    stderr, worded as the command's other warnings, not as Python's file:line report."""
    python_format = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        text = str(message)
        if not text.startswith("occtrack: "):
            return python_format(message, category, filename, lineno, file, line)
        print(f"{prog}: warning: {text.removeprefix('occtrack: ')}", file=file or sys.stderr)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = python_format


_MAIN_PID: list[int] = []


def _raise_terminated(signum: int, frame) -> None:
    if os.getpid() not in _MAIN_PID:  # a forked worker (a pool's, Dask's): die as before
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
        return
    raise Terminated(signum)


@contextmanager
def _catch_termination():
    """Turn SIGTERM and SIGHUP into `Terminated` while a command runs, and put the handlers
    back after it (main thread only: signal handlers can only be set there; a caller's own
    handlers are left alone)."""
    import threading

    replaced = {}
    if threading.current_thread() is threading.main_thread():
        _MAIN_PID[:] = [os.getpid()]
        for name in ("SIGTERM", "SIGHUP"):
            sig = getattr(signal, name, None)
            if sig is not None and signal.getsignal(sig) in (signal.SIG_DFL, None):
                replaced[sig] = signal.signal(sig, _raise_terminated)
    try:
        yield
    finally:
        for sig, handler in replaced.items():
            signal.signal(sig, handler)

EXIT_STATUS = f"""\
exit status:
  0    success
  {BAD_INPUT}    bad input or a failure outside occtrack (a malformed or missing
       file, no permission, a full disk, out of memory): one line on stderr
       names the file and what to do
  {USAGE}    usage: an unknown option or a bad option value
  {INTERRUPTED}  interrupted (Ctrl-C)
  {TERMINATED + signal.SIGTERM}  terminated by SIGTERM ({TERMINATED + signal.SIGHUP} by SIGHUP)
Output files are written whole or not at all: a failed or interrupted run leaves
the old file, or none, never a partial one. --debug, given before the
subcommand (occtrack --debug track ...), shows the traceback of a failure."""

_OS_ADVICE = {
    errno.EACCES: "check the permissions of the file and its folder, or use another path",
    errno.EPERM: "check the permissions of the file and its folder, or use another path",
    errno.ENOSPC: "free some space or write to another disk",
    errno.EDQUOT: "free some space or write to another disk",
    errno.EROFS: "write to a writable folder",
    errno.ENOENT: "check the path",
    errno.EISDIR: "give a file, not a folder",
    errno.ENOTDIR: "a part of the path is a file, not a folder; check the path",
    errno.ENAMETOOLONG: "use a shorter path",
    errno.EMFILE: "raise the open-file limit (ulimit -n)",
}


def _command_of(argv: list[str]) -> str | None:
    """The subcommand named in argv: the first word that is not an option (occtrack's own
    options take no value)."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole parser, with the options of `command` only (every subcommand's when
    `command` is "*"), so that `occtrack --help` runs no subcommand's `configure`."""
    parser = argparse.ArgumentParser(
        prog="occtrack",
        description="Occlusion-aware multi-object tracking (measurement-wise and object-wise "
                    "occlusion in a Poisson multi-Bernoulli tracker).",
        epilog=EXIT_STATUS, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"occtrack {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the traceback of a failure instead of a one-line message")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"occtrack.cli.{name}")
        p = sub.add_parser(module.NAME, help=module.HELP,
                           description=getattr(module, "DESCRIPTION", module.HELP),
                           epilog=EXIT_STATUS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        if command in (module.NAME, "*"):
            module.configure(p)
            p.set_defaults(_run=module.run)
    return parser


def _os_message(err: OSError) -> str:
    where = f"{err.filename}: " if err.filename is not None else ""
    what = err.strerror or str(err)
    advice = _OS_ADVICE.get(err.errno)
    return f"{where}{what[:1].lower()}{what[1:]}" + (f"; {advice}" if advice else "")


def explain(err: BaseException, config: str | None = None,
            largest_input: tuple[str, int] | None = None) -> str:
    """One line for a failure: where, what, and what to do. `config` is the settings file
    the run was given, if any, and `largest_input` (path, bytes) its largest input file: the
    likely culprits of running out of memory."""
    if isinstance(err, OcctrackError):
        return str(err)
    if isinstance(err, ImportError):
        from occtrack.extras import explain_missing

        missing = explain_missing(err, "this command")
        if missing is not None:
            return missing
    if isinstance(err, OSError):
        return _os_message(err)
    if isinstance(err, UnicodeDecodeError):
        return (f"an input is not UTF-8 text (byte {err.start}: {err.reason}); save it as "
                f"UTF-8")
    if isinstance(err, tomllib.TOMLDecodeError):
        return f"a settings file is not valid TOML: {err}"
    if isinstance(err, MemoryError):
        causes = []
        if largest_input is not None:
            path, size = largest_input
            causes.append(f"the largest input is {path} ({size / 1e6:.0f} MB): split it")
        if config:
            causes.append(f"lower the sizes set in {config} (capacity, max_labels, particles, "
                          f"...)")
        return "out of memory; " + "; or ".join(causes + ["give the run more memory"])
    return (f"internal error: {type(err).__name__}: {err}; this is a bug in occtrack, please "
            f"report it with the output of the same command run as occtrack --debug ...")


def _largest_input(args: argparse.Namespace) -> tuple[str, int] | None:
    """The largest existing file among the command's arguments (not its outputs), with its
    size: what to name when memory runs out."""
    found = []
    for name, value in vars(args).items():
        if name in ("output", "out", "out_dir", "figure", "animation", "json") or name[0] == "_":
            continue
        for item in value if isinstance(value, list | tuple) else [value]:
            if isinstance(item, str | os.PathLike) and os.path.isfile(item):
                found.append((os.path.getsize(item), str(item)))
    if not found:
        return None
    size, path = max(found)
    return path, size


def _quiet_stdout() -> None:
    """After a closed pipe (occtrack ... | head), send what is left to /dev/null so that
    Python's exit does not complain about the lost output."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


NEGATIVE_VALUED = ("--score-range",)
"""Options whose value may start with a minus sign (`--score-range -10,10`), which argparse
would otherwise read as an option of its own."""


def _join_negative_values(argv: list[str]) -> list[str]:
    """`--score-range -10,10` as `--score-range=-10,10`, so that a value starting with a minus
    sign reaches its option."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] in NEGATIVE_VALUED and arg.startswith("-") and arg[1:2].isdigit():
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = _join_negative_values(sys.argv[1:] if argv is None else list(argv))
    parser = build_parser(_command_of(argv))
    args = parser.parse_args(argv)
    if not hasattr(args, "_run"):
        parser.print_help()
        return USAGE
    prog = f"occtrack {args.command}"
    try:
        with _catch_termination(), _warnings_as_lines(prog):
            return int(args._run(args) or 0)
    except BrokenPipeError:
        _quiet_stdout()
        return 0
    except KeyboardInterrupt as err:
        if args.debug:
            raise
        ended = isinstance(err, Terminated)
        print(f"{prog}: {'terminated (' + str(err) + ')' if ended else 'interrupted'}; output "
              f"files are left as they were", file=sys.stderr)
        return TERMINATED + err.signum if ended else INTERRUPTED
    except Exception as err:
        if args.debug:
            raise
        config = getattr(args, "config", None)
        largest = _largest_input(args) if isinstance(err, MemoryError) else None
        print(f"{prog}: error: {explain(err, config and str(config), largest)}",
              file=sys.stderr)
        return BAD_INPUT
