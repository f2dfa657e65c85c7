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
    tiny = np.finfo(float).tiny
    w_miss = np.maximum(np.asarray(w_miss, dtype=float), tiny)
    w_new = np.maximum(np.asarray(w_new, dtype=float), tiny)
    n, m, E = len(w_miss), len(w_new), len(rows)
    if E == 0:
        return SparseMarginals(np.zeros(0), np.ones(n), np.ones(m), 0, 0)
    ratio = w_hit / w_miss[rows]
    if E >= CLUSTER_MIN_PAIRS:
        count, cluster = clusters_of(rows, cols, n, m)
        order = np.argsort(cluster, kind="stable")
        sizes = np.bincount(cluster, minlength=count)
    else:
        count, order, sizes = 1, np.arange(E), np.array([E])
    nu = np.ones(E)
    # the pairs still iterating, grouped by cluster: positions in `order`
    live = order
    a_rows, a_cols, a_ratio, a_new = rows[live], cols[live], ratio[live], w_new[cols[live]]
    a_nu = np.ones(len(live))
    a_sizes = sizes[sizes > 0]
    iterations = 0
    while len(live) and iterations < max_iter:
        iterations += 1
        s = a_ratio * a_nu
        total = np.bincount(a_rows, weights=s, minlength=n)
        mu = a_ratio / (1.0 + total[a_rows] - s)
        into = np.bincount(a_cols, weights=mu, minlength=m)
        nu_new = 1.0 / (a_new + into[a_cols] - mu)
        change = np.abs(nu_new - a_nu) / nu_new
        a_nu = nu_new
        if len(a_sizes) == 1:
            if change.max() < tol:
                break
            continue
        starts = np.cumsum(a_sizes) - a_sizes
        done = np.maximum.reduceat(change, starts) < tol
        if done.any():
            finished = np.repeat(done, a_sizes)
            nu[live[finished]] = a_nu[finished]
            keep = ~finished
            live, a_rows, a_cols, a_ratio, a_new, a_nu = (
                live[keep], a_rows[keep], a_cols[keep], a_ratio[keep], a_new[keep], a_nu[keep])
            a_sizes = a_sizes[~done]
    nu[live] = a_nu
    s = ratio * nu
    total = np.bincount(rows, weights=s, minlength=n)
    p_hit = s / (1.0 + total[rows])
    p_miss = 1.0 / (1.0 + total)
    mu = ratio / (1.0 + total[rows] - s)
    p_new = w_new / (w_new + np.bincount(cols, weights=mu, minlength=m))
    return SparseMarginals(p_hit, p_miss, p_new, iterations, count)
