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
        module = importlib.import_module(f"occtrack.experiments.{name}")
        p = sub.add_parser(module.NAME, help=module.HELP,
                           description=getattr(module, "DESCRIPTION", module.HELP),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        module.configure(p)
        p.set_defaults(_table_run=module.run)


def run(args: argparse.Namespace) -> int:
    return args._table_run(args)
