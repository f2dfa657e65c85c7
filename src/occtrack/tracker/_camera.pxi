# Kernels of occtrack.tracker.camera (included by _tracker.pyx): the camera's shift and
# expansion from two frames' boxes. Boxes are (N, 4) left, top, width, height: b[i * 4 + c].


cdef Py_ssize_t argmax_strided(const f64* v, Py_ssize_t n, Py_ssize_t stride) noexcept nogil:
    """numpy's (and numba's) argmax of v[0], v[stride], ..., n > 0: the first largest, or the
    first NaN."""
    cdef double best = v[0], x
    cdef Py_ssize_t k, index = 0
    if best != best:
        return 0
    for k in range(1, n):
        x = v[k * stride]
        if x != x:
            return k
        if x > best:
            best = x
            index = k
    return index


cdef double nan_max(const f64* v, Py_ssize_t n) noexcept nogil:
    """numba's a.max() of n > 0 floats: NaN if any is."""
    cdef double best = v[0]
    cdef Py_ssize_t k
    if best != best:
        return best
    for k in range(1, n):
        if v[k] != v[k]:
            return v[k]
        if v[k] > best:
            best = v[k]
    return best


cdef double nan_min(const f64* v, Py_ssize_t n) noexcept nogil:
    """numba's a.min() of n > 0 floats: NaN if any is."""
    cdef double best = v[0]
    cdef Py_ssize_t k
    if best != best:
        return best
    for k in range(1, n):
        if v[k] != v[k]:
            return v[k]
        if v[k] < best:
            best = v[k]
    return best


cdef Py_ssize_t search_left(const f64* a, Py_ssize_t n, double v) noexcept nogil:
    """np.searchsorted(a[:n], v, side="left") on sorted a (NaN largest): the first index whose
    value is not below v."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while hi > lo:
        mid = (lo + hi) >> 1
        if a[mid] < v or (v != v and a[mid] == a[mid]):
            lo = mid + 1
        else:
            hi = mid
    return lo


cdef void _first_best_c(const i64* group, const f64* value, const i64* other, Py_ssize_t E,
                        Py_ssize_t size, f64* best_value, i64* best_index,
                        b8* seen) noexcept nogil:
    cdef Py_ssize_t e, g
    for g in range(size):
        best_value[g] = 0.0
        best_index[g] = 0
        seen[g] = False
    for e in range(E):
        g = group[e]
        if (not seen[g] or value[e] > best_value[g]
                or (value[e] == best_value[g] and other[e] < best_index[g])):
            seen[g] = True
            best_value[g] = value[e]
            best_index[g] = other[e]


def _first_best(object group, object value, object other, Py_ssize_t size):
    """Per group g < size: the largest value and, among ties, the smallest `other`
    (argmax's choice); groups without pairs get value 0 and index 0, as argmax over a row of
    zeros gives."""
    cdef const i64* g = integers(group, 1, "group")
    cdef const f64* v = doubles(value, 1, "value")
    cdef const i64* o = integers(other, 1, "other")
    cdef Py_ssize_t E = dim(group, 0)
    length(value, E, "value")
    length(other, E, "other")
    best_value, best_index = new_doubles(1, size), new_integers(1, size)
    seen = new_booleans(1, size)
    _first_best_c(g, v, o, E, size, fdata(best_value), idata(best_index), bdata(seen))
    return best_value, best_index


cdef void sort_doubles(f64* x, Py_ssize_t n, f64* work) noexcept nogil:
    """np.sort(x[:n]) in place (NaN last): a bottom-up merge sort of the values, insertion
    sort on runs of 8 first; `work` n floats."""
    cdef Py_ssize_t i, k, width, lo, mid, hi, a, b
    cdef double v
    cdef f64* src = x
    cdef f64* dst = work
    cdef f64* tmp
    for lo in range(0, n, 8):
        hi = lo + 8 if lo + 8 < n else n
        for i in range(lo + 1, hi):
            v = x[i]
            k = i
            while k > lo and (v < x[k - 1] or (x[k - 1] != x[k - 1] and v == v)):
                x[k] = x[k - 1]
                k -= 1
            x[k] = v
    width = 8
    while width < n:
        lo = 0
        while lo < n:
            mid = lo + width if lo + width < n else n
            hi = lo + 2 * width if lo + 2 * width < n else n
            a, b, k = lo, mid, lo
            while a < mid and b < hi:
                if src[b] < src[a] or (src[a] != src[a] and src[b] == src[b]):
                    dst[k] = src[b]
                    b += 1
                else:
                    dst[k] = src[a]
                    a += 1
                k += 1
            while a < mid:
                dst[k] = src[a]
                a += 1
                k += 1
            while b < hi:
                dst[k] = src[b]
                b += 1
                k += 1
            lo = hi
        tmp = src
        src = dst
        dst = tmp
        width *= 2
    if src != x:
        for i in range(n):
            x[i] = src[i]


cdef void _median_rows_c(const f64* values, Py_ssize_t P, f64* out, f64* column,
                         f64* work) noexcept nogil:
    """np.median(values, axis=0) of (P, 2) values, P >= 1; `column` and `work` P floats of
    scratch. (numba sorts by quicksort: the same values in order, up to the order of -0.0
    and 0.0, which compare equal.)"""
    cdef Py_ssize_t axis, p, half = P // 2
    for axis in range(2):
        for p in range(P):
            column[p] = values[p * 2 + axis]
        sort_doubles(column, P, work)
        if P % 2:
            out[axis] = column[half]
        else:
            out[axis] = (column[half - 1] + column[half]) / 2.0


def _median_rows(object values):
    """np.median(values, axis=0) of (P, 2) values, P >= 1."""
    cdef const f64* v = doubles(values, 2, "values")
    cdef Py_ssize_t P = dim(values, 0)
    if P < 1 or dim(values, 1) != 2:
        raise ValueError("values: (P, 2) with P >= 1 are needed")
    out = new_doubles(1, 2)
    column, work = new_doubles(1, P), new_doubles(1, P)
    _median_rows_c(v, P, fdata(out), fdata(column), fdata(work))
    return out


cdef tuple _shift_and_error_c(const f64* pairs, Py_ssize_t P):
    if P < 1:
        raise ValueError("pairs: (P, 2) with P >= 1 are needed")
    shift, error = new_doubles(1, 2), new_doubles(1, 2)
    deviation, column, work = new_doubles(2, P, 2), new_doubles(1, P), new_doubles(1, P)
    cdef f64* s = fdata(shift)
    cdef f64* e = fdata(error)
    cdef f64* d = fdata(deviation)
    cdef f64 sigma[2]
    cdef Py_ssize_t p, a
    _median_rows_c(pairs, P, s, fdata(column), fdata(work))
    for p in range(P):
        for a in range(2):
            d[p * 2 + a] = fabs(pairs[p * 2 + a] - s[a])
    _median_rows_c(d, P, sigma, fdata(column), fdata(work))
    for a in range(2):
        sigma[a] = 1.4826 * sigma[a]
        e[a] = sqrt(3.141592653589793 / 2.0) * sigma[a] / sqrt(<double>P)
    return shift, error


def _shift_and_error(object pairs):
    """(median shift, its standard error) of the displacements (P, 2): `estimate_motion`."""
    cdef const f64* p = doubles(pairs, 2, "pairs")
    if dim(pairs, 1) != 2:
        raise ValueError("pairs: (P, 2) are needed")
    return _shift_and_error_c(p, dim(pairs, 0))


cdef bint _expansion_fit_c(const f64* pairs, const i64* which, Py_ssize_t P,
                           const f64* previous, const f64* current, const f64* centre,
                           f64* lever, double* k_out, double* variance) noexcept nogil:
    cdef f64 mean_l[2]
    cdef f64 mean_d[2]
    cdef Py_ssize_t p, a, i, j
    cdef double height, norm = 0.0, cross = 0.0, k, rss = 0.0, e
    mean_l[0] = mean_l[1] = 0.0
    mean_d[0] = mean_d[1] = 0.0
    for p in range(P):
        i, j = which[p * 2], which[p * 2 + 1]
        height = sqrt(previous[i * 4 + 3] * current[j * 4 + 3])
        for a in range(2):
            lever[p * 2 + a] = height * (previous[i * 4 + a] + previous[i * 4 + 2 + a] / 2.0
                                         - centre[a])
            mean_l[a] += lever[p * 2 + a] / P
            mean_d[a] += pairs[p * 2 + a] / P
    for p in range(P):
        for a in range(2):
            lever[p * 2 + a] -= mean_l[a]
            norm += lever[p * 2 + a] * lever[p * 2 + a]
            cross += (pairs[p * 2 + a] - mean_d[a]) * lever[p * 2 + a]
    if not norm > 0.0:
        k_out[0] = 0.0
        variance[0] = 0.0
        return False
    k = cross / norm
    for p in range(P):
        for a in range(2):
            e = pairs[p * 2 + a] - mean_d[a] - k * lever[p * 2 + a]
            rss += e * e
    k_out[0] = k
    variance[0] = rss / py_imax(2 * P - 3, 1) / norm
    return True


def _expansion_fit(object pairs, object which, object previous, object current, object centre):
    """(found, k, its variance): with lever l = sqrt(h_prev h_cur) (previous centre - centre)
    and displacement d per pair and axis, both about their means over the pairs,
    k = sum(d l) / sum(l^2) and var k = sum((d - k l)^2) / (2 P - 3) / sum(l^2) (two intercepts
    and k); not found when the levers do not vary."""
    cdef const f64* d = doubles(pairs, 2, "pairs")
    cdef const i64* w = integers(which, 2, "which")
    cdef const f64* pv = doubles(previous, 2, "previous")
    cdef const f64* cu = doubles(current, 2, "current")
    cdef const f64* ce = doubles(centre, 1, "centre")
    cdef Py_ssize_t P = dim(pairs, 0)
    cdef double k, variance
    length(which, P, "which")
    lever = new_doubles(2, P, 2)
    found = _expansion_fit_c(d, w, P, pv, cu, ce, fdata(lever), &k, &variance)
    return found, k, variance


cdef inline bint _qualifies_c(double hp, double hc, double dx, double dy, double height_ratio,
                              double inverse_ratio, double* unit) noexcept nogil:
    """`_qualifies` given 1.0 / height_ratio (the same number, once a loop); sqrt(hp hc) in
    `unit`. (numba's `and` of the three tests, each evaluated: no side effect, no branch.)"""
    cdef double ratio = hc / py_max(hp, 1e-9)
    unit[0] = sqrt(hp * hc)
    return ((ratio < height_ratio) & (ratio > inverse_ratio)
            & (py_max(fabs(dx), fabs(dy)) < unit[0]))


def _qualifies(double hp, double hc, double dx, double dy, double height_ratio):
    """Step 1's test of a pair: heights hp (previous) and hc (current) within height_ratio
    of each other, the centre moved by (dx, dy) less than sqrt(hp hc) on each axis."""
    cdef double unit
    return _qualifies_c(hp, hc, dx, dy, height_ratio, 1.0 / height_ratio, &unit)


cdef inline double _iou_c(const f64* a, Py_ssize_t i, const f64* b,
                          Py_ssize_t j) noexcept nogil:
    cdef double iw = py_max(py_min(a[i * 4 + 0] + a[i * 4 + 2], b[j * 4 + 0] + b[j * 4 + 2])
                          - py_max(a[i * 4 + 0], b[j * 4 + 0]), 0.0)
    cdef double ih = py_max(py_min(a[i * 4 + 1] + a[i * 4 + 3], b[j * 4 + 1] + b[j * 4 + 3])
                          - py_max(a[i * 4 + 1], b[j * 4 + 1]), 0.0)
    cdef double inter = iw * ih
    cdef double union = a[i * 4 + 2] * a[i * 4 + 3] + b[j * 4 + 2] * b[j * 4 + 3] - inter
    return inter / union if union > 0 else 0.0


def _iou(object a, Py_ssize_t i, object b, Py_ssize_t j):
    """IoU of boxes a[i] and b[j], left, top, width, height (0 for boxes without area)."""
    cdef const f64* pa = doubles(a, 2, "a")
    cdef const f64* pb = doubles(b, 2, "b")
    if not (0 <= i < dim(a, 0) and 0 <= j < dim(b, 0)):
        raise IndexError("box index out of range")
    return _iou_c(pa, i, pb, j)


cdef tuple _estimate_dense_c(const f64* previous, Py_ssize_t N, const f64* current,
                             Py_ssize_t M, double height_ratio, double mode_radius,
                             double min_iou, Py_ssize_t min_pairs):
    cp_, cc_ = new_doubles(2, N, 2), new_doubles(2, M, 2)
    candidates_, unit_ = new_doubles(2, N * M, 2), new_doubles(1, N * M)
    cdef f64* cp = fdata(cp_)
    cdef f64* cc = fdata(cc_)
    cdef f64* candidates = fdata(candidates_)
    cdef f64* unit = fdata(unit_)
    cdef Py_ssize_t i, j, a, C = 0, P = 0
    cdef double dx, dy, root, inverse_ratio = 1.0 / height_ratio
    cdef f64 mode[2]
    for i in range(N):
        for a in range(2):
            cp[i * 2 + a] = previous[i * 4 + a] + previous[i * 4 + 2 + a] / 2.0
    for j in range(M):
        for a in range(2):
            cc[j * 2 + a] = current[j * 4 + a] + current[j * 4 + 2 + a] / 2.0
    for i in range(N):  # 1. candidates, in the order previous, then current
        for j in range(M):
            dx, dy = cc[j * 2] - cp[i * 2], cc[j * 2 + 1] - cp[i * 2 + 1]
            if _qualifies_c(previous[i * 4 + 3], current[j * 4 + 3], dx, dy, height_ratio,
                            inverse_ratio, &root):
                candidates[C * 2], candidates[C * 2 + 1] = dx, dy
                unit[C] = root
                C += 1
    if C < min_pairs:
        return False, zero_doubles(2, 0, 2), zero_integers(2, 0, 2)
    radius_ = new_doubles(1, C)
    cdef f64* radius = fdata(radius_)
    for i in range(C):
        radius[i] = mode_radius * unit[i]
    _mode_shift_c(candidates, C, radius, mode)  # 2. the mode
    moved_ = new_doubles(2, N, 4)  # 3. mutual best IoU after the mode, and the median
    cdef f64* moved = fdata(moved_)
    for i in range(N):
        moved[i * 4 + 0] = previous[i * 4 + 0] + mode[0]
        moved[i * 4 + 1] = previous[i * 4 + 1] + mode[1]
        moved[i * 4 + 2] = previous[i * 4 + 2]
        moved[i * 4 + 3] = previous[i * 4 + 3]
    overlap_, best_prev_ = new_doubles(2, N, M), new_integers(1, M)
    cdef f64* overlap = fdata(overlap_)
    cdef i64* best_prev = idata(best_prev_)
    for i in range(N):
        for j in range(M):
            overlap[i * M + j] = _iou_c(moved, i, current, j)
    if N == 0 or M == 0:
        raise ValueError("attempt to get argmax of an empty sequence")
    for j in range(M):
        best_prev[j] = argmax_strided(overlap + j, N, M)
    pairs_, which_ = new_doubles(2, N, 2), new_integers(2, N, 2)
    cdef f64* pairs = fdata(pairs_)
    cdef i64* which = idata(which_)
    for i in range(N):
        j = argmax_strided(overlap + i * M, M, 1)
        if best_prev[j] == i and overlap[i * M + j] > min_iou:
            pairs[P * 2], pairs[P * 2 + 1] = cc[j * 2] - cp[i * 2], cc[j * 2 + 1] - cp[i * 2 + 1]
            which[P * 2], which[P * 2 + 1] = i, j
            P += 1
    if P < min_pairs:
        return False, zero_doubles(2, 0, 2), zero_integers(2, 0, 2)
    if P < N:
        return True, pairs_[:P], which_[:P]
    return True, pairs_, which_


cdef int check_boxes(object a, str name) except -1:
    doubles(a, 2, name)
    if dim(a, 1) != 4:
        raise ValueError(f"{name}: boxes (N, 4) are needed")
    return 0


def _estimate_dense(object previous, object current, double height_ratio, double mode_radius,
                    double min_iou, Py_ssize_t min_pairs):
    """Steps 1-3 over every pair of boxes: (found, the matched pairs' displacements, their
    (previous, current) box indices)."""
    check_boxes(previous, "previous")
    check_boxes(current, "current")
    return _estimate_dense_c(fdata(previous), dim(previous, 0), fdata(current),
                             dim(current, 0), height_ratio, mode_radius, min_iou, min_pairs)


def _camera_dense(object previous, object current, object centre, double height_ratio,
                  double mode_radius, double min_iou, Py_ssize_t min_pairs):
    """`estimate_camera` over every pair in one call: (found, shift, its standard error,
    whether k was fitted, k, its variance), the steps of `matched_pairs` (`_estimate_dense`),
    `_shift_and_error` and `_expansion_fit`."""
    check_boxes(previous, "previous")
    check_boxes(current, "current")
    cdef const f64* ce = doubles(centre, 1, "centre")
    cdef double k, variance
    found, pairs, which = _estimate_dense_c(fdata(previous), dim(previous, 0), fdata(current),
                                            dim(current, 0), height_ratio, mode_radius,
                                            min_iou, min_pairs)
    if not found:
        return False, zero_doubles(1, 2), zero_doubles(1, 2), False, 0.0, 0.0
    cdef Py_ssize_t P = dim(pairs, 0)
    shift, error = _shift_and_error_c(fdata(pairs), P)
    lever = new_doubles(2, P, 2)
    fitted = _expansion_fit_c(fdata(pairs), idata(which), P, fdata(previous), fdata(current),
                              ce, fdata(lever), &k, &variance)
    return True, shift, error, fitted, k, variance


def _candidates(object i, object j, object hp, object hc, object cp, object cc,
                double height_ratio, i64 M):
    """Step 1 on the pairs (i, j) within reach: the candidate shifts and their units (box
    heights), in the dense form's order (by previous box, then current)."""
    cdef const i64* pi = integers(i, 1, "i")
    cdef const i64* pj = integers(j, 1, "j")
    cdef const f64* h_p = doubles(hp, 1, "hp")
    cdef const f64* h_c = doubles(hc, 1, "hc")
    cdef const f64* c_p = doubles(cp, 2, "cp")
    cdef const f64* c_c = doubles(cc, 2, "cc")
    cdef Py_ssize_t E = dim(i, 0), e, t, K = 0
    cdef i64 a, b
    cdef double root, inverse_ratio = 1.0 / height_ratio
    length(j, E, "j")
    keep_ = new_integers(1, E)
    cdef i64* keep = idata(keep_)
    for e in range(E):
        a, b = pi[e], pj[e]
        if _qualifies_c(h_p[a], h_c[b], c_c[b * 2] - c_p[a * 2], c_c[b * 2 + 1] - c_p[a * 2 + 1],
                        height_ratio, inverse_ratio, &root):
            keep[K] = e
            K += 1
    key_, order_, work_ = new_integers(1, K), new_integers(1, K), new_integers(1, K)
    cdef i64* key = idata(key_)
    cdef i64* order = idata(order_)
    for t in range(K):
        key[t] = pi[keep[t]] * M + pj[keep[t]]
    # (numba's default-kind argsort here: the keys are distinct pairs, so any sort agrees)
    argsort_stable(key, K, order, idata(work_))
    candidates_, unit_ = new_doubles(2, K, 2), new_doubles(1, K)
    cdef f64* candidates = fdata(candidates_)
    cdef f64* unit = fdata(unit_)
    for t in range(K):
        e = keep[order[t]]
        a, b = pi[e], pj[e]
        candidates[t * 2] = c_c[b * 2] - c_p[a * 2]
        candidates[t * 2 + 1] = c_c[b * 2 + 1] - c_p[a * 2 + 1]
        unit[t] = sqrt(h_p[a] * h_c[b])
    return candidates_, unit_


def _mutual_shifts(object p, object c, object moved, object current, object cp, object cc,
                   double min_iou):
    """Step 3 on the overlapping pairs (p, c) of moved previous and current boxes: the
    displacement of every pair that is each other's best IoU (ties: the lower index, as
    argmax), above min_iou, in the order of the previous boxes, and the pairs' (previous,
    current) indices."""
    cdef const i64* pp = integers(p, 1, "p")
    cdef const i64* pc = integers(c, 1, "c")
    check_boxes(moved, "moved")
    check_boxes(current, "current")
    cdef const f64* mv = fdata(moved)
    cdef const f64* cu = fdata(current)
    cdef const f64* c_p = doubles(cp, 2, "cp")
    cdef const f64* c_c = doubles(cc, 2, "cc")
    cdef Py_ssize_t E = dim(p, 0), N = dim(moved, 0), M = dim(current, 0), e, k, P = 0
    cdef i64 b
    length(c, E, "c")
    overlap_ = new_doubles(1, E)
    cdef f64* overlap = fdata(overlap_)
    for e in range(E):
        overlap[e] = _iou_c(mv, pp[e], cu, pc[e])
    best_iou_, best_cur_, seen_ = new_doubles(1, N), new_integers(1, N), new_booleans(1, N)
    other_value_, best_prev_ = new_doubles(1, M), new_integers(1, M)
    seen_m_ = new_booleans(1, M)
    cdef f64* best_iou = fdata(best_iou_)
    cdef i64* best_cur = idata(best_cur_)
    cdef i64* best_prev = idata(best_prev_)
    _first_best_c(pp, overlap, pc, E, N, best_iou, best_cur, bdata(seen_))
    _first_best_c(pc, overlap, pp, E, M, fdata(other_value_), best_prev, bdata(seen_m_))
    shifts_, which_ = new_doubles(2, N, 2), new_integers(2, N, 2)
    cdef f64* shifts = fdata(shifts_)
    cdef i64* which = idata(which_)
    for k in range(N):
        if best_prev[best_cur[k]] == k and best_iou[k] > min_iou:
            b = best_cur[k]
            shifts[P * 2] = c_c[b * 2] - c_p[k * 2]
            shifts[P * 2 + 1] = c_c[b * 2 + 1] - c_p[k * 2 + 1]
            which[P * 2], which[P * 2 + 1] = k, b
            P += 1
    if P < N:
        return shifts_[:P], which_[:P]
    return shifts_, which_


cdef int _mode_shift_c(const f64* candidates, Py_ssize_t C, const f64* radius,
                       f64* out) except -1:
    """`_mode_shift` of C candidates (C, 2) into out (2,)."""
    cdef Py_ssize_t k, best = -1
    cdef i64 top
    cdef double key, key_best
    if C == 0:
        raise ValueError("zero-size array to reduction operation maximum which has no "
                         "identity")
    x_, y_, votes_ = new_doubles(1, C), new_doubles(1, C), new_integers(1, C)
    cdef f64* x = fdata(x_)
    cdef f64* y = fdata(y_)
    cdef i64* votes = idata(votes_)
    for k in range(C):
        x[k], y[k] = candidates[k * 2], candidates[k * 2 + 1]
    _votes_c(x, y, radius, C, votes)
    top = votes[0]
    for k in range(1, C):
        if votes[k] > top:
            top = votes[k]
    for k in range(C):
        if votes[k] != top:
            continue
        if best < 0:
            best = k
            continue
        key = fabs(candidates[k * 2]) + fabs(candidates[k * 2 + 1])
        key_best = fabs(candidates[best * 2]) + fabs(candidates[best * 2 + 1])
        if key < key_best or (key == key_best and (
                candidates[k * 2] < candidates[best * 2] or (
                    candidates[k * 2] == candidates[best * 2]
                    and candidates[k * 2 + 1] < candidates[best * 2 + 1]))):
            best = k
    out[0], out[1] = candidates[best * 2], candidates[best * 2 + 1]
    return 0


def _mode_shift(object candidates, object radius):
    """The candidate shift with the most votes (`_votes`). Ties go to the smallest
    |dx| + |dy|, then the lowest (dx, dy), so that the order of the boxes, which is no
    information, does not matter."""
    cdef const f64* c = doubles(candidates, 2, "candidates")
    cdef const f64* r = doubles(radius, 1, "radius")
    cdef Py_ssize_t C = dim(candidates, 0)
    if dim(candidates, 1) != 2:
        raise ValueError("candidates: (C, 2) are needed")
    length(radius, C, "radius")
    out = new_doubles(1, 2)
    _mode_shift_c(c, C, r, fdata(out))
    return out


cdef int _votes_c(const f64* x, const f64* y, const f64* radius, Py_ssize_t C,
                  i64* votes) except -1:
    """`_votes` of C candidates into votes (C,)."""
    cdef Py_ssize_t k, t, s, a, b, strips
    cdef double low, tall, xa, ya, ra, mx, my, limit
    cdef i64 last, own, near
    for k in range(C):
        votes[k] = 1
    if C == 0 or not nan_max(radius, C) > 0:
        return 0
    low = nan_min(y, C)
    tall = py_max(nan_max(radius, C), (nan_max(y, C) - low) / C)  # any height is exact
    strip_, first_, order_, work_ = (new_integers(1, C), new_integers(1, C),
                                     new_integers(1, C), new_integers(1, C))
    cdef i64* strip = idata(strip_)
    cdef i64* first = idata(first_)
    cdef i64* order = idata(order_)
    cdef i64* work = idata(work_)
    for k in range(C):
        strip[k] = <i64>floor((y[k] - low) / tall)
    argsort_stable(x, C, first, work)  # by x, then (stably) by strip
    key_, by_strip_ = new_integers(1, C), new_integers(1, C)
    cdef i64* key = idata(key_)
    cdef i64* by_strip = idata(by_strip_)
    for k in range(C):
        key[k] = strip[first[k]]
    argsort_stable(key, C, by_strip, work)
    for k in range(C):
        order[k] = first[by_strip[k]]
    strips = strip[order[C - 1]] + 1
    start_ = zero_integers(1, strips + 1)
    cdef i64* start = idata(start_)
    for k in range(C):
        start[strip[k] + 1] += 1
    for s in range(1, strips + 1):
        start[s] += start[s - 1]
    xs_, ys_, rs_, counted_ = (new_doubles(1, C), new_doubles(1, C), new_doubles(1, C),
                               new_integers(1, C))
    cdef f64* xs = fdata(xs_)
    cdef f64* ys = fdata(ys_)
    cdef f64* rs = fdata(rs_)
    cdef i64* counted = idata(counted_)
    for k in range(C):
        xs[k], ys[k], rs[k] = x[order[k]], y[order[k]], radius[order[k]]
        counted[k] = 1
    for s in range(strips):
        for a in range(start[s], start[s + 1]):
            xa, ya, ra = xs[a], ys[a], rs[a]
            # a margin far above rounding, so that no pair within reach is left out
            mx, my = 1e-9 * (fabs(xa) + ra), 1e-9 * (fabs(ya) + fabs(low) + ra)
            last = py_imin(<i64>floor((ya + ra + my - low) / tall), strips - 1)
            own = 0
            for t in range(s, last + 1):
                if t == s:
                    b = a + 1
                else:
                    b = start[t] + search_left(xs + start[t], start[t + 1] - start[t],
                                               xa - ra - mx)
                while b < start[t + 1] and xs[b] < xa + ra + mx:
                    limit = py_min(ra, rs[b])
                    near = py_max(fabs(xs[b] - xa), fabs(ys[b] - ya)) < limit
                    own += near
                    counted[b] += near
                    b += 1
            counted[a] += own
    for k in range(C):
        votes[order[k]] = counted[k]
    return 0


def _votes(object x, object y, object radius):
    """Per candidate a, the candidates b (a included) with |x_b - x_a| and |y_b - y_a| both
    below min(radius_a, radius_b). The candidates are binned in strips of y as tall as the
    largest radius (taller if that made more strips than candidates) and sorted by x within a
    strip; each pair is looked at once, from the one in the lower strip (or earlier in x),
    over its own strip and those within its radius above. The people who moved alike make a
    dense cluster of shifts, and a sweep along x alone compared each of them with every
    candidate in that column."""
    # (not on the tracker's path, which calls the cdef form from `_mode_shift`: columns of an
    # array are taken as they come)
    x = np.ascontiguousarray(x, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64)
    radius = np.ascontiguousarray(radius, dtype=np.float64)
    cdef const f64* px = doubles(x, 1, "x")
    cdef const f64* py = doubles(y, 1, "y")
    cdef const f64* pr = doubles(radius, 1, "radius")
    cdef Py_ssize_t C = dim(x, 0)
    length(y, C, "y")
    length(radius, C, "radius")
    votes = new_integers(1, C)
    _votes_c(px, py, pr, C, idata(votes))
    return votes
