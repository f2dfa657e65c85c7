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

Zero weights are hard constraints: w_miss[i] = 0 says object i is surely detected, w_new[j] = 0
that measurement j surely comes from an object (no clutter, no births). Where only one pair is
left to meet such a constraint its message is 1 / 0; `forced_pairs` takes those pairs exactly
first (and names the object or measurement when nothing can meet one), and BP runs on the rest.

The loops are compiled (`_association.pyx` beside this module): `_one_cluster` (fewer pairs
than `CLUSTER_MIN_PAIRS`: all of them as one cluster, in one call), `_iterate_clusters` (the
two message equations above, cluster by cluster, each frozen once its largest relative change
of nu is below `tol`) and `_marginals` (the marginals from the converged messages).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.association._association import (  # the compiled kernels
    _clusters,
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
    """The marginals of every object and measurement; w_hit (n, m), w_miss (n,), w_new (m,),
    weights >= 0 (zeros: see `forced_pairs`)."""
    w_hit = np.asarray(w_hit, dtype=float)
    w_miss = np.asarray(w_miss, dtype=float)
    w_new = np.asarray(w_new, dtype=float)
    if w_hit.ndim != 2 or w_miss.shape != w_hit.shape[:1] or w_new.shape != w_hit.shape[1:]:
        raise ValueError(f"w_hit must be (n, m), w_miss (n,) and w_new (m,), not "
                         f"{w_hit.shape}, {w_miss.shape} and {w_new.shape}")
    _check_weights(w_hit, w_miss, w_new)
    if (w_miss <= 0).any() or (w_new <= 0).any():  # the sparse form's, on the pairs
        rows, cols = np.nonzero(w_hit > 0)
        sub = _sparse_with_zeros(rows, cols, w_hit[rows, cols], w_miss, w_new, tol, max_iter)
        p_hit = np.zeros(w_hit.shape)
        p_hit[rows, cols] = sub.p_hit
        return Marginals(p_hit, sub.p_miss, sub.p_new, sub.iterations)
    return _lbp_dense(w_hit, w_miss, w_new, tol, max_iter)


def _lbp_dense(w_hit: np.ndarray, w_miss: np.ndarray, w_new: np.ndarray, tol: float,
               max_iter: int) -> Marginals:
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
    edges are the pairs (rows[e], cols[e]), over all n + m nodes, numbered by their lowest
    node (as scipy.sparse.csgraph.connected_components numbers them; a union-find compiled in
    `_clusters`: building scipy's sparse graph cost more than the whole of loopy BP)."""
    return _clusters(np.ascontiguousarray(rows, dtype=np.int64),
                     np.ascontiguousarray(cols, dtype=np.int64), int(n), int(m))


def lbp_sparse(rows: np.ndarray, cols: np.ndarray, w_hit: np.ndarray, w_miss: np.ndarray,
               w_new: np.ndarray, tol: float = 1e-7, max_iter: int = 1000) -> SparseMarginals:
    """Loopy BP on the pairs (rows[e], cols[e]) with weights w_hit[e] > 0 (each pair once);
    w_miss (n,) and w_new (m,) as in `lbp_marginals`, zeros included (`forced_pairs`). Cluster
    by cluster: a cluster stops when its own messages change less than `tol`."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)  # the compiled kernels read them in place
    cols = np.ascontiguousarray(cols, dtype=np.int64)
    w_hit = np.ascontiguousarray(w_hit, dtype=float)
    w_miss = np.asarray(w_miss, dtype=float)
    w_new = np.asarray(w_new, dtype=float)
    if (w_miss <= 0).any() or (w_new <= 0).any():
        _check_weights(w_hit, w_miss, w_new)
        return _sparse_with_zeros(rows, cols, w_hit, w_miss, w_new, tol, max_iter)
    return _lbp_sparse(rows, cols, w_hit, w_miss, w_new, tol, max_iter)


def _lbp_sparse(rows: np.ndarray, cols: np.ndarray, w_hit: np.ndarray, w_miss: np.ndarray,
                w_new: np.ndarray, tol: float, max_iter: int) -> SparseMarginals:
    w_miss = np.maximum(w_miss, TINY)
    w_new = np.maximum(w_new, TINY)
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


# -- hard zeros -------------------------------------------------------------------------------

ZERO_FLOOR = 1e-150  # a zero weight left after the forced pairs, relative to the largest of its
# object's row (w_miss) or its measurement's column (w_new)


def _check_weights(w_hit: np.ndarray, w_miss: np.ndarray, w_new: np.ndarray) -> None:
    for name, w in (("w_hit", w_hit), ("w_miss", w_miss), ("w_new", w_new)):
        bad = w[~(np.isfinite(w) & (w >= 0))]
        if len(bad):
            raise ValueError(f"{name} must hold finite weights >= 0, not {bad[0]}")


def forced_pairs(rows: np.ndarray, cols: np.ndarray, w_miss: np.ndarray,
                 w_new: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hard zeros, exactly. An object with w_miss = 0 must produce a measurement, and a
    measurement with w_new = 0 must come from an object. When one pair (rows[e], cols[e]) is
    all that is left to do it, every association of positive weight holds that pair: it is
    taken (p_hit = 1), and its object and measurement leave the problem, which may force
    others. Messages would be infinite there (1 / 0), so BP never sees them.

    Returns (pairs taken (E,) bool, objects left (n,) bool, measurements left (m,) bool);
    a zero weight still left has at least two pairs to choose from and is floored at
    `ZERO_FLOOR` of its row's (column's) largest weight. Raises ValueError, naming the object or
    measurement, when no association has positive weight."""
    n, m = len(w_miss), len(w_new)
    must_hit, must_come = w_miss <= 0, w_new <= 0
    objects, measurements = np.ones(n, dtype=bool), np.ones(m, dtype=bool)
    live = np.ones(len(rows), dtype=bool)
    taken = np.zeros(len(rows), dtype=bool)
    while True:
        out_of = np.bincount(rows[live], minlength=n)
        into = np.bincount(cols[live], minlength=m)
        stuck = np.flatnonzero(objects & must_hit & (out_of == 0))
        if len(stuck):
            raise ValueError(f"no association has positive weight: object {stuck[0]} has "
                             f"w_miss = 0 and no measurement left to produce")
        stuck = np.flatnonzero(measurements & must_come & (into == 0))
        if len(stuck):
            raise ValueError(f"no association has positive weight: measurement {stuck[0]} "
                             f"has w_new = 0 and no object left to produce it")
        take = live & ((objects & must_hit & (out_of == 1))[rows]
                       | (measurements & must_come & (into == 1))[cols])
        if not take.any():
            return taken, objects, measurements
        e = np.flatnonzero(take)
        for ends, what, other in ((rows[e], "object", cols[e]),
                                  (cols[e], "measurement", rows[e])):
            ends_sorted = np.sort(ends)
            twice = ends_sorted[1:][ends_sorted[1:] == ends_sorted[:-1]]
            if len(twice):
                which = np.sort(other[ends == twice[0]])
                raise ValueError(f"no association has positive weight: {what} {twice[0]} "
                                 f"is all that is left to pair with both "
                                 f"{'objects' if what == 'measurement' else 'measurements'} "
                                 f"{which[0]} and {which[1]}")
        taken[e] = True
        objects[rows[e]] = False
        measurements[cols[e]] = False
        live &= objects[rows] & measurements[cols]


def _sparse_with_zeros(rows, cols, w_hit, w_miss, w_new, tol, max_iter) -> SparseMarginals:
    """`lbp_sparse` (and `lbp_marginals`) with zero miss or new weights: the forced pairs
    taken, BP on the rest after each measurement's column, then each object's row, is divided
    by its largest weight (an association holds one weight of each row and each column, so no
    marginal moves) and the zeros left are floored at ZERO_FLOOR: every weight is then in
    [ZERO_FLOOR, 1] and no message product overflows."""
    n, m = len(w_miss), len(w_new)
    pairs = w_hit > 0
    if not pairs.all():  # a pair of weight 0 is no way to produce a measurement
        sub = _sparse_with_zeros(rows[pairs], cols[pairs], w_hit[pairs], w_miss, w_new, tol,
                                 max_iter)
        p_hit = np.zeros(len(rows))
        p_hit[pairs] = sub.p_hit
        return SparseMarginals(p_hit, sub.p_miss, sub.p_new, sub.iterations, sub.clusters)
    taken, objects, measurements = forced_pairs(rows, cols, w_miss, w_new)
    p_hit, p_miss, p_new = taken.astype(float), np.zeros(n), np.zeros(m)
    rest = objects[rows] & measurements[cols]
    row_of, col_of = np.cumsum(objects) - 1, np.cumsum(measurements) - 1
    r, c = row_of[rows[rest]], col_of[cols[rest]]
    h, miss, new = w_hit[rest], w_miss[objects], w_new[measurements]
    col = new.copy()
    np.maximum.at(col, c, h)
    h, new = h / col[c], new / col
    row = miss.copy()
    np.maximum.at(row, r, h)
    h, miss = h / row[r], miss / row
    sub = _lbp_sparse(np.ascontiguousarray(r), np.ascontiguousarray(c), h,
                      np.maximum(miss, ZERO_FLOOR), np.maximum(new, ZERO_FLOOR), tol, max_iter)
    p_hit[rest], p_miss[objects], p_new[measurements] = sub.p_hit, sub.p_miss, sub.p_new
    return SparseMarginals(p_hit, p_miss, p_new, sub.iterations, sub.clusters)
