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

`lbp_sparse` runs the same messages on a sparse problem, only on the pairs (i, j) that can
associate (the gated ones, w_hit > 0): a message on any other pair is zero and carries nothing.
The pairs split the problem into clusters that share no object and no measurement (connected
components of the bipartite graph); the messages of one cluster never reach another, so each
cluster is iterated until its own largest change falls below `tol` and then left alone. In a
crowd most clusters are a person or two and settle in a few iterations, and the cost of an
iteration follows the pairs still moving, not n m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.jit import njit


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


@dataclass(frozen=True)
class SparseMarginals:
    """p_hit[e]: object rows[e] produced measurement cols[e], one per pair given; p_miss (n,)
    and p_new (m,) as in `Marginals`; `clusters`: how many clusters the pairs formed."""

    p_hit: np.ndarray
    p_miss: np.ndarray
    p_new: np.ndarray
    iterations: int = 0
    clusters: int = 0


TINY = np.finfo(float).tiny  # weights are floored here, so that no ratio divides by zero
CLUSTER_MIN_PAIRS = 256  # fewer pairs: one cluster, as the dense form would stop


def clusters_of(rows: np.ndarray, cols: np.ndarray, n: int, m: int) -> tuple[int, np.ndarray]:
    """(count, cluster of each pair): connected components of the bipartite graph whose
    edges are the pairs (rows[e], cols[e])."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, n + cols)),
                       shape=(n + m, n + m))
    count, node = connected_components(graph, directed=False)
    return count, node[rows]


def lbp_sparse(rows: np.ndarray, cols: np.ndarray, w_hit: np.ndarray, w_miss: np.ndarray,
               w_new: np.ndarray, tol: float = 1e-7, max_iter: int = 1000) -> SparseMarginals:
    """Loopy BP on the pairs (rows[e], cols[e]) with weights w_hit[e] > 0 (each pair once);
    w_miss (n,) and w_new (m,) as in `lbp_marginals`. Cluster by cluster: a cluster stops when
    its own messages change less than `tol`."""
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    w_hit = np.asarray(w_hit, dtype=float)
    w_miss = np.maximum(np.asarray(w_miss, dtype=float), TINY)
    w_new = np.maximum(np.asarray(w_new, dtype=float), TINY)
    n, m, E = len(w_miss), len(w_new), len(rows)
    if E == 0:
        return SparseMarginals(np.zeros(0), np.ones(n), np.ones(m), 0, 0)
    if E < CLUSTER_MIN_PAIRS:  # one cluster: the whole of it in one compiled call
        return SparseMarginals(*_one_cluster(rows, cols, w_hit, w_miss, w_new, tol, max_iter),
                               1)
    ratio = w_hit / w_miss[rows]
    count, cluster = clusters_of(rows, cols, n, m)
    order = np.argsort(cluster, kind="stable")
    sizes = np.bincount(cluster, minlength=count)
    grouped, iterations = _iterate_clusters(rows[order], cols[order], ratio[order],
                                            w_new[cols[order]], sizes[sizes > 0], n, m, tol,
                                            max_iter)
    p_hit, p_miss, p_new = _marginals(rows, cols, ratio, grouped, order, w_new, n)
    return SparseMarginals(p_hit, p_miss, p_new, iterations, count)


@njit
def _one_cluster(rows, cols, w_hit, w_miss, w_new, tol, max_iter):
    """`lbp_sparse` of pairs taken as one cluster (the pair order is the cluster's):
    (p_hit, p_miss, p_new, iterations), the same numbers as the clustered path gives."""
    E = len(rows)
    ratio, new = np.empty(E), np.empty(E)
    for e in range(E):
        ratio[e] = w_hit[e] / w_miss[rows[e]]
        new[e] = w_new[cols[e]]
    sizes = np.full(1, E, dtype=np.int64)
    nu, iterations = _iterate_clusters(rows, cols, ratio, new, sizes, len(w_miss), len(w_new),
                                       tol, max_iter)
    p_hit, p_miss, p_new = _marginals(rows, cols, ratio, nu, np.arange(E), w_new, len(w_miss))
    return p_hit, p_miss, p_new, iterations


@njit
def _marginals(rows, cols, ratio, grouped, order, w_new, n):
    """p_hit, p_miss and p_new from the converged messages nu (`grouped`, in the order
    `order` of the edges): with s_e = ratio_e nu_e and S_i the sum of s over row i,
    p_hit = s / (1 + S_i), p_miss = 1 / (1 + S_i), and p_new_j = w_new_j / (w_new_j + sum of
    mu_e = ratio_e / (1 + S_i - s_e) over column j)."""
    E, m = len(rows), len(w_new)
    s = np.empty(E)
    for i in range(E):
        s[order[i]] = ratio[order[i]] * grouped[i]
    total = np.zeros(n)
    for e in range(E):
        total[rows[e]] += s[e]
    p_hit = np.empty(E)
    to_new = np.zeros(m)
    for e in range(E):
        p_hit[e] = s[e] / (1.0 + total[rows[e]])
        to_new[cols[e]] += ratio[e] / (1.0 + total[rows[e]] - s[e])
    p_miss = np.empty(n)
    for i in range(n):
        p_miss[i] = 1.0 / (1.0 + total[i])
    p_new = np.empty(m)
    for j in range(m):
        p_new[j] = w_new[j] / (w_new[j] + to_new[j])
    return p_hit, p_miss, p_new


@njit
def _iterate_clusters(rows, cols, ratio, new, sizes, n, m, tol, max_iter):
    """The message iteration of `lbp_sparse` on pairs grouped by cluster (`sizes` pairs
    each, in order): (nu of each pair, iterations). A cluster whose largest relative change
    of nu falls below `tol` is frozen; the iteration ends when all are, or at `max_iter`."""
    E, C = len(rows), len(sizes)
    start = np.zeros(C + 1, dtype=np.int64)
    for c in range(C):
        start[c + 1] = start[c] + sizes[c]
    nu, s, mu = np.ones(E), np.empty(E), np.empty(E)
    total, into = np.zeros(n), np.zeros(m)
    live = np.ones(C, dtype=np.bool_)
    remaining, iterations = C, 0
    while remaining and iterations < max_iter:
        iterations += 1
        for c in range(C):
            if live[c]:
                for e in range(start[c], start[c + 1]):
                    total[rows[e]] = 0.0
                    into[cols[e]] = 0.0
        for c in range(C):
            if live[c]:
                for e in range(start[c], start[c + 1]):
                    s[e] = ratio[e] * nu[e]
                    total[rows[e]] += s[e]
        for c in range(C):
            if live[c]:
                for e in range(start[c], start[c + 1]):
                    mu[e] = ratio[e] / (1.0 + total[rows[e]] - s[e])
                    into[cols[e]] += mu[e]
        for c in range(C):
            if live[c]:
                change = 0.0
                for e in range(start[c], start[c + 1]):
                    nu_new = 1.0 / (new[e] + into[cols[e]] - mu[e])
                    change = max(change, abs(nu_new - nu[e]) / nu_new)
                    nu[e] = nu_new
                if change < tol:
                    live[c] = False
                    remaining -= 1
    return nu, iterations
