"""Scoring the highway trackers: GOSPA per step (paper appendix, Table III).

GOSPA with c = 5 m, p = 1, alpha = 2 (`occtrack.metrics.gospa`); the base distance between a
true car and an estimate is sqrt(dposition^2 + dlength^2) in the same lane and infinite across
lanes, the position being the car's front end (as in the authors' scoring). The paper's figure
is GOSPA averaged over time steps; the same total divided by the number of true cars summed
over steps (GOSPA per true object) is reported beside it, with the localisation / missed /
false split (each a per-step mean, adding up to the total).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.metrics.gospa import Gospa, gospa_from_distances

C = 5.0
P = 1.0


def distances(truth_lane, truth_front, truth_length, est_lane, est_front,
              est_length) -> np.ndarray:
    """(n_true, n_estimated) base distances: Euclidean in (front, length), inf across lanes."""
    d = np.hypot(np.subtract.outer(truth_front, est_front),
                 np.subtract.outer(truth_length, est_length))
    return np.where(np.equal.outer(truth_lane, est_lane), d, np.inf)


def step_gospa(cars, estimates, c: float = C, p: float = P) -> Gospa:
    """GOSPA of one step between the true Cars and the tracker's Estimates."""
    d = distances(cars.lane, cars.front, cars.length, estimates.lane, estimates.front,
                  estimates.length)
    return gospa_from_distances(d, c, p)


@dataclass(frozen=True)
class HighwayScore:
    """per_step: mean GOSPA per time step (the paper's figure); per_object: total GOSPA over
    the number of true cars summed over steps; localisation / missed / false: per-step means
    of the split; steps and car_steps: the counts behind them; tracks: tracks ever reported
    (when known)."""

    per_step: float
    per_object: float
    localisation: float
    missed: float
    false: float
    steps: int
    car_steps: int
    n_missed: int
    n_false: int
    tracks: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


class ScoreAccumulator:
    """Sums GOSPA over steps (p = 1, so totals add)."""

    def __init__(self, c: float = C, p: float = P):
        self.c, self.p = c, p
        self.steps = self.car_steps = self.n_missed = self.n_false = 0
        self.total = self.localisation = self.missed = self.false = 0.0

    def add(self, cars, estimates) -> Gospa:
        g = step_gospa(cars, estimates, self.c, self.p)
        self.steps += 1
        self.car_steps += len(cars)
        self.total += g.total
        self.localisation += g.localisation
        self.missed += g.missed
        self.false += g.false
        self.n_missed += g.n_missed
        self.n_false += g.n_false
        return g

    def result(self) -> HighwayScore:
        s = max(self.steps, 1)
        return HighwayScore(self.total / s, self.total / max(self.car_steps, 1),
                            self.localisation / s, self.missed / s, self.false / s,
                            self.steps, self.car_steps, self.n_missed, self.n_false)
