"""The occlusion interface shared by every tracker in occtrack.

Occlusion changes only each component's detection and miss terms (paper section IV):

    hit   l_kj = w_k P_D(x_k) v_k (1 - h_j) p(z_j | x_k)
    miss  m_k  = w_k (1 - P_D(x_k) v_k + P_D(x_k) v_k q_k)

v_k is the probability that component k's object is visible (object-wise occlusion, static
approximation: P_D(x) <- P_D(x) P(v | x), paper eq. "misstermOWO") and q_k the probability that
its would-be measurement is hidden by the measurements that were seen (measurement-wise
occlusion: the integral of p(z | x_k) p(not v | z, Z^V), paper eq. "new_individual_MM"); h_j,
optional, is the probability that the other visible measurements would hide a measurement at
z_j (measurement-wise; it matters only for sources that may or may not be occludable, see
`occtrack.filters.gmpmb`). `none` returns v = 1, q = 0; object-wise returns q = 0; measurement-
wise returns v = 1. (With an occludability o_k, the filter applies v, q and h to the occludable
part only.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np


@dataclass(frozen=True)
class OcclusionContext:
    """What an occlusion model may look at when it sets each component's terms.

    means / covs: predicted component states (covs None for particles); weights: each
    component's weight within its object; owner: the object index of each component (-1 for the
    Poisson part); existence: r of each object; measurements: this step's visible measurements;
    measurement_model: the model that maps states to measurements; gating: whether a model may
    look only at pairs that can interact (True), or must build full tables (for checking).
    """

    means: np.ndarray
    covs: np.ndarray | None
    weights: np.ndarray
    owner: np.ndarray
    existence: np.ndarray
    measurements: np.ndarray
    measurement_model: Any = None
    gating: bool = True


@dataclass(frozen=True)
class OcclusionTerms:
    """visible[k] = v_k and hidden[k] = q_k, both in [0, 1], one per component.

    seen_hidden[j] = h_j, optional, one per visible measurement: the probability that an
    occludable measurement where z_j is would have been hidden by the other visible
    measurements (measurement-wise occlusion). z_j was seen, so its source was either not
    occludable or escaped: with occludability o_k the hit term carries 1 - o_k h_j. None means
    0 (a measurement is never hidden by the others, or occlusion is object-wise).

    hidden_centre (K, 2) and hidden_variance (K, 2), optional: the mean and per-axis variance
    of each component's centre given that its measurement was hidden (the moments of
    p(x) q(x) / q_k, in the filter's frame). Given, a missed component's density takes the
    miss branch too: the hidden part of its miss moves it there (`occtrack.filters.gmpmb`).
    None: the miss child keeps its parent's density (q read at one point)."""

    visible: np.ndarray
    hidden: np.ndarray
    seen_hidden: np.ndarray | None = None
    hidden_centre: np.ndarray | None = None
    hidden_variance: np.ndarray | None = None


class OcclusionModel(Protocol):
    """The interface of an occlusion model: a `name`, and `terms(ctx)`, which returns each
    component's `OcclusionTerms` (visible v_k, hidden q_k) from an `OcclusionContext`."""

    name: str

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms: ...


class NoOcclusion:
    """Every object is visible and no measurement is ever hidden."""

    name = "none"

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        k = len(ctx.means)
        return OcclusionTerms(np.ones(k), np.zeros(k))
