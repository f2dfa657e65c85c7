"""Exact posteriors for small discrete multi-object problems, by enumeration with Fractions.

The reference that every approximate filter in occtrack is tested against. Objects are
Bernoulli over a finite set of cells: object i exists with probability r_i and then sits in cell
c with probability p_i(c). A present, visible object yields one measurement in cell z with
probability `measurement[c][z]` and none with the remainder (1 - P_D). Clutter is Poisson with
rate `clutter[z]` per cell (kappa p_F).

Occlusion is an operator on a random set (paper section IV), given by a shadow matrix S:
S[a][b] is the probability that an item in cell a hides an item in cell b. Occlusion is
*restricted*: only visible items hide others. Items are processed nearest first (S must be
acyclic); an item is visible with probability prod over the visible items a before it of
(1 - S[a][b]).

- object-wise: the items are objects; a hidden object yields no measurement.
- measurement-wise: every object first yields its measurement; the items are measurements
  (objects' and clutter), and only the visible ones are observed.

`posterior` enumerates every joint configuration (presence and cell of each object, each
object's generated measurement, which items are hidden) and returns exact marginals. Hidden
clutter and e^(-kappa) only multiply every configuration by the same constant, so they cancel;
so does the visible set's own survival term under measurement-wise occlusion, but it is kept
because it is what makes an outcome impossible (paper outcome E).
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from math import factorial, prod

Matrix = tuple[tuple[Fraction, ...], ...]

OCCLUSIONS = ("none", "object-wise", "measurement-wise")


class ImpossibleObservation(ValueError):
    """The observed measurements have probability zero under the model."""


@dataclass(frozen=True)
class DiscreteModel:
    """A discrete multi-object model. Indices are cells 0..n-1; `cells` names them."""

    cells: tuple[str, ...]
    existence: tuple[Fraction, ...]
    location: Matrix
    measurement: Matrix
    clutter: tuple[Fraction, ...] = ()
    occlusion: str = "none"
    shadow: Matrix = ()
    depth: tuple[int, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = len(self.cells)
        as_frac = _fractions
        object.__setattr__(self, "existence", as_frac(self.existence))
        object.__setattr__(self, "location", tuple(as_frac(row) for row in self.location))
        object.__setattr__(self, "measurement", tuple(as_frac(row) for row in self.measurement))
        object.__setattr__(self, "clutter", as_frac(self.clutter or (0,) * n))
        object.__setattr__(self, "shadow", tuple(as_frac(row) for row in self.shadow)
                           or tuple((Fraction(0),) * n for _ in range(n)))
        if self.occlusion not in OCCLUSIONS:
            raise ValueError(f"occlusion must be one of {OCCLUSIONS}, not {self.occlusion!r}")
        if len(self.location) != len(self.existence):
            raise ValueError("need one location row per object")
        for name, rows in (("location", self.location), ("measurement", self.measurement),
                           ("shadow", self.shadow)):
            if any(len(row) != n for row in rows):
                raise ValueError(f"every {name} row needs one entry per cell ({n})")
        if len(self.measurement) != n or len(self.shadow) != n:
            raise ValueError("measurement and shadow are cell x cell matrices")
        if len(self.clutter) != n:
            raise ValueError("clutter needs one rate per cell")
        for r in self.existence:
            _check_probability(r, "existence")
        for row in self.location:
            if sum(row) != 1 or any(p < 0 for p in row):
                raise ValueError(f"a location row must be a distribution, got {_show(row)}")
        for row in self.measurement:
            if any(p < 0 for p in row) or sum(row) > 1:
                raise ValueError(f"a measurement row must be non-negative and sum to at most 1 "
                                 f"(the rest is a miss), got {_show(row)}")
        if any(k < 0 for k in self.clutter):
            raise ValueError("clutter rates must be non-negative")
        for row in self.shadow:
            for s in row:
                _check_probability(s, "shadow")
        object.__setattr__(self, "depth", _depth_order(self.shadow))


@dataclass(frozen=True)
class Posterior:
    """existence[i] = P(object i exists | Z); location[i][c] = P(object i in cell c | it
    exists, Z), None where the object surely does not exist; evidence = P(Z) up to the
    constant factors every configuration shares."""

    existence: tuple[Fraction, ...]
    location: tuple[tuple[Fraction, ...] | None, ...]
    evidence: Fraction


def posterior(model: DiscreteModel, observed: Sequence[int]) -> Posterior:
    """Exact posterior marginals of every object given the cells of the observed measurements
    (a multiset: repeat a cell for several measurements in it)."""
    n_cells = len(model.cells)
    for z in observed:
        if not 0 <= z < n_cells:
            raise ValueError(f"observed cell {z} is not one of 0..{n_cells - 1}")
    seen = Counter(observed)
    n_obj = len(model.existence)
    joint_exists = [Fraction(0)] * n_obj
    joint_cell = [[Fraction(0)] * n_cells for _ in range(n_obj)]
    total = Fraction(0)
    for config, prior in _object_configurations(model):
        weight = prior * _likelihood(model, config, seen)
        if weight == 0:
            continue
        total += weight
        for i, cell in enumerate(config):
            if cell is not None:
                joint_exists[i] += weight
                joint_cell[i][cell] += weight
    if total == 0:
        names = ", ".join(model.cells[z] for z in observed) or "no measurement"
        raise ImpossibleObservation(
            f"observing [{names}] has probability 0 under {model.occlusion} occlusion")
    existence = tuple(e / total for e in joint_exists)
    location = tuple(tuple(c / e for c in row) if e else None
                     for row, e in zip(joint_cell, joint_exists, strict=True))
    return Posterior(existence, location, total)


def _object_configurations(model: DiscreteModel):
    """Every assignment of each object to absent (None) or a cell, with its prior."""
    choices = []
    for r, row in zip(model.existence, model.location, strict=True):
        options = [(None, 1 - r)] + [(c, r * p) for c, p in enumerate(row) if p and r]
        choices.append([o for o in options if o[1]])
    for combo in itertools.product(*choices):
        yield tuple(c for c, _ in combo), prod((p for _, p in combo), start=Fraction(1))


def _generated(model: DiscreteModel, cell: int):
    """(measurement cell or None, probability) for one object in `cell`."""
    row = model.measurement[cell]
    miss = 1 - sum(row)
    out = [(None, miss)] if miss else []
    return out + [(z, p) for z, p in enumerate(row) if p]


def _likelihood(model: DiscreteModel, config: tuple[int | None, ...], seen: Counter) -> Fraction:
    present = [c for c in config if c is not None]
    if model.occlusion == "object-wise":
        total = Fraction(0)
        for visible, p_vis in _visibility_patterns(model, present):
            emitters = [c for c, v in zip(present, visible, strict=True) if v]
            total += p_vis * _standard_likelihood(model, emitters, seen)
        return total
    if model.occlusion == "measurement-wise":
        return _measurementwise_likelihood(model, present, seen)
    return _standard_likelihood(model, present, seen)


def _standard_likelihood(model: DiscreteModel, emitters: list[int], seen: Counter) -> Fraction:
    """P(observed multiset | objects in `emitters` each yield at most one measurement)."""
    total = Fraction(0)
    for outcome in itertools.product(*(_generated(model, c) for c in emitters)):
        made = Counter(z for z, _ in outcome if z is not None)
        if made - seen:
            continue
        total += prod((p for _, p in outcome), start=Fraction(1)) * \
            _clutter_weight(model, seen - made)
    return total


def _measurementwise_likelihood(model: DiscreteModel, present: list[int],
                                seen: Counter) -> Fraction:
    """Every object yields its measurement; then measurements hide measurements. Visible
    clutter is whatever of the observation the objects' visible measurements do not explain."""
    total = Fraction(0)
    observed_items = sorted(seen.elements())
    for outcome in itertools.product(*(_generated(model, c) for c in present)):
        p_gen = prod((p for _, p in outcome), start=Fraction(1))
        made = [z for z, _ in outcome if z is not None]
        for keep in itertools.product((True, False), repeat=len(made)):
            shown = Counter(z for z, k in zip(made, keep, strict=True) if k)
            if shown - seen:
                continue
            hidden = [z for z, k in zip(made, keep, strict=True) if not k]
            items = observed_items + hidden
            visible = [True] * len(observed_items) + [False] * len(hidden)
            p_occ = _pattern_probability(model, items, visible)
            if p_occ:
                total += p_gen * p_occ * _clutter_weight(model, seen - shown)
    return total


def _visibility_patterns(model: DiscreteModel, cells: list[int]):
    """Every visible/hidden pattern of items in `cells`, with its probability."""
    for visible in itertools.product((True, False), repeat=len(cells)):
        p = _pattern_probability(model, cells, list(visible))
        if p:
            yield visible, p


def _pattern_probability(model: DiscreteModel, cells: list[int], visible: list[bool]) -> Fraction:
    """Probability of one visible/hidden pattern, processing items nearest first: an item is
    visible with probability prod over earlier visible items a of (1 - S[a][b])."""
    order = sorted(range(len(cells)), key=lambda k: model.depth[cells[k]])
    p = Fraction(1)
    shown: list[int] = []
    for k in order:
        b = cells[k]
        p_vis = prod((1 - model.shadow[a][b] for a in shown), start=Fraction(1))
        if visible[k]:
            p *= p_vis
            shown.append(b)
        else:
            p *= 1 - p_vis
        if p == 0:
            return p
    return p


def _clutter_weight(model: DiscreteModel, counts: Counter) -> Fraction:
    """Poisson multiset probability of the clutter, without the shared factor e^(-kappa)."""
    w = Fraction(1)
    for z, n in counts.items():
        w *= model.clutter[z] ** n / factorial(n)
    return w


def _depth_order(shadow: Matrix) -> tuple[int, ...]:
    """Rank of each cell in a nearest-first order; refuses a cyclic shadow relation."""
    n = len(shadow)
    rank = [-1] * n
    remaining = set(range(n))
    level = 0
    while remaining:
        front = [b for b in remaining
                 if not any(shadow[a][b] for a in remaining if a != b)]
        if not front or any(shadow[b][b] for b in front):
            raise ValueError("the shadow relation must be acyclic (no cell may hide itself "
                             "or, through others, a cell that hides it)")
        for b in front:
            rank[b] = level
            remaining.discard(b)
        level += 1
    return tuple(rank)


def _fractions(values) -> tuple[Fraction, ...]:
    return tuple(Fraction(v) for v in values)


def _check_probability(p: Fraction, what: str) -> None:
    if not 0 <= p <= 1:
        raise ValueError(f"{what} probability {p} is outside [0, 1]")


def _show(row) -> str:
    return "[" + ", ".join(str(p) for p in row) + "]"
