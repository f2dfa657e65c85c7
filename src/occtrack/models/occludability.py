"""How often the detector still finds an object the occlusion model calls hidden: learnt while
tracking.

The filter's occludability o_k is a two-state Markov feature (`occtrack.models.markov`)
relaxing to one stationary value o: the share of an object's measurements that another object
(or measurement) can hide. With the occlusion model's visibility v_k and hidden share q_k, an
object is detected with probability

    P(hit) = d (1 - o + o v (1 - q)) = d (1 - o u),    u = 1 - v (1 - q),

d its detectability and u how hidden the model says it is (object-wise: q = 0, u = 1 - v;
measurement-wise: v = 1, u = q). The o of the prototype, 0.8, was calibrated with a detector
that misses hidden people: against MOT17's labels, 1 - P(hit | under a fifth visible) /
P(hit | visible) is .95 to 1.00 for FRCNN. A detector trained on amodal boxes does not miss
them: YOLOX-X, trained on MOT17's labels, boxes people hidden behind others (at low scores),
and the same ratio gives .11 to .24 (`benchmarks/learnt_models.py`). An occlusion model that
calls their misses likely keeps tracks alive that the detector itself has let go. So o is
learnt from the tracker's own confirmed objects, by least squares on 1 - hit / d = o u:

    o = (A + n0 o0) / (B + n0),    A = sum w u (1 - h / d),    B = sum w u^2,

h whether the object took a detection this frame, w its existence, the sums discounted with
`memory` seconds, n0 = `prior_weight` pseudo-objects at the prior o0 (clipped to [0, 1]).
Only the objects the model calls mostly hidden (u >= `hidden`, 0.8) count: a detector's
response to partial occlusion is a step, not the model's line (FRCNN finds people more than
half visible nearly always), and the partly hidden objects would pull o down where o matters
least; o is the probability that a hidden object's measurement is lost, and the hidden
objects measure it.

Hand-written: a weighted least-squares count on the filter's own objects; no library learns a
filter's occlusion model from its association.
"""

from __future__ import annotations

import math

import numpy as np


class OccludabilityLearner:
    """The learnt stationary occludability o (see the module)."""

    def __init__(self, prior: float, prior_weight: float = 20.0, memory: float = 60.0,
                 hidden: float = 0.8):
        if not 0.0 <= prior <= 1.0:
            raise ValueError(f"prior occludability must be in [0, 1], not {prior}")
        if not prior_weight > 0 or not memory > 0:
            raise ValueError("prior_weight and memory must be positive")
        if not 0.0 < hidden <= 1.0:
            raise ValueError(f"hidden must be in (0, 1], not {hidden}")
        self.prior, self.prior_weight = float(prior), float(prior_weight)
        self.memory, self.hidden = float(memory), float(hidden)
        self.evidence = 0.0  # A: discounted sum of w u (1 - h / d)
        self.weight = 0.0  # B: discounted sum of w u^2

    def update(self, existence: np.ndarray, hidden: np.ndarray, took: np.ndarray,
               detectability: float, dt: float) -> None:
        """One frame: for each confirmed object its existence w, how hidden the occlusion model
        says it is (u in [0, 1]) and whether it took a detection; `detectability` d."""
        w = np.asarray(existence, dtype=float)
        u = np.asarray(hidden, dtype=float)
        h = np.asarray(took, dtype=float)
        m = u >= self.hidden
        if not detectability > 0:  # (a detector that never detects says nothing of hiding)
            m[:] = False
        self.add(float(np.sum(w[m] * u[m] * (1.0 - h[m] / max(detectability, 1e-300)))),
                 float(np.sum(w[m] * u[m] ** 2)), dt)

    def add(self, evidence: float, weight: float, dt: float) -> None:
        """One frame's sums A and B (`update` without the arrays: the filter computes them
        in one compiled pass, `filters.gmpmb.weights._hidden_evidence`)."""
        keep = math.exp(-dt / self.memory)
        self.evidence = keep * self.evidence + evidence
        self.weight = keep * self.weight + weight

    @property
    def value(self) -> float:
        """o: the prior, moved by the hidden objects' hits and misses."""
        o = (self.evidence + self.prior_weight * self.prior) / (self.weight + self.prior_weight)
        return min(1.0, max(0.0, o))
