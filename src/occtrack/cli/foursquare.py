"""`occtrack foursquare`: paper Table I, computed exactly by the discrete engine."""

from __future__ import annotations

import argparse
import math
from fractions import Fraction
from pathlib import Path

from occtrack.errors import OcctrackError

NAME = "foursquare"
HELP = "exact posteriors of the paper's four-square example (Table I)"
DESCRIPTION = """\
Exact posteriors of the four-square example (paper section II, Table I) under no, object-wise
and measurement-wise occlusion, by enumerating every joint configuration with exact fractions.

Outcomes (top measurement, bottom measurement): A (none, none), B (none, left),
C (left, none), D (left, right), E (left, left). Quantities: P(top object exists),
P(top object on left | it exists), P(bottom object on left). With the paper's parameters each
value is printed beside the paper's and differences are marked with '!'.

Probabilities are exact fractions such as 3/5 or decimals such as 0.6; a miss takes the
remainder 1 - p-correct - p-wrong."""


def probability(text: str) -> Fraction:
    """argparse type: an exact probability from '3/5', '0.6' or '1'."""
    try:
        value = Fraction(text.strip())
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a probability (write a fraction like 3/5 or a decimal like 0.6)"
        ) from None
    if not 0 <= value <= 1 or math.isnan(float(value)):
        raise argparse.ArgumentTypeError(f"{text} is outside [0, 1]")
    return value


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--p-correct", type=probability, default=Fraction(1, 2), metavar="P",
                        help="probability that a present object is measured in its own square "
                             "(default 1/2)")
    parser.add_argument("--p-wrong", type=probability, default=Fraction(1, 4), metavar="P",
                        help="probability that it is measured in the other square of its row "
                             "(default 1/4)")
    parser.add_argument("--p-top", type=probability, default=Fraction(1, 2), metavar="P",
                        help="probability that the top object is present (default 1/2)")
    parser.add_argument("--json", action="store_true",
                        help="print {model: {outcome: {quantity: 'fraction'}}}, null where "
                             "the outcome is impossible")
    parser.add_argument("--figure", metavar="PATH.png", type=Path,
                        help="also draw the model and the five outcomes (paper Figure 1)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing figure")


def run(args: argparse.Namespace) -> int:
    from occtrack.experiments.table1 import as_json, format_table
    from occtrack.scenarios.foursquare import FourSquare, table

    try:
        example = FourSquare(args.p_correct, args.p_wrong, args.p_top)
    except ValueError as err:
        raise OcctrackError(str(err)) from None
    result = table(example)
    print(as_json(result) if args.json else format_table(example, result))
    if args.figure is not None:
        from occtrack.viz.foursquare import draw_foursquare

        draw_foursquare(example, args.figure, overwrite=args.force)
    return 0
