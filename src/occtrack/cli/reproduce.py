"""`occtrack reproduce TABLE`: rerun one of the paper's tables and print ours beside the paper's."""

from __future__ import annotations

import argparse
import importlib

NAME = "reproduce"
HELP = "rerun one of the paper's tables (ours beside the paper's values), or the lidar study"
DESCRIPTION = HELP + ". Each table has its own options: occtrack reproduce TABLE --help."

EXPERIMENTS = (
    "table1",
    "table2",
    "table3",
    "lidar",
)


def configure(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="table", metavar="TABLE", required=True)
    for name in EXPERIMENTS:
        try:
            module = importlib.import_module(f"occtrack.experiments.{name}")
        except ImportError as err:
            # on an install without the extra it needs, the table is listed, and names the
            # extra when asked for (its --help included), instead of a traceback
            from occtrack.extras import explain_missing

            message = explain_missing(err, f"occtrack reproduce {name}")
            if message is None:
                raise
            # (no option prefix: every word after the table, --help included, reaches `rest`)
            p = sub.add_parser(name, help=message, add_help=False, prefix_chars="\0")
            p.add_argument("rest", nargs="*")
            p.set_defaults(_table_run=_missing(message))
            continue
        p = sub.add_parser(module.NAME, help=module.HELP,
                           description=getattr(module, "DESCRIPTION", module.HELP),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        module.configure(p)
        p.set_defaults(_table_run=module.run)


def _missing(message: str):
    """A table's run that only says which extra it needs."""
    def run(args: argparse.Namespace) -> int:
        from occtrack.errors import OcctrackError

        if {"-h", "--help"} & set(args.rest):
            print(message)
            return 0
        raise OcctrackError(message)
    return run


def run(args: argparse.Namespace) -> int:
    return args._table_run(args)
