"""Two-state Markov features carried as probabilities: detectability and occludability.

A feature is on or off and switches at random; each Gaussian component carries the
probability p that it is on. The chain is set by its stationary probability s and its
half-second ratio h, the fraction of a departure from s that is forgotten in half a second:

    p <- s + lambda (p - s),    lambda = (1 - h) ** (dt / 0.5)

(paper section VI; the authors' prototype used detectability s = 0.9 or 0.93, h = 0.99 and
occludability s = 0.8, h = 0.8).

Detectability D: a component with D on yields a measurement unless occluded, so P_D = p.
Occludability O: only a measurement from an object with O on can be occluded; an object that
stays undetected where nothing could hide it loses occludability, one that is missed where it
could be hidden gains it, and one detected where the other detections would have hidden it
loses it, which keeps the order of occlusion stable.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TwoStateMarkov:
    stationary: float
    half_second_ratio: float

    def __post_init__(self) -> None:
        if not 0.0 <= self.stationary <= 1.0:
            raise ValueError(f"stationary probability {self.stationary} is outside [0, 1]")
        if not 0.0 <= self.half_second_ratio <= 1.0:
            raise ValueError(f"half-second ratio {self.half_second_ratio} is outside [0, 1]")

    def memory(self, dt: float) -> float:
        """lambda: the fraction of a departure from the stationary value kept after dt."""
        return (1.0 - self.half_second_ratio) ** (dt / 0.5)

    def predict(self, p, dt: float):
        return self.stationary + self.memory(dt) * (p - self.stationary)
