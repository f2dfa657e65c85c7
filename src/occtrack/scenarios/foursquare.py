"""The four-square example of paper section II, as a model for the exact engine.

Cells: top-left, top-right, bottom-left, bottom-right. The bottom object always exists, left or
right with probability 1/2; the top object exists with probability `p_top`, then left or right
1/2 each. A present object yields a measurement in its own square with probability `p_correct`,
in the other square of its row with `p_wrong`, and none otherwise. No clutter. The bottom row is
nearer the sensor: object-wise, a bottom object hides a top object in its column; measurement-wise,
a bottom measurement hides a top measurement in its column.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from occtrack.exact import OCCLUSIONS, DiscreteModel, ImpossibleObservation, posterior

CELLS = ("top-left", "top-right", "bottom-left", "bottom-right")
TL, TR, BL, BR = range(4)
TOP, BOTTOM = 0, 1

OUTCOMES = {
    "A": (),
    "B": (BL,),
    "C": (TL,),
    "D": (TL, BR),
    "E": (TL, BL),
}
"""Outcome name -> observed cells: (top measurement, bottom measurement), none omitted."""

QUANTITIES = ("top_exists", "top_left_given_exists", "bottom_left")

HALF = Fraction(1, 2)


@dataclass(frozen=True)
class FourSquare:
    p_correct: Fraction = HALF
    p_wrong: Fraction = Fraction(1, 4)
    p_top: Fraction = HALF

    def __post_init__(self) -> None:
        for name in ("p_correct", "p_wrong", "p_top"):
            value = Fraction(getattr(self, name))
            if not 0 <= value <= 1:
                raise ValueError(f"{name} = {value} is outside [0, 1]")
            object.__setattr__(self, name, value)
        if self.p_correct + self.p_wrong > 1:
            raise ValueError(f"p_correct + p_wrong = {self.p_correct + self.p_wrong} exceeds 1 "
                             f"(a miss takes the remainder)")

    def model(self, occlusion: str) -> DiscreteModel:
        c, w = self.p_correct, self.p_wrong
        z = Fraction(0)
        measurement = ((c, w, z, z), (w, c, z, z), (z, z, c, w), (z, z, w, c))
        shadow = tuple(tuple(Fraction(int(occlusion != "none" and (a, b) in ((BL, TL), (BR, TR))))
                             for b in range(4)) for a in range(4))
        return DiscreteModel(cells=CELLS, existence=(self.p_top, Fraction(1)),
                             location=((HALF, HALF, z, z), (z, z, HALF, HALF)),
                             measurement=measurement, occlusion=occlusion, shadow=shadow)


def table(example: FourSquare | None = None) -> dict[str, dict[str, dict | None]]:
    """Table I: occlusion model -> outcome -> quantity -> exact Fraction; an outcome that the
    model deems impossible maps to None."""
    example = example or FourSquare()
    result: dict[str, dict[str, dict | None]] = {}
    for occlusion in OCCLUSIONS:
        model = example.model(occlusion)
        result[occlusion] = {}
        for name, observed in OUTCOMES.items():
            try:
                post = posterior(model, observed)
            except ImpossibleObservation:
                result[occlusion][name] = None
                continue
            top = post.location[TOP]
            result[occlusion][name] = {
                "top_exists": post.existence[TOP],
                "top_left_given_exists": top[TL] if top is not None else None,
                "bottom_left": post.location[BOTTOM][BL],
            }
    return result
