# The kernels of occtrack.models.highway_sensor (included by _models.pyx): the maths is in
# highway_sensor.py. The end terms (`_ndtr_c`, `_end_term_c`, `_near_c`, `_both_orders_c`) are
# inline in _highway_sensor.pxd, for the particle tracker's extension to call too.


def _ndtr(double x):
    """Phi(x). Beyond 9 (below -39) erfc rounds Phi to exactly 1 (0) in double precision, so
    those are returned without calling it: the same numbers, for less work where a hidden
    part is wide against sigma."""
    return _ndtr_c(x)


def _end_term(double e, double z_lo, double z_hi, bint hidden, double inv_sigma, double tail):
    """f(e): N(z; e, sigma^2) for a seen end, P(e + noise in [z_lo, z_hi]) for a hidden one;
    0 beyond `tail` standard deviations."""
    return _end_term_c(e, z_lo, z_hi, hidden, inv_sigma, tail)


def _near(double e, double z_lo, double z_hi, bint hidden, double inv_sigma, double tail):
    """Whether `_end_term` is computed rather than taken as 0 (within `tail` sigma)."""
    return _near_c(e, z_lo, z_hi, hidden, inv_sigma, tail)


def _both_orders(double lo, double hi, double zl0, double zl1, bint lh, double zr0,
                 double zr1, bint rh, double inv, double tail):
    """p(z | ends lo, hi) summed over the two orders of the two ends; a product is computed
    only where both its ends are near (most particles are far from most measurements, and
    the reversed order is far for all but the shortest shapes)."""
    return _both_orders_c(lo, hi, zl0, zl1, lh, zr0, zr1, rh, inv, tail)


def _likelihood(object left, object right, object z_left, object z_right, object left_hidden,
                object right_hidden, double sigma, double tail):
    """`_both_orders` of every (particle row, particle)."""
    cdef const f64* L = doubles(left, 2, "left")
    cdef const f64* R = doubles(right, 2, "right")
    cdef const f64* zl = doubles(z_left, 2, "z_left")
    cdef const f64* zr = doubles(z_right, 2, "z_right")
    cdef const b8* lh_ = booleans(left_hidden, 1, "left_hidden")
    cdef const b8* rh_ = booleans(right_hidden, 1, "right_hidden")
    cdef Py_ssize_t rows = dim(left, 0), n = dim(left, 1), p, k
    if (dim(right, 0) != rows or dim(right, 1) != n or dim(z_left, 0) < rows
            or dim(z_left, 1) != 2 or dim(z_right, 0) < rows or dim(z_right, 1) != 2
            or dim(left_hidden, 0) < rows or dim(right_hidden, 0) < rows):
        raise ValueError("_likelihood: left, right (P, N), z_left, z_right (P, 2), "
                         "left_hidden, right_hidden (P,) are needed")
    cdef cnp.ndarray out_ = new_doubles(2, rows, n)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef double inv = 1.0 / sigma, zl0, zl1, zr0, zr1
    cdef bint lh, rh
    for p in range(rows):
        zl0, zl1, lh = zl[p * 2], zl[p * 2 + 1], lh_[p]
        zr0, zr1, rh = zr[p * 2], zr[p * 2 + 1], rh_[p]
        for k in range(n):
            out[p * n + k] = _both_orders_c(L[p * n + k], R[p * n + k], zl0, zl1, lh, zr0, zr1,
                                            rh, inv, tail)
    return out_


def _hit_weights(object particles, object weights, object row, object first, object count,
                 Py_ssize_t width, object z_left, object z_right, object left_hidden,
                 object right_hidden, double sigma, double tail):
    """weights[row[p], first[p] + k] times `_both_orders` of particle (row[p], first[p] + k)
    (left end, length, ...) against measurement p, for k < count[p]; 0 up to `width`."""
    cdef const f64* x = doubles(particles, 3, "particles")
    cdef const f64* w = doubles(weights, 2, "weights")
    cdef const i64* row_ = integers(row, 1, "row")
    cdef const i64* first_ = integers(first, 1, "first")
    cdef const i64* count_ = integers(count, 1, "count")
    cdef const f64* zl = doubles(z_left, 2, "z_left")
    cdef const f64* zr = doubles(z_right, 2, "z_right")
    cdef const b8* lh_ = booleans(left_hidden, 1, "left_hidden")
    cdef const b8* rh_ = booleans(right_hidden, 1, "right_hidden")
    cdef Py_ssize_t pairs = dim(row, 0), N = dim(particles, 1), D = dim(particles, 2)
    cdef Py_ssize_t Nw = dim(weights, 1), p, k
    if (dim(first, 0) < pairs or dim(count, 0) < pairs or dim(z_left, 0) < pairs
            or dim(z_left, 1) != 2 or dim(z_right, 0) < pairs or dim(z_right, 1) != 2
            or dim(left_hidden, 0) < pairs or dim(right_hidden, 0) < pairs or D < 2):
        raise ValueError("_hit_weights: row, first, count, z_left, z_right (pairs, 2), "
                         "left_hidden, right_hidden of every pair, particles (R, N, >= 2) "
                         "are needed")
    cdef cnp.ndarray out_ = zero_doubles(2, pairs, width)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef double inv = 1.0 / sigma, zl0, zl1, zr0, zr1, lo, hi
    cdef bint lh, rh
    cdef i64 r, f0
    for p in range(pairs):
        zl0, zl1, lh = zl[p * 2], zl[p * 2 + 1], lh_[p]
        zr0, zr1, rh = zr[p * 2], zr[p * 2 + 1], rh_[p]
        r, f0 = row_[p], first_[p]
        for k in range(count_[p]):
            lo = x[(r * N + f0 + k) * D]
            hi = lo + x[(r * N + f0 + k) * D + 1]
            out[p * width + k] = w[r * Nw + f0 + k] * _both_orders_c(lo, hi, zl0, zl1, lh, zr0,
                                                                    zr1, rh, inv, tail)
    return out_


def _occluded_parts(object scan_lane, object ext_lo, object ext_hi, object distances):
    """Lane k's hidden parts: the union of the angles [lo, hi] / d covered by the shapes of
    lanes 0 .. k-1 (touching intervals merged), scaled back by d_k, concatenated over the lanes
    (lo/hi[start[k]:start[k + 1]]). One sort of all shapes by angle, then one merging walk per
    lane over the shapes of its nearer lanes."""
    cdef const i64* lane_ = integers(scan_lane, 1, "scan_lane")
    cdef const f64* e_lo = doubles(ext_lo, 1, "ext_lo")
    cdef const f64* e_hi = doubles(ext_hi, 1, "ext_hi")
    cdef const f64* dist = doubles(distances, 1, "distances")
    cdef Py_ssize_t lanes = dim(distances, 0), m = dim(scan_lane, 0), j, k, t, c
    if dim(ext_lo, 0) < m or dim(ext_hi, 0) < m:
        raise ValueError("_occluded_parts: an extent per shape is needed")
    cdef cnp.ndarray a_lo_ = new_doubles(1, m), a_hi_ = new_doubles(1, m)
    cdef cnp.ndarray order_ = new_integers(1, m), work_ = new_integers(1, m)
    cdef f64* a_lo = <f64*>cnp.PyArray_DATA(a_lo_)
    cdef f64* a_hi = <f64*>cnp.PyArray_DATA(a_hi_)
    cdef i64* order = <i64*>cnp.PyArray_DATA(order_)
    cdef double d
    for j in range(m):
        d = dist[lane_[j]]
        a_lo[j] = e_lo[j] / d
        a_hi[j] = e_hi[j] / d
    argsort_stable(a_lo, m, order, <i64*>cnp.PyArray_DATA(work_))
    cdef Py_ssize_t size = max(lanes * m, 1)
    cdef cnp.ndarray lo_ = new_doubles(1, size), hi_ = new_doubles(1, size)
    cdef cnp.ndarray start_ = zero_integers(1, lanes + 1)
    cdef f64* lo = <f64*>cnp.PyArray_DATA(lo_)
    cdef f64* hi = <f64*>cnp.PyArray_DATA(hi_)
    cdef i64* start = <i64*>cnp.PyArray_DATA(start_)
    cdef bint have
    cdef double run_lo, run_hi
    c = 0
    for k in range(lanes):
        start[k] = c
        d = dist[k]
        have = False
        run_lo = run_hi = 0.0
        for t in range(m):
            j = order[t]
            if lane_[j] >= k:
                continue
            if have and a_lo[j] <= run_hi:
                run_hi = max(run_hi, a_hi[j])
                continue
            if have:
                lo[c] = run_lo * d
                hi[c] = run_hi * d
                c += 1
            have = True
            run_lo = a_lo[j]
            run_hi = a_hi[j]
        if have:
            lo[c] = run_lo * d
            hi[c] = run_hi * d
            c += 1
    start[lanes] = c
    return lo_[:c], hi_[:c], start_


def _hidden_probability(object lane, object left, object right, object lo, object hi,
                        object start, double sigma, double reach):
    """Parts of lane k are lo/hi[start[k]:start[k + 1]], sorted and disjoint (a few). A
    particle equal to the one before it (resampling makes copies, and sorting puts them side
    by side) takes its q without the normal CDFs."""
    cdef const i64* lane_ = integers(lane, 1, "lane")
    cdef const f64* L = doubles(left, 1, "left")
    cdef const f64* R = doubles(right, 1, "right")
    cdef const f64* lo_ = doubles(lo, 1, "lo")
    cdef const f64* hi_ = doubles(hi, 1, "hi")
    cdef const i64* start_ = integers(start, 1, "start")
    cdef Py_ssize_t n = dim(lane, 0), i, j
    if dim(left, 0) < n or dim(right, 0) < n:
        raise ValueError("_hidden_probability: lane, left and right of one length are needed")
    cdef cnp.ndarray q_ = zero_doubles(1, n)
    cdef f64* q = <f64*>cnp.PyArray_DATA(q_)
    cdef double inv = 1.0 / sigma, li, ri, a, b, total
    cdef i64 k, first
    for i in range(n):
        k = lane_[i]
        first = start_[k]
        li, ri = L[i], R[i]
        if i > 0 and li == L[i - 1] and ri == R[i - 1] and k == lane_[i - 1]:
            q[i] = q[i - 1]
            continue
        total = 0.0
        # from the last part, skip those starting beyond reach of the left end, then add
        # while a part can hold the right end (ends grow with the index: parts are disjoint)
        for j in range(start_[k + 1] - 1, first - 1, -1):
            if lo_[j] > li + reach:
                continue
            if hi_[j] < ri - reach:
                break
            a, b = lo_[j], hi_[j]
            total += ((_ndtr_c((b - li) * inv) - _ndtr_c((a - li) * inv))
                      * (_ndtr_c((b - ri) * inv) - _ndtr_c((a - ri) * inv)))
        q[i] = min(max(total, 0.0), 1.0)
    return q_


cdef inline double _overlap_c(double a0, double a1, double b0, double b1) noexcept nogil:
    return max(min(a1, b1) - max(a0, b0), 0.0)


def _overlap(double a0, double a1, double b0, double b1):
    """Length of [a0, a1] intersected with [b0, b1] (0 if they do not meet)."""
    return _overlap_c(a0, a1, b0, b1)


cdef inline bint _hw_less(double a, double b) noexcept nogil:
    """numba's order of a float sort: a < b, NaN last."""
    return a < b or (b != b and a == a)


def _clutter_density(object left, object right, object left_hidden, object right_hidden,
                     double half, double lmin, double lmax, double c):
    """c times: for two seen ends, 1 if the left end is on the section and the length within
    [lmin, lmax]; for one hidden end, the length of its interval that such a shape allows;
    for two, the area of {(s, e) in the two intervals: lmin <= e - s <= lmax}, exact by the
    trapezoid rule on the breakpoints of the piecewise-linear overlap."""
    cdef const f64* L = doubles(left, 2, "left")
    cdef const f64* R = doubles(right, 2, "right")
    cdef const b8* lh = booleans(left_hidden, 1, "left_hidden")
    cdef const b8* rh = booleans(right_hidden, 1, "right_hidden")
    cdef Py_ssize_t m = dim(left, 0), j, t, s
    if (dim(left, 1) != 2 or dim(right, 0) < m or dim(right, 1) != 2
            or dim(left_hidden, 0) < m or dim(right_hidden, 0) < m):
        raise ValueError("_clutter_density: left, right (M, 2) and their hidden flags (M,) "
                         "are needed")
    cdef cnp.ndarray out_ = new_doubles(1, m)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef double knots[6]
    cdef double l0, l1, r0, r1, seen, gap, v, s0, s1, top, w0, w1, key
    for j in range(m):
        l0, l1, r0, r1 = L[j * 2], L[j * 2 + 1], R[j * 2], R[j * 2 + 1]
        seen = 1.0 if -half <= l0 <= half else 0.0
        if not lh[j] and not rh[j]:
            gap = r0 - l0
            v = seen if lmin <= gap <= lmax else 0.0
        elif not rh[j]:
            v = _overlap_c(max(l0, -half), min(l1, half), r0 - lmax, r0 - lmin)
        elif not lh[j]:
            v = seen * _overlap_c(r0, r1, l0 + lmin, l0 + lmax)
        else:
            s0, s1 = max(l0, -half), min(l1, half)
            top = max(s0, s1)
            knots[0], knots[1], knots[2] = s0, s1, r0 - lmax
            knots[3], knots[4], knots[5] = r0 - lmin, r1 - lmax, r1 - lmin
            for t in range(6):
                knots[t] = min(max(knots[t], s0), top)
            # knots.sort(): numba sorts so few by insertion, stably (reproduced here)
            for t in range(1, 6):
                key = knots[t]
                s = t
                while s > 0 and _hw_less(key, knots[s - 1]):
                    knots[s] = knots[s - 1]
                    s -= 1
                knots[s] = key
            v = 0.0
            for t in range(5):
                w0 = _overlap_c(r0, r1, knots[t] + lmin, knots[t] + lmax)
                w1 = _overlap_c(r0, r1, knots[t + 1] + lmin, knots[t + 1] + lmax)
                v += 0.5 * (w1 + w0) * (knots[t + 1] - knots[t])
        out[j] = c * v
    return out_
