"""The `occtrack` command: one console script, one module per subcommand.

Each module in COMMANDS defines NAME, HELP (one line), `configure(parser)` and `run(args) -> int`.
Adding a subcommand is adding a module and its name here; nothing else changes.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from occtrack import __version__
from occtrack.errors import OcctrackError

COMMANDS = (
    "benchmark",
    "demo",
    "eval",
    "foursquare",
    "lidar",
    "reproduce",
    "simulate",
    "simulate_detections",
    "track",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="occtrack",
        description="Occlusion-aware multi-object tracking (measurement-wise and object-wise "
                    "occlusion in a Poisson multi-Bernoulli tracker).",
    )
    parser.add_argument("--version", action="version", version=f"occtrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"occtrack.cli.{name}")
        p = sub.add_parser(module.NAME, help=module.HELP,
                           description=getattr(module, "DESCRIPTION", module.HELP),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        module.configure(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "_run"):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except OcctrackError as err:
        print(f"occtrack {args.command}: error: {err}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
