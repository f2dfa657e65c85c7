# cython: language_level=3
"""Compiled kernels of occtrack.association (issue 23): loopy BP's message loops for
`lbp_sparse` (the maths and the call are in lbp.py): `_one_cluster`, `_iterate_clusters` and
`_marginals`.

Each kernel is written as its numba loop read: the arrays are C pointers, so x[e] is read and
written as in numpy, and each sum is taken in the same order (no fused multiply-add, no
reassociation), so the numbers are the same to the last bit. A `def` entry checks each array
once (dtype, dimensions, C order: `occtrack._arrays`) and hands pointers to a `cdef` kernel;
the kernels themselves touch no Python object.
"""

cimport numpy as cnp
from libc.math cimport fabs

from occtrack._arrays cimport bdata, fdata, idata, length
from occtrack._arrays cimport (b8, dim, doubles, f64, i64, integers, new_booleans,
                               new_doubles, new_integers, zero_doubles, zero_integers)

cnp.import_array()


# ---- the kernels ----------------------------------------------------------------------------

cdef i64 _iterate_clusters_c(const i64* rows, const i64* cols, const f64* ratio,
                             const f64* new, const i64* sizes, Py_ssize_t E, Py_ssize_t C,
                             Py_ssize_t n, Py_ssize_t m, double tol, i64 max_iter,
                             f64* nu) except -1:
    """The message iteration of `lbp_sparse` on pairs grouped by cluster (`sizes` pairs
    each, in order): nu of each pair (written into `nu`), and the iterations. A cluster whose
    largest relative change of nu falls below `tol` is frozen; the iteration ends when all
    are, or at `max_iter`."""
    cdef cnp.ndarray start_ = zero_integers(1, C + 1), s_ = new_doubles(1, E)
    cdef cnp.ndarray mu_ = new_doubles(1, E), total_ = zero_doubles(1, n)
    cdef cnp.ndarray into_ = zero_doubles(1, m), live_ = new_booleans(1, C)
    cdef i64* start = idata(start_)
    cdef f64* s = fdata(s_)
    cdef f64* mu = fdata(mu_)
    cdef f64* total = fdata(total_)
    cdef f64* into = fdata(into_)
    cdef b8* live = <b8*>cnp.PyArray_DATA(live_)
    cdef Py_ssize_t c, e, remaining = C
    cdef i64 iterations = 0
    cdef double change, nu_new, step
    for c in range(C):
        start[c + 1] = start[c] + sizes[c]
        live[c] = True
    if start[C] > E:
        raise ValueError(f"sizes: {start[C]} pairs in all, more than the {E} given")
    for e in range(E):
        nu[e] = 1.0
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
                    step = fabs(nu_new - nu[e]) / nu_new
                    if step > change:  # max(change, step), as Python's and numba's max
                        change = step
                    nu[e] = nu_new
                if change < tol:
                    live[c] = False
                    remaining -= 1
    return iterations


cdef void _marginals_c(const i64* rows, const i64* cols, const f64* ratio, const f64* grouped,
                       const i64* order, const f64* w_new, Py_ssize_t E, Py_ssize_t n,
                       Py_ssize_t m, f64* s, f64* total, f64* to_new, f64* p_hit,
                       f64* p_miss, f64* p_new) noexcept nogil:
    """p_hit (E), p_miss (n) and p_new (m) from the converged messages nu (`grouped`, in the
    order `order` of the edges); s (E), total (n, zeros) and to_new (m, zeros) are scratch."""
    cdef Py_ssize_t e, i, j
    for i in range(E):
        s[order[i]] = ratio[order[i]] * grouped[i]
    for e in range(E):
        total[rows[e]] += s[e]
    for e in range(E):
        p_hit[e] = s[e] / (1.0 + total[rows[e]])
        to_new[cols[e]] += ratio[e] / (1.0 + total[rows[e]] - s[e])
    for i in range(n):
        p_miss[i] = 1.0 / (1.0 + total[i])
    for j in range(m):
        p_new[j] = w_new[j] / (w_new[j] + to_new[j])


cdef tuple _marginals_new(const i64* rows, const i64* cols, const f64* ratio,
                          const f64* grouped, const i64* order, const f64* w_new, Py_ssize_t E,
                          Py_ssize_t n, Py_ssize_t m):
    """`_marginals_c` into new arrays: (p_hit, p_miss, p_new)."""
    cdef cnp.ndarray s = new_doubles(1, E), total = zero_doubles(1, n)
    cdef cnp.ndarray to_new = zero_doubles(1, m)
    cdef cnp.ndarray p_hit = new_doubles(1, E), p_miss = new_doubles(1, n)
    cdef cnp.ndarray p_new = new_doubles(1, m)
    _marginals_c(rows, cols, ratio, grouped, order, w_new, E, n, m, fdata(s), fdata(total),
                 fdata(to_new), fdata(p_hit), fdata(p_miss), fdata(p_new))
    return p_hit, p_miss, p_new


# ---- the entries lbp.py calls -------------------------------------------------------------

def _one_cluster(rows, cols, w_hit, w_miss, w_new, double tol, i64 max_iter):
    """`lbp_sparse` of pairs taken as one cluster (the pair order is the cluster's):
    (p_hit, p_miss, p_new, iterations), the same numbers as the clustered path gives."""
    cdef const i64* r = integers(rows, 1, "rows")
    cdef Py_ssize_t E = dim(rows, 0), e
    cdef const i64* k = integers(cols, 1, "cols")
    cdef const f64* hit = doubles(w_hit, 1, "w_hit")
    cdef const f64* miss = doubles(w_miss, 1, "w_miss")
    cdef const f64* wnew = doubles(w_new, 1, "w_new")
    length(cols, E, "cols")
    length(w_hit, E, "w_hit")
    cdef Py_ssize_t n = dim(w_miss, 0), m = dim(w_new, 0)
    cdef cnp.ndarray ratio_ = new_doubles(1, E), new_ = new_doubles(1, E)
    cdef cnp.ndarray nu_ = new_doubles(1, E), order_ = new_integers(1, E)
    cdef f64* ratio = fdata(ratio_)
    cdef f64* new = fdata(new_)
    cdef i64* order = idata(order_)
    cdef i64 size = E
    for e in range(E):
        ratio[e] = hit[e] / miss[r[e]]
        new[e] = wnew[k[e]]
        order[e] = e
    iterations = _iterate_clusters_c(r, k, ratio, new, &size, E, 1, n, m, tol, max_iter,
                                     fdata(nu_))
    return _marginals_new(r, k, ratio, fdata(nu_), order, wnew, E, n, m) + (iterations,)


def _iterate_clusters(rows, cols, ratio, new, sizes, Py_ssize_t n, Py_ssize_t m, double tol,
                      i64 max_iter):
    """The message iteration of `lbp_sparse` on pairs grouped by cluster (`sizes` pairs
    each, in order): (nu of each pair, iterations). A cluster whose largest relative change
    of nu falls below `tol` is frozen; the iteration ends when all are, or at `max_iter`."""
    cdef const i64* r = integers(rows, 1, "rows")
    cdef Py_ssize_t E = dim(rows, 0)
    cdef const i64* k = integers(cols, 1, "cols")
    cdef const f64* q = doubles(ratio, 1, "ratio")
    cdef const f64* w = doubles(new, 1, "new")
    cdef const i64* z = integers(sizes, 1, "sizes")
    length(cols, E, "cols")
    length(ratio, E, "ratio")
    length(new, E, "new")
    nu = new_doubles(1, E)
    iterations = _iterate_clusters_c(r, k, q, w, z, E, dim(sizes, 0), n, m, tol, max_iter,
                                     fdata(nu))
    return nu, iterations


def _marginals(rows, cols, ratio, grouped, order, w_new, Py_ssize_t n):
    """p_hit, p_miss and p_new from the converged messages nu (`grouped`, in the order
    `order` of the edges): with s_e = ratio_e nu_e and S_i the sum of s over row i,
    p_hit = s / (1 + S_i), p_miss = 1 / (1 + S_i), and p_new_j = w_new_j / (w_new_j + sum of
    mu_e = ratio_e / (1 + S_i - s_e) over column j)."""
    cdef const i64* r = integers(rows, 1, "rows")
    cdef Py_ssize_t E = dim(rows, 0)
    cdef const i64* k = integers(cols, 1, "cols")
    cdef const f64* q = doubles(ratio, 1, "ratio")
    cdef const f64* g = doubles(grouped, 1, "grouped")
    cdef const i64* o = integers(order, 1, "order")
    cdef const f64* w = doubles(w_new, 1, "w_new")
    length(cols, E, "cols")
    length(ratio, E, "ratio")
    length(grouped, E, "grouped")
    length(order, E, "order")
    return _marginals_new(r, k, q, g, o, w, E, n, dim(w_new, 0))


cdef inline i64 _root(i64* parent, i64 x) noexcept nogil:
    """The root of x's set, halving the path on the way."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


def _clusters(rows, cols, Py_ssize_t n, Py_ssize_t m):
    """`clusters_of` by union-find: (count, cluster of each pair) over the n + m nodes
    (objects 0..n-1, measurements n..n+m-1), components numbered by their lowest node as
    scipy's `connected_components` numbers them (every node, in no pair or not, is one)."""
    cdef const i64* r = integers(rows, 1, "rows")
    cdef Py_ssize_t E = dim(rows, 0)
    cdef const i64* k = integers(cols, 1, "cols")
    length(cols, E, "cols")
    cdef Py_ssize_t N = n + m, e, x
    cdef i64 a, b
    for e in range(E):
        if not (0 <= r[e] < n and 0 <= k[e] < m):
            raise IndexError(f"pair {e} ({r[e]}, {k[e]}) lies outside {n} x {m}")
    parent_ = new_integers(1, N)
    label_ = new_integers(1, N)
    cdef i64* parent = idata(parent_)
    cdef i64* label = idata(label_)
    for x in range(N):
        parent[x] = x
        label[x] = -1
    for e in range(E):
        a = _root(parent, r[e])
        b = _root(parent, n + k[e])
        if a != b:  # the lower root stays the root
            if a < b:
                parent[b] = a
            else:
                parent[a] = b
    cdef i64 count = 0
    for x in range(N):
        a = _root(parent, x)
        if label[a] < 0:
            label[a] = count
            count += 1
    out_ = new_integers(1, E)
    cdef i64* out = idata(out_)
    for e in range(E):
        out[e] = label[_root(parent, r[e])]
    return int(count), out_
