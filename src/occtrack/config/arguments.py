"""argparse types shared by the subcommands and the experiments' parsers, so every command words
its errors the same way (floor 1: the command line's numbers are settings too)."""

from __future__ import annotations

import argparse
from collections.abc import Callable


def whole_number(minimum: int) -> Callable[[str], int]:
    """An argparse type: an integer no smaller than `minimum`."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{text} must be at least {minimum}")
        return value

    parse.__name__ = "whole number"
    return parse


def positive_float(text: str) -> float:
    """An argparse type: a finite number above zero."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text} must be a finite number above 0")
    return value


positive_float.__name__ = "positive number"


def seconds(text: str) -> float:
    """An argparse type: a finite number of seconds, 0 or more."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value >= 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text} must be a finite number of seconds, 0 or more")
    return value


seconds.__name__ = "seconds"


def frame_rate(text: str) -> float:
    """An argparse type: a frame rate a camera can have (`occtrack.config`'s MIN_FPS to
    MAX_FPS), so that --fps 20000 is a bad option value, as --fps 0 is."""
    from occtrack.config import MAX_FPS, MIN_FPS

    value = positive_float(text)
    if not MIN_FPS <= value <= MAX_FPS:
        raise argparse.ArgumentTypeError(f"{text} must be between {MIN_FPS:g} and {MAX_FPS:g} "
                                          f"frames a second")
    return value


frame_rate.__name__ = "frame rate"

DAY_AT_30_FPS = 24 * 3600 * 30
"""Default bound on a run of empty frames: a day of video at the usual MOTChallenge rate."""

positive_int = whole_number(1)
seed_int = whole_number(0)
