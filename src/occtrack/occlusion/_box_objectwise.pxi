# Kernels of occtrack.occlusion.box_objectwise (the maths: its docstring).

cdef int _occluder_boxes_c(const f64* boxes, const f64* weights, const i64* owner,
                           Py_ssize_t K, const i64* occluders, Py_ssize_t n_occ, f64* sums,
                           i64* own) except -1:
    """`_occluder_boxes` into sums (n_occ * 4, zeros) and own (K)."""
    cdef Py_ssize_t P = 0, i, k, j
    cdef i64 top
    if K:
        top = owner[0]
        for k in range(1, K):
            if owner[k] > top:
                top = owner[k]
        P = top + 1 if top + 1 > 0 else 0
    position_ = new_integers(1, P)
    total_ = zero_doubles(1, n_occ)
    cdef i64* position = <i64*>cnp.PyArray_DATA(position_)
    cdef f64* total = <f64*>cnp.PyArray_DATA(total_)
    for i in range(P):
        position[i] = -1
    for i in range(n_occ):
        if occluders[i] < 0:
            raise IndexError(f"occluders: {occluders[i]} is no object")
        if occluders[i] < P:
            position[occluders[i]] = i
    for k in range(K):
        own[k] = -1
    for k in range(K):
        if owner[k] >= 0 and position[owner[k]] >= 0:
            i = position[owner[k]]
            own[k] = i
            total[i] += weights[k]
            for j in range(4):
                sums[i * 4 + j] += weights[k] * boxes[k * 4 + j]
    for i in range(n_occ):
        for j in range(4):
            sums[i * 4 + j] /= py_max(total[i], 1e-300)
    return 0


def _occluder_boxes(boxes, weights, owner, occluders):
    """The occluders' mean boxes, (n, 2, 2): each the weight-averaged edges of its object's
    components; and each component's place among the occluders (-1: its object is none, or
    it is the Poisson part's), the one occluder it never counts."""
    cdef const f64* b = _boxes(boxes, "boxes")
    cdef Py_ssize_t K = dim(boxes, 0)
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const i64* o = integers(owner, 1, "owner")
    cdef const i64* occ = integers(occluders, 1, "occluders")
    length(weights, K, "weights")
    length(owner, K, "owner")
    cdef Py_ssize_t n_occ = dim(occluders, 0)
    sums, own = zero_doubles(3, n_occ, 2, 2), new_integers(1, K)
    _occluder_boxes_c(b, w, o, K, occ, n_occ, <f64*>cnp.PyArray_DATA(sums),
                      <i64*>cnp.PyArray_DATA(own))
    return sums, own


def _visible_behind_means(boxes, weights, owner, occluders, existence, double gain,
                          double ramp_zero, double ramp_one):
    """v_k over every (component, occluder) pair: `_occluder_boxes`, then the product of
    `box_geometry`'s dense form with the occluders' existences as weights."""
    cdef const f64* b = _boxes(boxes, "boxes")
    cdef Py_ssize_t K = dim(boxes, 0), i
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const i64* o = integers(owner, 1, "owner")
    cdef const i64* occ = integers(occluders, 1, "occluders")
    cdef const f64* r = doubles(existence, 1, "existence")
    length(weights, K, "weights")
    length(owner, K, "owner")
    cdef Py_ssize_t n_occ = dim(occluders, 0), n_r = dim(existence, 0)
    sums_, own_ = zero_doubles(1, n_occ * 4), new_integers(1, K)
    r_occ_, out = new_doubles(1, n_occ), new_doubles(1, K)
    cdef f64* sums = <f64*>cnp.PyArray_DATA(sums_)
    cdef i64* own = <i64*>cnp.PyArray_DATA(own_)
    cdef f64* r_occ = <f64*>cnp.PyArray_DATA(r_occ_)
    for i in range(n_occ):
        if occ[i] < 0 or occ[i] >= n_r:
            raise IndexError(f"occluders: {occ[i]} is no object of {n_r}")
        r_occ[i] = r[occ[i]]
    _occluder_boxes_c(b, w, o, K, occ, n_occ, sums, own)
    _visible_dense_c(b, K, sums, n_occ, r_occ, n_occ, own, K, gain, ramp_zero, ramp_one,
                     <f64*>cnp.PyArray_DATA(out))
    return out
