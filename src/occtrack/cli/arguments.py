"""The argparse types live in the schema on the bottom floor, `occtrack.config.arguments`;
the option groups that several subcommands share live here."""

import argparse

from occtrack.config.arguments import (
    DAY_AT_30_FPS,
    frame_rate,
    positive_float,
    positive_int,
    seconds,
    seed_int,
    whole_number,
)

__all__ = ["DAY_AT_30_FPS", "add_engine_options", "frame_rate", "positive_float", "positive_int",
           "seconds", "seed_int", "whole_number"]


def add_engine_options(parser: argparse.ArgumentParser, sequential_help: str) -> None:
    """--workers / --scheduler / --sequential: where the tasks of a Dask-run command go."""
    engine = parser.add_mutually_exclusive_group()
    engine.add_argument("--workers", type=positive_int, metavar="N",
                        help="worker processes of the LocalCluster (default: one per core)")
    engine.add_argument("--scheduler", metavar="ADDRESS",
                        help="a running Dask scheduler, e.g. tcp://127.0.0.1:8786")
    engine.add_argument("--sequential", action="store_true", help=sequential_help)


def existing_file(path: str, expected: str) -> None:
    """Refuse, naming `path`, an input that is missing or a folder, before anything is looked
    up beside it (a missing detection file is "no such file", not "image size unknown")."""
    import os

    from occtrack.errors import OcctrackError

    if not os.path.exists(path):
        raise OcctrackError("no such file", path)
    if os.path.isdir(path):
        raise OcctrackError(f"is a directory, expected {expected}", path)
