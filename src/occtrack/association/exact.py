"""Exact association marginals by enumerating every association: the reference for tests.

Cost grows as the number of partial matchings, so it is meant for a handful of objects and
measurements.
"""

from __future__ import annotations

import numpy as np

from occtrack.association.lbp import Marginals


def exact_marginals(w_hit: np.ndarray, w_miss: np.ndarray, w_new: np.ndarray) -> Marginals:
    w_hit = np.asarray(w_hit, dtype=float)
    w_miss = np.asarray(w_miss, dtype=float)
    w_new = np.asarray(w_new, dtype=float)
    n, m = w_hit.shape
    p_hit = np.zeros((n, m))
    p_miss = np.zeros(n)
    total = 0.0
    choice = [-1] * n

    def visit(i: int, used: frozenset, weight: float) -> None:
        nonlocal total
        if i == n:
            full = weight * np.prod([w_new[j] for j in range(m) if j not in used])
            total += full
            for k, j in enumerate(choice):
                if j < 0:
                    p_miss[k] += full
                else:
                    p_hit[k, j] += full
            return
        choice[i] = -1
        visit(i + 1, used, weight * w_miss[i])
        for j in range(m):
            if j not in used and w_hit[i, j] > 0:
                choice[i] = j
                visit(i + 1, used | {j}, weight * w_hit[i, j])
        choice[i] = -1

    visit(0, frozenset(), 1.0)
    if not total > 0:
        raise ValueError("no association has positive weight")
    p_hit /= total
    p_miss /= total
    p_new = 1.0 - p_hit.sum(axis=0)
    return Marginals(p_hit, p_miss, p_new, 0)
