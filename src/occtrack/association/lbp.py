"""Loopy belief propagation for association marginals (Williams and Lau, 2014).

The association problem has n objects and m measurements. `w_hit[i, j]` is object i's weight for
producing measurement j (existence times the hit term), `w_miss[i]` its weight for producing none
(1 - r_i + r_i times the miss term), and `w_new[j]` the weight that measurement j is new or clutter
(kappa p_F(z_j) plus the Poisson part's hit terms). With messages mu (object to measurement) and
nu (measurement to object) the two message equations are

    mu[i, j] = w_hit[i, j] / (w_miss[i] + sum_{j' != j} w_hit[i, j'] nu[j', i])
    nu[j, i] = 1 / (w_new[j] + sum_{i' != i} mu[i', j])

iterated until the largest relative change of nu falls below `tol` (at most `max_iter` times).
The algorithm is short and exact on tree-shaped problems; no well-kept library ships it for this
bipartite form, so it is written here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Marginals:
    """p_hit[i, j]: object i produced measurement j; p_miss[i]: object i produced none;
    p_new[j]: measurement j is new or clutter. Rows of [p_miss, p_hit] and columns of
    [p_new; p_hit] each sum to 1."""

    p_hit: np.ndarray
    p_miss: np.ndarray
    p_new: np.ndarray
    iterations: int = 0


def lbp_marginals(w_hit: np.ndarray, w_miss: np.ndarray, w_new: np.ndarray,
                  tol: float = 1e-7, max_iter: int = 1000) -> Marginals:
    w_hit = np.asarray(w_hit, dtype=float)
    w_miss = np.asarray(w_miss, dtype=float)
    w_new = np.asarray(w_new, dtype=float)
    n, m = w_hit.shape
    if n == 0 or m == 0:
        return Marginals(np.zeros((n, m)), np.ones(n), np.ones(m), 0)
    tiny = np.finfo(float).tiny
    w_miss = np.maximum(w_miss, tiny)
    w_new = np.maximum(w_new, tiny)
    # Scale each object's row by its miss weight: marginals are unchanged, messages stay O(1).
    ratio = w_hit / w_miss[:, None]
    nu = np.ones((n, m))  # nu[i, j]: message from measurement j to object i
    iterations = 0
    while iterations < max_iter:
        iterations += 1
        s = ratio * nu
        mu = ratio / (1.0 + s.sum(axis=1, keepdims=True) - s)
        nu_new = 1.0 / (w_new[None, :] + mu.sum(axis=0, keepdims=True) - mu)
        change = np.max(np.abs(nu_new - nu) / nu_new)
        nu = nu_new
        if change < tol:
            break
    s = ratio * nu
    denom = 1.0 + s.sum(axis=1)
    p_hit = s / denom[:, None]
    p_miss = 1.0 / denom
    mu = ratio / (1.0 + s.sum(axis=1, keepdims=True) - s)
    p_new = w_new / (w_new + mu.sum(axis=0))
    return Marginals(p_hit, p_miss, p_new, iterations)
