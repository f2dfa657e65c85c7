"""Paper Table I: exact posteriors of the four-square example under three occlusion models."""

from __future__ import annotations

import argparse
import json
from fractions import Fraction

from occtrack.scenarios.foursquare import OUTCOMES, QUANTITIES, FourSquare, table

NAME = "table1"
HELP = "the four-square example (paper Table I), exact; same as `occtrack foursquare`"

F = Fraction
PAPER = {
    "none": {"top_exists": (F(1, 5), F(1, 5), 1, 1, 1),
             "top_left_given_exists": (F(1, 2), F(1, 2), F(2, 3), F(2, 3), F(2, 3)),
             "bottom_left": (F(1, 2), F(2, 3), F(1, 2), F(1, 3), F(2, 3))},
    "object-wise": {"top_exists": (F(5, 13), F(5, 13), 1, 1, 1),
                    "top_left_given_exists": (F(1, 2), F(3, 5), F(2, 3), F(4, 5), F(1, 2)),
                    "bottom_left": (F(1, 2), F(2, 3), F(1, 3), F(1, 5), F(1, 2))},
    "measurement-wise": {"top_exists": (F(1, 5), F(5, 13), 1, 1, None),
                         "top_left_given_exists": (F(1, 2), F(3, 5), F(2, 3), F(2, 3), None),
                         "bottom_left": (F(1, 2), F(2, 3), F(1, 2), F(1, 3), None)},
}
"""The values printed in the paper (None: '-', impossible), shown beside ours; never used to
compute anything."""

LABELS = {"top_exists": "P(top object exists)",
          "top_left_given_exists": "P(top object on left | exists)",
          "bottom_left": "P(bottom object on left)"}


def paper_value(model: str, outcome: str, quantity: str) -> Fraction | None:
    value = PAPER[model][quantity][list(OUTCOMES).index(outcome)]
    return None if value is None else Fraction(value)


def as_json(result: dict) -> str:
    def cell(q):
        return None if q is None else {k: (None if v is None else str(v)) for k, v in q.items()}
    return json.dumps({m: {o: cell(q) for o, q in row.items()} for m, row in result.items()},
                      indent=2)


def format_table(example: FourSquare, result: dict) -> str:
    """Text table; beside each value the paper's, when the example is the paper's."""
    compare = example == FourSquare()
    lines = [f"Four-square example (paper section II): P(own square) = {example.p_correct}, "
             f"P(other square) = {example.p_wrong}, "
             f"P(miss) = {1 - example.p_correct - example.p_wrong}, "
             f"P(top object present) = {example.p_top}."]
    if compare:
        lines.append("Each cell: exact posterior by enumeration [paper's Table I value]; "
                     "'!' marks a difference, '-' an impossible outcome.")
    else:
        lines.append("Exact posteriors by enumeration ('-': impossible outcome). The paper's "
                     "values are shown only for its own parameters.")
    differences = 0
    width = 14 if compare else 7
    for quantity in QUANTITIES:
        header = f"  {'occlusion':<18}" + "".join(f"{o:<{width}}" for o in OUTCOMES)
        lines += ["", LABELS[quantity], header.rstrip()]
        for model, row in result.items():
            cells = []
            for outcome, values in row.items():
                ours = None if values is None else values[quantity]
                text = "-" if ours is None else str(ours)
                if compare:
                    paper = paper_value(model, outcome, quantity)
                    mark = "" if paper == ours else "!"
                    differences += bool(mark)
                    text = f"{text} [{'-' if paper is None else paper}]{mark}"
                cells.append(f"{text:<{width}}")
            lines.append((f"  {model:<18}" + "".join(cells)).rstrip())
    if compare:
        total = len(QUANTITIES) * len(OUTCOMES) * len(result)
        lines += ["", f"{total - differences} of {total} cells equal the paper's Table I."]
    return "\n".join(lines)


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print the table as JSON")


def run(args: argparse.Namespace) -> int:
    example = FourSquare()
    result = table(example)
    print(as_json(result) if args.json else format_table(example, result))
    return 0
