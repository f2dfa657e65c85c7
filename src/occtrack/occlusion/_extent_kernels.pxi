# Kernels of occtrack.occlusion.extent_kernels, the highway's object-wise occlusion handlers
# (the maths: that module's docstring and occtrack.occlusion.highway). Particles arrive flat;
# the particles of one track are contiguous.

def track_extents(owner, lane, weights, a_left, a_right, Py_ssize_t n):
    """Lane and expected extent (angles) of each of the n tracks."""
    cdef const i64* own = integers(owner, 1, "owner")
    cdef Py_ssize_t K = dim(owner, 0), p, i
    cdef const i64* ln = integers(lane, 1, "lane")
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const f64* al = doubles(a_left, 1, "a_left")
    cdef const f64* ar = doubles(a_right, 1, "a_right")
    length(lane, K, "lane")
    length(weights, K, "weights")
    length(a_left, K, "a_left")
    length(a_right, K, "a_right")
    total_, sum_l_, sum_r_ = zero_doubles(1, n), zero_doubles(1, n), zero_doubles(1, n)
    track_lane_ = zero_integers(1, n)
    cdef f64* total = <f64*>cnp.PyArray_DATA(total_)
    cdef f64* sum_l = <f64*>cnp.PyArray_DATA(sum_l_)
    cdef f64* sum_r = <f64*>cnp.PyArray_DATA(sum_r_)
    cdef i64* track_lane = <i64*>cnp.PyArray_DATA(track_lane_)
    cdef double wp, t
    for p in range(K):
        i = own[p]
        if i < 0:
            continue
        if i >= n:
            raise IndexError(f"owner: track {i} of {n}")
        wp = w[p]
        total[i] += wp
        sum_l[i] += wp * al[p]
        sum_r[i] += wp * ar[p]
        track_lane[i] = ln[p]
    for i in range(n):
        t = py_max(total[i], DBL_MIN)
        sum_l[i] /= t
        sum_r[i] /= t
    return track_lane_, sum_l_, sum_r_


def expval_visibility(owner, lane, a_left, a_right, existence, occ_lane, occ_l, occ_r,
                      double beta, double min_visible):
    """v = max(prod_i (1 - r_i (1 - e^(-beta cover_l)) (1 - e^(-beta cover_r))), v_min) over
    the tracks i of nearer lanes whose expected extent covers both ends' sides. Each run of
    particles sharing owner and lane is tested against an occluder by its hull first."""
    cdef const i64* own = integers(owner, 1, "owner")
    cdef Py_ssize_t k = dim(owner, 0), start, end, p, i
    cdef const i64* ln = integers(lane, 1, "lane")
    cdef const f64* al = doubles(a_left, 1, "a_left")
    cdef const f64* ar = doubles(a_right, 1, "a_right")
    cdef const f64* r = doubles(existence, 1, "existence")
    cdef const i64* o_lane = integers(occ_lane, 1, "occ_lane")
    cdef const f64* o_l = doubles(occ_l, 1, "occ_l")
    cdef const f64* o_r = doubles(occ_r, 1, "occ_r")
    length(lane, k, "lane")
    length(a_left, k, "a_left")
    length(a_right, k, "a_right")
    cdef Py_ssize_t n_occ = dim(occ_lane, 0)
    length(existence, n_occ, "existence")
    length(occ_l, n_occ, "occ_l")
    length(occ_r, n_occ, "occ_r")
    log_open_ = zero_doubles(1, k)
    cdef f64* log_open = <f64*>cnp.PyArray_DATA(log_open_)
    cdef i64 run_lane
    cdef double max_l, min_r, cover_l, cover_r, hidden
    start = 0
    while start < k:
        end = start + 1
        while end < k and own[end] == own[start] and ln[end] == ln[start]:
            end += 1
        run_lane = ln[start]
        max_l = -INFINITY
        min_r = INFINITY
        for p in range(start, end):
            max_l = py_max(max_l, al[p])
            min_r = py_min(min_r, ar[p])
        for i in range(n_occ):
            if o_lane[i] >= run_lane or o_l[i] >= max_l or o_r[i] <= min_r:
                continue
            for p in range(start, end):
                cover_l = al[p] - o_l[i]
                cover_r = o_r[i] - ar[p]
                if cover_l > 0 and cover_r > 0:
                    hidden = r[i] * -expm1(-beta * cover_l) * -expm1(-beta * cover_r)
                    log_open[p] += log1p(-py_min(hidden, 1.0 - 1e-12))
        start = end
    visible_ = new_doubles(1, k)
    cdef f64* visible = <f64*>cnp.PyArray_DATA(visible_)
    for p in range(k):
        visible[p] = py_max(exp(log_open[p]), min_visible)
    return visible_


def grid_visibility(owner, lane, weights, a_left, a_right, existence, Py_ssize_t n,
                    Py_ssize_t n_lanes, double c0, double step, double top, Py_ssize_t cells):
    """The visibility grid: a cell seen from lane k is open with probability prod_i (1 - r_i
    P(track i covers it)) over the tracks of lanes nearer than k; a particle is as visible as
    the most open cell whose centre it covers (the cell nearest its middle if it covers
    none), 1 outside the grid."""
    cdef const i64* own = integers(owner, 1, "owner")
    cdef Py_ssize_t k = dim(owner, 0), p, i, c, j
    cdef const i64* ln = integers(lane, 1, "lane")
    cdef const f64* w = doubles(weights, 1, "weights")
    cdef const f64* al = doubles(a_left, 1, "a_left")
    cdef const f64* ar = doubles(a_right, 1, "a_right")
    cdef const f64* r = doubles(existence, 1, "existence")
    length(lane, k, "lane")
    length(weights, k, "weights")
    length(a_left, k, "a_left")
    length(a_right, k, "a_right")
    length(existence, n, "existence")
    first_, last_ = new_integers(1, k), new_integers(1, k)
    diff_, total_ = zero_doubles(1, n * (cells + 1)), zero_doubles(1, n)
    track_lane_ = zero_integers(1, n)
    log_open_, open_ = zero_doubles(1, n_lanes * cells), new_doubles(1, n_lanes * cells)
    visible_ = new_doubles(1, k)
    cdef i64* first = <i64*>cnp.PyArray_DATA(first_)
    cdef i64* last = <i64*>cnp.PyArray_DATA(last_)
    cdef f64* diff = <f64*>cnp.PyArray_DATA(diff_)
    cdef f64* total = <f64*>cnp.PyArray_DATA(total_)
    cdef i64* track_lane = <i64*>cnp.PyArray_DATA(track_lane_)
    cdef f64* log_open = <f64*>cnp.PyArray_DATA(log_open_)
    cdef f64* opened = <f64*>cnp.PyArray_DATA(open_)
    cdef f64* visible = <f64*>cnp.PyArray_DATA(visible_)
    cdef double t, covered, p_cover, behind, best
    cdef i64 f, g, row
    for p in range(k):
        first[p] = py_imax(<i64>ceil((al[p] - c0) / step), 0)
        last[p] = py_imin(<i64>floor((ar[p] - c0) / step), cells - 1)
    for p in range(k):
        i = own[p]
        if i < 0:
            continue
        if i >= n:
            raise IndexError(f"owner: track {i} of {n}")
        total[i] += w[p]
        track_lane[i] = ln[p]
        if first[p] <= last[p]:
            diff[i * (cells + 1) + first[p]] += w[p]
            diff[i * (cells + 1) + last[p] + 1] -= w[p]
    for i in range(n):
        if track_lane[i] < 0 or track_lane[i] >= n_lanes:
            raise IndexError(f"lane: {track_lane[i]} of {n_lanes}")
        t = py_max(total[i], DBL_MIN)
        covered = 0.0
        for c in range(cells):
            covered += diff[i * (cells + 1) + c]
            p_cover = py_min(py_max(covered / t, 0.0), 1.0)
            log_open[track_lane[i] * cells + c] += log1p(-py_min(r[i] * p_cover, 1.0 - 1e-12))
    # open probability seen from lane k: occluders in lanes 0 .. k-1 only
    for c in range(cells):
        behind = 0.0
        for j in range(n_lanes):
            opened[j * cells + c] = exp(behind)
            behind += log_open[j * cells + c]
    for p in range(k):
        visible[p] = 1.0
        if ar[p] < c0 or al[p] > top:
            continue
        f, g = first[p], last[p]
        if f > g:
            f = py_imin(py_imax(<i64>floor((0.5 * (al[p] + ar[p]) - c0) / step + 0.5), 0),
                      cells - 1)
            g = f
        best = 0.0
        row = ln[p]
        if row < 0 or row >= n_lanes:
            raise IndexError(f"lane: {row} of {n_lanes}")
        for c in range(f, g + 1):
            best = py_max(best, opened[row * cells + c])
        visible[p] = best
    return visible_
