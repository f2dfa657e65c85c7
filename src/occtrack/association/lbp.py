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

The loops are compiled (`_association.pyx` beside this module): `_one_cluster` (fewer pairs
than `CLUSTER_MIN_PAIRS`: all of them as one cluster, in one call), `_iterate_clusters` (the
two message equations above, cluster by cluster, each frozen once its largest relative change
of nu is below `tol`) and `_marginals` (the marginals from the converged messages).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.association._association import (  # the compiled kernels
    _iterate_clusters,
    _marginals,
    _one_cluster,
)


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
    rows = np.ascontiguousarray(rows, dtype=np.int64)  # the compiled kernels read them in place
    cols = np.ascontiguousarray(cols, dtype=np.int64)
    w_hit = np.ascontiguousarray(w_hit, dtype=float)
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
