"""People from legs: a laser at leg height sees a person as two small segments, one when the
legs cross or stand together (issue 41, item 2). The scan tracker's filter tracks each leg as a
disc (its beam likelihood fits a leg's returns beam for beam); this module pairs the leg
tracks into people and reports each person at the midpoint of its legs, under one identity
that outlives the legs' own (a leg track that breaks, or a leg hidden behind the other, does
not end the person).

The rules, per scan, in this order (leg_tracker's "joint leg" pairing made deterministic;
Leigh et al., ICRA 2015):

1. A person keeps each of its legs that is still tracked and lies within `separation` m of
   its first (legs that drift further apart part: the far one is free again).
2. Free legs join people who lack a leg: a person with one leg takes the nearest free leg
   within `separation` of it; a person with none, the nearest within `gate` m of where it
   was last seen (not carried on by its velocity: a leg's velocity, swing or stance, says
   little of its person's) (least total distance, scipy's Hungarian).
3. Free legs left over pair with each other, the closest pair within `separation` first;
   a leg with no partner is a person of one leg.
4. A person with no leg for more than `hold` seconds is gone.
5. People closer than half a stride (`separation` / 2) are one person, the elder, who takes
   the younger's legs (a leg the filter tracks twice, a person's legs first seen apart).

Legs not yet confirmed by the filter (tentative: a leg whose track broke on a scan that saw
it in pieces and began again) take part in rules 1 and 2 only: they keep or re-find a person,
never start one, and never count towards a pair.

Reported: every person with a leg that has once had two confirmed ones, or one confirmed
whose segment was wider than a leg can look (two legs side by side: a leg shows at most its
diameter, `2 leg_radius`, to the scanner; up to twice that) (`pairs_only`: a lone leg-sized
segment, a post, a bush, is not somebody until a second leg joins it) and has held
a confirmed leg within the last `hold` seconds; position the midpoint
of its two legs furthest apart (a leg tracked twice does not pull it), velocity the mean of its
legs', and existence and confidence those of its likeliest leg (the probability that
someone is there is at least that of its surest leg; the two legs of one person are not
independent evidence of two people, so they are not combined as if they were).

Written by hand: no library pairs a tracker's leg tracks into people; the few lines of
assignment use scipy's `linear_sum_assignment` and its k-d tree for the legs within a stride.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

FAR = 1e9  # a cost no assignment takes


@dataclass(frozen=True)
class People:
    """The people reported after one scan, n of them, sorted by id: ids (n,), positions and
    velocities (n, 2) (m, m/s), existence and confidence (n,), legs (n, 2) the ids of the two
    leg tracks its position is the midpoint of (-1: none), occluded (n,) (every leg of theirs
    missed and more likely hidden)."""

    ids: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    legs: np.ndarray
    occluded: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)

    def select(self, keep: np.ndarray) -> People:
        return People(self.ids[keep], self.positions[keep], self.velocities[keep],
                      self.existence[keep], self.confidence[keep], self.legs[keep],
                      self.occluded[keep])


@dataclass
class _Person:
    legs: list[int]
    position: np.ndarray
    velocity: np.ndarray
    seen: float  # time its last leg was tracked
    paired: bool = False  # ever seen on two legs
    sure: float = -math.inf  # time it last held a confirmed leg


def _outer(legs: np.ndarray) -> list[int]:
    """The indices of the two legs (L, 2) furthest apart (all of them when two or one)."""
    if len(legs) <= 2:
        return list(range(len(legs)))
    d = np.sum((legs[:, None, :] - legs[None, :, :]) ** 2, axis=-1)
    return sorted(int(i) for i in np.unravel_index(np.argmax(d), d.shape))


def _midpoint(legs: np.ndarray) -> np.ndarray:
    """The midpoint of the two legs furthest apart (a leg tracked twice does not pull it)."""
    return legs[_outer(legs)].mean(axis=0)


def _assign(cost: np.ndarray) -> list[tuple[int, int]]:
    """Least-total-cost pairs (row, column) of a cost matrix, pairs at FAR left out."""
    if cost.size == 0:
        return []
    rows, cols = linear_sum_assignment(cost)
    return [(int(r), int(c)) for r, c in zip(rows, cols, strict=True) if cost[r, c] < FAR]


class LegPairing:
    """Pairs leg tracks into people, scan by scan (see the module).

    Args:
        separation: the widest stride, m: two legs further apart are not one person's.
        gate: how far, m, from where it was last seen a person who lost both legs may be
            found again by a new leg.
        hold: seconds a person without a leg is kept for a new leg to take up.
        pairs_only: report a person only once it has been seen on two legs (a lone
            leg-sized segment, a post or a bush, is not somebody until a second leg joins).
    """

    def __init__(self, separation: float = 0.8, gate: float = 0.5, hold: float = 1.0,
                 pairs_only: bool = True):
        for name, value in (("separation", separation), ("gate", gate), ("hold", hold)):
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a non-negative number, not {value}")
        self.separation, self.gate, self.hold = float(separation), float(gate), float(hold)
        self.pairs_only = bool(pairs_only)
        self.reset()

    def reset(self) -> None:
        self._people: dict[int, _Person] = {}
        self._next = 1

    def update(self, time: float, ids: np.ndarray, positions: np.ndarray,
               velocities: np.ndarray, existence: np.ndarray, confidence: np.ndarray,
               occluded: np.ndarray | None = None,
               tentative: np.ndarray | None = None, wide: np.ndarray | None = None) -> People:
        """One scan's leg tracks (ids (L,), positions and velocities (L, 2), existence and
        confidence (L,), occluded (L,), tentative (L,): not yet confirmed, such a leg may keep
        or join a person but never starts one; wide (L,): its segment this scan was wider than
        one leg can look, two legs together) in; the people out."""
        ids = np.asarray(ids, dtype=np.int64)
        tentative = (np.zeros(len(ids), bool) if tentative is None
                     else np.asarray(tentative, bool).reshape(-1))
        wide = (np.zeros(len(ids), bool) if wide is None
                else np.asarray(wide, bool).reshape(-1))
        positions = np.asarray(positions, dtype=float).reshape(-1, 2)
        velocities = np.asarray(velocities, dtype=float).reshape(-1, 2)
        row = {int(i): k for k, i in enumerate(ids)}
        sep2 = self.separation ** 2
        # 1. legs still tracked and still with the person's first
        for person in self._people.values():
            person.legs = [leg for leg in person.legs if leg in row]
            if len(person.legs) > 1:
                anchor = positions[row[person.legs[0]]]
                person.legs = person.legs[:1] + [
                    leg for leg in person.legs[1:]
                    if np.sum((positions[row[leg]] - anchor) ** 2) <= sep2]
        for key in [key for key, p in self._people.items()  # 4. (before any takes a leg)
                    if not p.legs and time - p.seen > self.hold]:
            del self._people[key]
        taken = {leg for person in self._people.values() for leg in person.legs}
        free = [k for k, i in enumerate(ids) if int(i) not in taken]
        # 2. free legs to people who lack one
        wanting = [key for key, p in self._people.items() if len(p.legs) < 2]
        if free and wanting:
            cost = np.full((len(wanting), len(free)), FAR)
            for r, key in enumerate(wanting):
                person = self._people[key]
                if person.legs:
                    anchor, reach = positions[row[person.legs[0]]], self.separation
                else:  # where it was last seen (a leg's velocity, swing or stance, says
                    # little of the person's)
                    anchor, reach = person.position, self.gate
                d = np.hypot(*(positions[free] - anchor).T)
                cost[r] = np.where(d <= reach, d, FAR)
            for r, c in _assign(cost):
                self._people[wanting[r]].legs.append(int(ids[free[c]]))
            taken = {leg for person in self._people.values() for leg in person.legs}
            free = [k for k in free if int(ids[k]) not in taken]
        # 3. the rest pair with each other, or stand alone (a tentative leg is nobody yet)
        free = [k for k in free if not tentative[k]]
        if len(free) > 1:  # (the pairs within a stride, from a k-d tree: no all-pairs table)
            p = positions[free]
            close = cKDTree(p).query_pairs(self.separation, output_type="ndarray")
            close = close[np.lexsort((close[:, 1], close[:, 0]))]  # (a fixed order)
            d = np.hypot(*(p[close[:, 0]] - p[close[:, 1]]).T)
            paired: set[int] = set()
            for a, b in close[np.argsort(d, kind="stable")].tolist():
                if a in paired or b in paired:
                    continue
                paired.update((a, b))
                self._new([int(ids[free[a]]), int(ids[free[b]])], time)
            free = [k for n, k in enumerate(free) if n not in paired]
        for k in free:
            self._new([int(ids[k])], time)
        # 5. people closer than half a stride are one, the elder (until none are)
        half2 = sep2 / 4
        merged = True
        while merged:
            merged = False
            kept: list[int] = []
            for key in sorted(self._people):
                person = self._people[key]
                if not person.legs:
                    continue
                person.position = _midpoint(positions[[row[leg] for leg in person.legs]])
                elder = next((k for k in kept if np.sum(
                    (self._people[k].position - person.position) ** 2) < half2), None)
                if elder is None:
                    kept.append(key)
                    continue
                self._people[elder].legs += person.legs
                del self._people[key]
                merged = True
                break
        out = []
        for key in kept:
            person = self._people[key]
            rows = [row[leg] for leg in person.legs]
            person.velocity = velocities[rows].mean(axis=0)
            person.seen = time
            sure = ~tentative[rows]
            person.paired |= int(np.count_nonzero(sure)) > 1 or bool((sure & wide[rows]).any())
            if not tentative[rows].all():
                person.sure = time
            if (person.paired or not self.pairs_only) and time - person.sure <= self.hold:
                out.append((key, rows))
        return self._report(out, positions, velocities, np.asarray(existence, float),
                            np.asarray(confidence, float),
                            None if occluded is None else np.asarray(occluded, bool), ids)

    @property
    def members(self) -> dict[int, tuple[int, ...]]:
        """Every person kept (reported or held) and the leg track ids it holds now."""
        return {key: tuple(p.legs) for key, p in sorted(self._people.items())}

    def kept_positions(self) -> np.ndarray:
        """Where each person kept (reported or held) was last seen (n, 2), m."""
        if not self._people:
            return np.zeros((0, 2))
        return np.array([p.position for _, p in sorted(self._people.items())], float)

    def _new(self, legs: list[int], time: float) -> None:
        self._people[self._next] = _Person(legs, np.zeros(2), np.zeros(2), time)
        self._next += 1

    def _report(self, out, positions, velocities, existence, confidence, occluded,
                ids) -> People:
        n = len(out)
        legs = np.full((n, 2), -1, dtype=np.int64)
        exist, conf, hidden = np.zeros(n), np.zeros(n), np.zeros(n, dtype=bool)
        pos, vel = np.zeros((n, 2)), np.zeros((n, 2))
        for i, (_, rows) in enumerate(out):
            rows = np.asarray(rows)
            outer = rows[_outer(positions[rows])]
            legs[i, :len(outer)] = ids[outer]
            best = rows[np.argmax(existence[rows])]
            exist[i], conf[i] = existence[best], confidence[rows].max()
            hidden[i] = occluded is not None and bool(occluded[rows].all())
            pos[i], vel[i] = positions[outer].mean(axis=0), velocities[rows].mean(axis=0)
        return People(np.array([key for key, _ in out], dtype=np.int64), pos, vel, exist,
                      conf, legs, hidden)
