# Kernels of occtrack.occlusion.box_geometry (the maths: its docstring). Boxes are edge
# arrays (n, 2, 2), box k's edge [axis, low/high] at k * 4 + axis * 2 + e.

cdef inline double _hides_c(const f64* a, const f64* b, double gain, double ramp_zero,
                            double ramp_one) noexcept nogil:
    """p(box a hidden by box b), a and b pointing at one box each (4 values)."""
    cdef double cover = 1.0, overlap, gap, order
    cdef int axis
    for axis in range(2):
        overlap = py_max(py_min(a[axis * 2 + 1], b[axis * 2 + 1])
                       - py_max(a[axis * 2], b[axis * 2]), 0.0)
        cover *= overlap / py_max(a[axis * 2 + 1] - a[axis * 2], 1e-9)
    gap = (b[3] - a[3]) / py_max(b[3] - b[2], 1e-9)
    order = (gap - ramp_zero) / (ramp_one - ramp_zero)
    return py_min(py_max(gain * cover, 0.0), 1.0) * py_min(py_max(order, 0.0), 1.0)


cdef void _visible_dense_c(const f64* hidden, Py_ssize_t K, const f64* occluders,
                           Py_ssize_t N, const f64* weights, Py_ssize_t n_weights,
                           const i64* skip, Py_ssize_t n_skip, double gain, double ramp_zero,
                           double ramp_one, f64* out) noexcept nogil:
    """out[k] = prod_n (1 - w_n p[k, n]) over every occluder n but skip[k] (no weights: all
    1; no skip: none)."""
    cdef Py_ssize_t k, n
    cdef double p
    for k in range(K):
        out[k] = 1.0
        for n in range(N):
            if n_skip == 0 or n != skip[k]:
                p = _hides_c(hidden + k * 4, occluders + n * 4, gain, ramp_zero, ramp_one)
                out[k] *= 1.0 - (weights[n] * p if n_weights else p)


cdef int _check_weights_skip(Py_ssize_t n_weights, Py_ssize_t N, Py_ssize_t n_skip,
                             Py_ssize_t K) except -1:
    if n_weights and n_weights != N:
        raise ValueError(f"weights: {N} values (one an occluder) or none are needed, "
                         f"not {n_weights}")
    if n_skip and n_skip != K:
        raise ValueError(f"skip: {K} values (one a hidden box) or none are needed, "
                         f"not {n_skip}")
    return 0


def _hides(a, b, double gain, double ramp_zero, double ramp_one):
    """p(box a hidden by box b): the formula at the top of box_geometry.py (a, b: (2, 2))."""
    cdef const f64* pa = doubles(a, 2, "a")
    cdef const f64* pb = doubles(b, 2, "b")
    if dim(a, 0) != 2 or dim(a, 1) != 2 or dim(b, 0) != 2 or dim(b, 1) != 2:
        raise ValueError("a, b: one box (2, 2) each is needed")
    return _hides_c(pa, pb, gain, ramp_zero, ramp_one)


def _table(hidden, occluders, double gain, double ramp_zero, double ramp_one):
    """p[k, n] for every pair."""
    cdef const f64* h = _boxes(hidden, "hidden")
    cdef const f64* o = _boxes(occluders, "occluders")
    cdef Py_ssize_t K = dim(hidden, 0), N = dim(occluders, 0), k, n
    out = new_doubles(2, K, N)
    cdef f64* p = <f64*>cnp.PyArray_DATA(out)
    for k in range(K):
        for n in range(N):
            p[k * N + n] = _hides_c(h + k * 4, o + n * 4, gain, ramp_zero, ramp_one)
    return out


def _visible_dense(hidden, occluders, weights, skip, double gain, double ramp_zero,
                   double ramp_one):
    """prod_n (1 - w_n p[k, n]) over every occluder n but skip[k]."""
    cdef const f64* h = _boxes(hidden, "hidden")
    cdef const f64* o = _boxes(occluders, "occluders")
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const i64* s = integers(skip, 1, "skip")
    cdef Py_ssize_t K = dim(hidden, 0), N = dim(occluders, 0)
    _check_weights_skip(dim(weights, 0), N, dim(skip, 0), K)
    out = new_doubles(1, K)
    _visible_dense_c(h, K, o, N, w, dim(weights, 0), s, dim(skip, 0), gain, ramp_zero,
                     ramp_one, <f64*>cnp.PyArray_DATA(out))
    return out


def _visible_pairs(hidden, occluders, k, n, weights, skip, double gain, double ramp_zero,
                   double ramp_one):
    """The same product over the listed (k, n) pairs only (the others have p = 0), summed
    as logarithms."""
    cdef const f64* h = _boxes(hidden, "hidden")
    cdef const f64* o = _boxes(occluders, "occluders")
    cdef const i64* pk = integers(k, 1, "k")
    cdef const i64* pn = integers(n, 1, "n")
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const i64* s = integers(skip, 1, "skip")
    cdef Py_ssize_t K = dim(hidden, 0), N = dim(occluders, 0), E = dim(k, 0), e
    cdef Py_ssize_t n_weights = dim(weights, 0), n_skip = dim(skip, 0)
    length(n, E, "n")
    _check_weights_skip(n_weights, N, n_skip, K)
    cdef double p
    log_visible_ = zero_doubles(1, K)
    cdef f64* log_visible = <f64*>cnp.PyArray_DATA(log_visible_)
    for e in range(E):
        if n_skip == 0 or pn[e] != s[pk[e]]:
            p = _hides_c(h + pk[e] * 4, o + pn[e] * 4, gain, ramp_zero, ramp_one)
            if n_weights:
                p *= w[pn[e]]
            log_visible[pk[e]] += log1p(-py_min(p, 1.0)) if p < 1.0 else -INFINITY
    for e in range(K):
        log_visible[e] = exp(log_visible[e])
    return log_visible_


def _hidden_dense(boxes, z, double gain, double ramp_zero, double ramp_one):
    """`hidden_by_seen` over every pair: (1 - prod_n (1 - p[k, n]), the same for z_j over the
    other seen boxes)."""
    cdef const f64* b = _boxes(boxes, "boxes")
    cdef const f64* pz = _boxes(z, "z")
    cdef Py_ssize_t K = dim(boxes, 0), M = dim(z, 0), j
    q_, h_, self_ = new_doubles(1, K), new_doubles(1, M), new_integers(1, M)
    cdef f64* q = <f64*>cnp.PyArray_DATA(q_)
    cdef f64* h = <f64*>cnp.PyArray_DATA(h_)
    cdef i64* own = <i64*>cnp.PyArray_DATA(self_)
    for j in range(M):
        own[j] = j
    _visible_dense_c(b, K, pz, M, NULL, 0, NULL, 0, gain, ramp_zero, ramp_one, q)
    for j in range(K):
        q[j] = 1.0 - q[j]
    _visible_dense_c(pz, M, pz, M, NULL, 0, own, M, gain, ramp_zero, ramp_one, h)
    for j in range(M):
        h[j] = 1.0 - h[j]
    return q_, h_
