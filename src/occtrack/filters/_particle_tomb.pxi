# Kernels of occtrack.filters.particle_tomb (included by _filters.pyx): the highway's particle
# multi-Bernoulli tracker, one call per stage of a step, one pass over the particles each.
# Python's min/max are written out (`_min`, `_max`: the first argument unless the second is
# strictly smaller / larger), as numba compiled them, so signed zeros and NaN come out alike.

from libc.math cimport sqrt, exp

from occtrack.models._highway_sensor cimport _both_orders_c  # the sensor's two-ends term

from occtrack._arrays cimport py_imax, py_imin, py_max, py_min
from occtrack._arrays cimport (f64, i64, b8, doubles, integers, booleans, dim, new_doubles,
                               zero_doubles, new_integers, zero_integers)


ctypedef cnp.float32_t f32


cdef inline f32* _floats(object a, int ndim, str name) except NULL:
    """a's data, if a is a C-contiguous float32 array of `ndim` dimensions."""
    if not cnp.PyArray_Check(a):
        raise TypeError(f"{name}: a numpy array is needed, not {type(a).__name__}")
    cdef cnp.ndarray arr = <cnp.ndarray>a
    if (cnp.PyArray_TYPE(arr) != cnp.NPY_FLOAT32 or cnp.PyArray_NDIM(arr) != ndim
            or not cnp.PyArray_IS_C_CONTIGUOUS(arr)):
        raise TypeError(f"{name}: a C-contiguous {ndim}-d float32 array is needed, not "
                        f"{arr.dtype} {arr.ndim}-d"
                        f"{'' if cnp.PyArray_IS_C_CONTIGUOUS(arr) else ' (not contiguous)'}")
    return <f32*>cnp.PyArray_DATA(arr)


cdef inline f64* _row_doubles(object a, int ndim, str name, Py_ssize_t* stride) except NULL:
    """a's data, if a is a float64 array of `ndim` (2 or 3) dimensions whose rows (a[i]) are
    each C-contiguous, one every `stride` float64 (set): a C-contiguous array, or a slice
    a[:, :k] of one (as `_advance` is given the Poisson part's first particles)."""
    if not cnp.PyArray_Check(a):
        raise TypeError(f"{name}: a numpy array is needed, not {type(a).__name__}")
    cdef cnp.ndarray arr = <cnp.ndarray>a
    if cnp.PyArray_TYPE(arr) != cnp.NPY_FLOAT64 or cnp.PyArray_NDIM(arr) != ndim:
        raise TypeError(f"{name}: a {ndim}-d float64 array is needed, not {arr.dtype} "
                        f"{arr.ndim}-d")
    cdef Py_ssize_t item = 8, d, row
    for d in range(ndim - 1, 0, -1):
        if cnp.PyArray_DIM(arr, d) > 1 and cnp.PyArray_STRIDE(arr, d) != item:
            raise TypeError(f"{name}: rows that are C-contiguous are needed")
        item *= cnp.PyArray_DIM(arr, d)
    row = cnp.PyArray_STRIDE(arr, 0)
    if cnp.PyArray_DIM(arr, 0) > 1 and (row < item or row % 8):
        raise TypeError(f"{name}: rows that do not overlap, whole float64 apart, are needed")
    stride[0] = row // 8 if cnp.PyArray_DIM(arr, 0) > 1 else item // 8
    return <f64*>cnp.PyArray_DATA(arr)


# ---- the kernels -------------------------------------------------------------------------------

cdef double _row_sum_c(const f64* a, Py_ssize_t n) noexcept nogil:
    """np.sum of n contiguous values, in numpy's order (see `_row_sum`)."""
    cdef double res, r0, r1, r2, r3, r4, r5, r6, r7
    cdef Py_ssize_t i, stop, half
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
        r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
        i = 8
        stop = n - n % 8
        while i < stop:
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return _row_sum_c(a, half) + _row_sum_c(a + half, n - half)


cdef void _advance_c(f64* x, Py_ssize_t x_stride, f64* w, Py_ssize_t w_stride,
                     const f64* direction, Py_ssize_t rows, Py_ssize_t n, double half,
                     double survival, f64* alive) noexcept nogil:
    """`_advance` on rows one every `x_stride` (x) and `w_stride` (w) float64."""
    cdef Py_ssize_t i, k
    cdef double total, left, rear
    cdef bint forward
    cdef f64* xi
    cdef f64* wi
    for i in range(rows):
        xi = x + i * x_stride
        wi = w + i * w_stride
        total = 0.0
        forward = direction[i] > 0
        for k in range(n):
            left = xi[k * 3] + xi[k * 3 + 2]
            xi[k * 3] = left
            rear = left if forward else -(left + xi[k * 3 + 1])
            if rear >= half:
                wi[k] = 0.0
            else:
                wi[k] *= survival
                total += wi[k]
        alive[i] = total


cdef void _window_c(const f64* row, Py_ssize_t n, double lo, double hi, Py_ssize_t* first,
                    Py_ssize_t* end) noexcept nogil:
    """`_window` of the n sorted values at row: [first, end)."""
    cdef Py_ssize_t a = 0, b = n, mid
    while a < b:
        mid = (a + b) // 2
        if row[mid] < lo:
            a = mid + 1
        else:
            b = mid
    first[0] = a
    b = n
    while a < b:
        mid = (a + b) // 2
        if row[mid] <= hi:
            a = mid + 1
        else:
            b = mid
    end[0] = a


cdef void _systematic_c(const f64* weights, Py_ssize_t rows, Py_ssize_t n, const f64* u0,
                        Py_ssize_t n_out, i64* idx) noexcept nogil:
    """`_systematic` into idx (rows, n_out)."""
    cdef Py_ssize_t r, k, j
    cdef double total, scale, c, u
    cdef const f64* wr
    for r in range(rows):
        wr = weights + r * n
        total = 0.0
        for k in range(n):
            total += wr[k]
        scale = 1.0 / total if total > 0 else 0.0
        k = 0
        c = wr[0] * scale
        for j in range(n_out):
            u = (u0[r] + <double>j) / <double>n_out
            while c <= u and k < n - 1:
                k += 1
                c += wr[k] * scale
            idx[r * n_out + j] = k


cdef inline double _reflect1_c(double v, double lo, double hi) noexcept nogil:
    if v < lo:
        v = 2 * lo - v
    if v > hi:
        v = 2 * hi - v
    return py_min(py_max(v, lo), hi)


cdef void _liu_west_c(const f64* x, const f64* w, Py_ssize_t n, const i64* idx,
                      Py_ssize_t rows, Py_ssize_t n_out, const f32* eps, double h,
                      const f64* direction, double min_length, double max_length,
                      double min_speed, double max_speed, f64* out) noexcept nogil:
    """`_liu_west` into out (rows, n_out, 3); x (rows, n, 3), w (rows, n)."""
    cdef double a = sqrt(1.0 - h * h)
    cdef double mean[3]
    cdef double cov[9]
    cdef double chol[9]
    cdef double total, wk, dd, t, sign, move
    cdef Py_ssize_t r, k, d, e, f, j, src
    cdef const f64* xr
    cdef const f64* wr
    cdef f64* o
    for d in range(9):
        chol[d] = 0.0
    for r in range(rows):
        xr = x + r * n * 3
        wr = w + r * n
        total = 0.0
        for k in range(n):
            total += wr[k]
        for d in range(3):
            mean[d] = 0.0
        for k in range(n):
            for d in range(3):
                mean[d] += wr[k] * xr[k * 3 + d]
        for d in range(3):
            mean[d] = mean[d] / total
        for d in range(9):
            cov[d] = 0.0
        for k in range(n):
            wk = wr[k] / total
            for d in range(3):
                dd = xr[k * 3 + d] - mean[d]
                for e in range(d + 1):
                    cov[d * 3 + e] += wk * dd * (xr[k * 3 + e] - mean[e])
        for d in range(3):  # Cholesky of the 3 x 3, lower; the jitter keeps it positive
            for e in range(d + 1):
                t = cov[d * 3 + e] + (1e-10 if d == e else 0.0)
                for f in range(e):
                    t -= chol[d * 3 + f] * chol[e * 3 + f]
                if d == e:
                    chol[d * 3 + e] = sqrt(py_max(t, 0.0))
                else:
                    chol[d * 3 + e] = t / chol[e * 3 + e] if chol[e * 3 + e] > 0 else 0.0
        sign = direction[r]
        for j in range(n_out):
            src = idx[r * n_out + j]
            o = out + (r * n_out + j) * 3
            for d in range(3):
                move = 0.0
                for e in range(d + 1):
                    move += chol[d * 3 + e] * <double>eps[(r * n_out + j) * 3 + e]
                o[d] = a * xr[src * 3 + d] + (1.0 - a) * mean[d] + h * move
            o[1] = _reflect1_c(o[1], min_length, max_length)
            o[2] = sign * _reflect1_c(sign * o[2], min_speed, max_speed)


# ---- the entries particle_tomb.py calls (the tests call _row_sum, _advance, _liu_west) -------

def _row_sum(object a):
    """np.sum of a contiguous 1-D array, in numpy's order: pairwise over blocks of 128, each
    block summed in 8 interleaved partial sums. Keeping the order keeps the results of the
    numpy code this replaced, to the last bit."""
    cdef const f64* p = doubles(a, 1, "a")
    return _row_sum_c(p, dim(a, 0))


def _advance(object x, object w, object direction, double half, double survival):
    """Constant speed for one step, then P_S: `survival` while the rear is on the section, else
    0, applied to the weights in place. Returns each row's surviving weight.

    x (rows, n, 3) and w (rows, n) may be slices [:, :n] of C-contiguous arrays (each row
    contiguous)."""
    cdef Py_ssize_t xs, ws
    cdef f64* xp = _row_doubles(x, 3, "x", &xs)
    cdef f64* wp = _row_doubles(w, 2, "w", &ws)
    cdef Py_ssize_t rows = dim(w, 0), n = dim(w, 1)
    cdef const f64* dp = doubles(direction, 1, "direction")
    alive = new_doubles(1, rows)
    _advance_c(xp, xs, wp, ws, dp, rows, n, half, survival, <f64*>cnp.PyArray_DATA(alive))
    return alive


def _predict(object x, object w, object r, object track_direction, object ux, object uw,
             Py_ssize_t nu, object sobol, object shift, object direction, double half,
             double survival, double min_speed, double max_speed, double min_length,
             double max_length, double birth_weight):
    """Step 1 in place: tracks and the Poisson part's first `nu` particles per lane move and
    survive (`_advance`), each track's existence takes its surviving weight and its weights
    are normalised again; the last particles of each lane become the births, cars that
    entered within the last step (front up to one step past the entry). Births are a scrambled
    Sobol set shifted by `shift[lane]` (randomised quasi-Monte Carlo: unbiased like plain
    draws, but it covers the box of (speed, length, entry fraction) more evenly)."""
    cdef f64* xp = doubles(x, 3, "x")
    cdef f64* wp = doubles(w, 2, "w")
    cdef f64* rp = doubles(r, 1, "r")
    cdef const f64* tdir = doubles(track_direction, 1, "track_direction")
    cdef f64* uxp = doubles(ux, 3, "ux")
    cdef f64* uwp = doubles(uw, 2, "uw")
    cdef const f64* sob = doubles(sobol, 2, "sobol")
    cdef const f64* sh = doubles(shift, 2, "shift")
    cdef const f64* dirp = doubles(direction, 1, "direction")
    cdef Py_ssize_t rows = dim(w, 0), N = dim(w, 1), n_r = dim(r, 0)
    cdef Py_ssize_t lanes = dim(uw, 0), per_lane = dim(uw, 1)
    cdef Py_ssize_t i, k, lane, e
    cdef double scale, d, speed, length, front
    cdef double u[3]
    alive_ = new_doubles(1, rows if rows > lanes else lanes)  # both calls' rows
    cdef f64* alive = <f64*>cnp.PyArray_DATA(alive_)
    _advance_c(xp, N * 3, wp, N, tdir, rows, N, half, survival, alive)
    for i in range(n_r):
        rp[i] *= alive[i]
        scale = alive[i] if alive[i] > 0 else 1.0
        for k in range(N):
            wp[i * N + k] /= scale
    _advance_c(uxp, per_lane * 3, uwp, per_lane, dirp, lanes, nu, half, survival, alive)
    for lane in range(lanes):
        d = dirp[lane]
        for k in range(nu, per_lane):
            for e in range(3):
                # (a + b) mod 1 for a, b in [0, 1): the subtraction is exact, as fmod is
                u[e] = sob[(k - nu) * 3 + e] + sh[lane * 3 + e]
                if u[e] >= 1.0:
                    u[e] -= 1.0
            speed = min_speed + (max_speed - min_speed) * u[0]
            length = min_length + (max_length - min_length) * u[1]
            front = -half + speed * u[2]
            uxp[(lane * per_lane + k) * 3] = front - length if d > 0 else -front
            uxp[(lane * per_lane + k) * 3 + 1] = length
            uxp[(lane * per_lane + k) * 3 + 2] = d * speed
            uwp[lane * per_lane + k] = birth_weight


def _reorder(object ux, object uw, object order):
    """Each lane's particles put in `order[lane]`."""
    cdef f64* uxp = doubles(ux, 3, "ux")
    cdef f64* uwp = doubles(uw, 2, "uw")
    cdef const i64* op = integers(order, 2, "order")
    cdef Py_ssize_t lanes = dim(uw, 0), per_lane = dim(uw, 1), lane, k, d, src
    xs_ = new_doubles(1, per_lane * 3)
    ws_ = new_doubles(1, per_lane)
    cdef f64* xs = <f64*>cnp.PyArray_DATA(xs_)
    cdef f64* ws = <f64*>cnp.PyArray_DATA(ws_)
    cdef f64* xl
    cdef f64* wl
    cdef const i64* ol
    for lane in range(lanes):
        xl = uxp + lane * per_lane * 3
        wl = uwp + lane * per_lane
        ol = op + lane * per_lane
        for k in range(per_lane):
            src = ol[k]
            for d in range(3):
                xs[k * 3 + d] = xl[src * 3 + d]
            ws[k] = wl[src]
        for k in range(per_lane * 3):
            xl[k] = xs[k]
        for k in range(per_lane):
            wl[k] = ws[k]


def _window(object row, double lo, double hi):
    """The slice [first, end) of the sorted `row` whose values lie in [lo, hi]."""
    cdef const f64* p = doubles(row, 1, "row")
    cdef Py_ssize_t first, end
    _window_c(p, dim(row, 0), lo, hi, &first, &end)
    return first, end


def _associate(object x, object w, object r, object lane, object ux, object uw,
               object visible, object hidden, double pd, object z_lane, object z_left,
               object z_right, object z_lh, object z_rh, object clutter, double sigma,
               double tail, double reach, double shift):
    """Steps 2-3 after the occlusion handler: miss terms of every particle (flat: the Poisson
    part's particles, then the tracks'), each track's miss weight, the Poisson part's hit
    weights and each measurement's new-object weight, the gated (track, measurement) pairs
    with their particles' hit weights, and the hit weight of every pair.

    The Poisson particles a measurement can have come from are the slice of its lane's
    (sorted by left end) whose left end lies within `reach` of the measured shape: compared
    after adding `shift` times the lane number to both sides, as in the flat search over all
    lanes this replaced. Pairs are those of one lane whose particle ends come within `reach`
    of the measured ends, grouped by track."""
    cdef const f64* xp = doubles(x, 3, "x")
    cdef const f64* wp = doubles(w, 2, "w")
    cdef const f64* rp = doubles(r, 1, "r")
    cdef const i64* lp = integers(lane, 1, "lane")
    cdef const f64* uxp = doubles(ux, 3, "ux")
    cdef const f64* uwp = doubles(uw, 2, "uw")
    cdef const f64* vis = doubles(visible, 1, "visible")
    cdef const f64* hid = doubles(hidden, 1, "hidden")
    cdef const i64* zl = integers(z_lane, 1, "z_lane")
    cdef const f64* zleft = doubles(z_left, 2, "z_left")
    cdef const f64* zright = doubles(z_right, 2, "z_right")
    cdef const b8* zlh = booleans(z_lh, 1, "z_lh")
    cdef const b8* zrh = booleans(z_rh, 1, "z_rh")
    cdef const f64* clut = doubles(clutter, 1, "clutter")
    cdef Py_ssize_t n = dim(w, 0), N = dim(w, 1), lanes = dim(uw, 0), per_lane = dim(uw, 1)
    cdef Py_ssize_t m = dim(z_lane, 0), K = dim(visible, 0)
    cdef Py_ssize_t i, j, k, p, a, b, base, width, pairs, lj, f0
    cdef double inv = 1.0 / sigma, pv, off, lo, hi, wv, zl0, zl1, zr0, zr1, s
    cdef double l_min, l_max, r_min, r_max, left, right
    cdef bint lh, rh

    miss_ = new_doubles(1, K)
    cdef f64* miss = <f64*>cnp.PyArray_DATA(miss_)
    for k in range(K):
        pv = pd * vis[k]
        miss[k] = 1.0 - pv + pv * hid[k]
    base = lanes * per_lane
    row_ = new_doubles(1, N)
    cdef f64* row = <f64*>cnp.PyArray_DATA(row_)
    w_miss_ = new_doubles(1, n)
    cdef f64* w_miss = <f64*>cnp.PyArray_DATA(w_miss_)
    for i in range(n):
        for k in range(N):
            row[k] = wp[i * N + k] * miss[base + i * N + k]
        w_miss[i] = 1.0 - rp[i] + rp[i] * _row_sum_c(row, N)

    # the Poisson part
    first_ = zero_integers(1, m)
    count_ = zero_integers(1, m)
    cdef i64* first = <i64*>cnp.PyArray_DATA(first_)
    cdef i64* count = <i64*>cnp.PyArray_DATA(count_)
    key_ = new_doubles(1, per_lane)
    cdef f64* key = <f64*>cnp.PyArray_DATA(key_)
    for j in range(m):
        lj = zl[j]
        off = shift * <double>lj
        for k in range(per_lane):
            key[k] = uxp[(lj * per_lane + k) * 3] + off
        lo = zleft[j * 2] - reach
        hi = py_max(zleft[j * 2 + 1], zright[j * 2 + 1]) + reach
        _window_c(key, per_lane, lo + off, hi + off, &a, &b)
        first[j] = a
        count[j] = b - a
    width = 1
    for j in range(m):
        if count[j] > width:
            width = count[j]
    hit_u_ = zero_doubles(2, m, width)
    e_ = new_doubles(1, m)
    w_new_ = new_doubles(1, m)
    cdef f64* hit_u = <f64*>cnp.PyArray_DATA(hit_u_)
    cdef f64* e = <f64*>cnp.PyArray_DATA(e_)
    cdef f64* w_new = <f64*>cnp.PyArray_DATA(w_new_)
    cdef f64* hj
    for j in range(m):
        lj, f0 = zl[j], first[j]
        zl0, zl1, lh = zleft[j * 2], zleft[j * 2 + 1], zlh[j]
        zr0, zr1, rh = zright[j * 2], zright[j * 2 + 1], zrh[j]
        hj = hit_u + j * width
        for k in range(count[j]):
            p = f0 + k
            wv = uwp[lj * per_lane + p] * vis[lj * per_lane + p]
            lo = uxp[(lj * per_lane + p) * 3]
            if (k > 0 and lo == uxp[(lj * per_lane + p - 1) * 3]
                    and uxp[(lj * per_lane + p) * 3 + 1] == uxp[(lj * per_lane + p - 1) * 3 + 1]
                    and wv == uwp[lj * per_lane + p - 1] * vis[lj * per_lane + p - 1]):
                hj[k] = hj[k - 1]  # a copy (resampling), beside its original
                continue
            hj[k] = wv * _both_orders_c(lo, lo + uxp[(lj * per_lane + p) * 3 + 1], zl0, zl1, lh,
                                        zr0, zr1, rh, inv, tail)
        e[j] = pd * _row_sum_c(hj, width)
        # A floor far below any real weight: outside the clutter's support (e.g. a car
        # entering) w_new may be 0, which loopy belief propagation cannot divide by.
        w_new[j] = py_max(clut[j] + e[j], 1e-12)

    # the tracks: gate, then score the pairs
    gate_ = new_integers(1, 2 * n * m)
    cdef i64* gate = <i64*>cnp.PyArray_DATA(gate_)
    pairs = 0
    for i in range(n):
        l_min = l_max = xp[i * N * 3]
        r_min = r_max = xp[i * N * 3] + xp[i * N * 3 + 1]
        for k in range(1, N):
            left = xp[(i * N + k) * 3]
            right = left + xp[(i * N + k) * 3 + 1]
            l_min = py_min(l_min, left)
            l_max = py_max(l_max, left)
            r_min = py_min(r_min, right)
            r_max = py_max(r_max, right)
        for j in range(m):
            if (lp[i] == zl[j] and l_min - reach <= zleft[j * 2 + 1]
                    and l_max + reach >= zleft[j * 2] and r_min - reach <= zright[j * 2 + 1]
                    and r_max + reach >= zright[j * 2]):
                gate[2 * pairs] = i
                gate[2 * pairs + 1] = j
                pairs += 1
    ti_ = new_integers(1, pairs)
    mj_ = new_integers(1, pairs)
    cdef i64* ti = <i64*>cnp.PyArray_DATA(ti_)
    cdef i64* mj = <i64*>cnp.PyArray_DATA(mj_)
    for p in range(pairs):
        ti[p] = gate[2 * p]
        mj[p] = gate[2 * p + 1]
    hit_pair_ = new_doubles(2, pairs, N)
    w_hit_ = zero_doubles(2, n, m)
    cdef f64* hit_pair = <f64*>cnp.PyArray_DATA(hit_pair_)
    cdef f64* w_hit = <f64*>cnp.PyArray_DATA(w_hit_)
    cdef f64* hp
    for p in range(pairs):
        i, j = ti[p], mj[p]
        zl0, zl1, lh = zleft[j * 2], zleft[j * 2 + 1], zlh[j]
        zr0, zr1, rh = zright[j * 2], zright[j * 2 + 1], zrh[j]
        hp = hit_pair + p * N
        for k in range(N):
            lo = xp[(i * N + k) * 3]
            hp[k] = (wp[i * N + k] * vis[base + i * N + k]) * _both_orders_c(
                lo, lo + xp[(i * N + k) * 3 + 1], zl0, zl1, lh, zr0, zr1, rh, inv, tail)
        w_hit[i * m + j] = rp[i] * pd * _row_sum_c(hp, N)
    return w_miss_, miss_, w_new_, e_, first_, hit_u_, ti_, mj_, hit_pair_, w_hit_


def _update(object x, object w, object r, object uw, object miss, object w_miss,
            object p_miss, object p_hit, object w_hit, object ti, object mj, object hit_pair,
            object p_new, object e, object w_new, double pd):
    """Step 4 in place: each track becomes the marginal-weighted mixture of its miss and hit
    posteriors (existence and normalised weights), the Poisson part keeps its miss term.
    Returns the existence of the track each measurement would start. (x is not read.)"""
    cdef f64* wp = doubles(w, 2, "w")
    cdef f64* rp = doubles(r, 1, "r")
    cdef f64* uwp = doubles(uw, 2, "uw")
    cdef const f64* missp = doubles(miss, 1, "miss")
    cdef const f64* wm = doubles(w_miss, 1, "w_miss")
    cdef const f64* pm = doubles(p_miss, 1, "p_miss")
    cdef const f64* ph = doubles(p_hit, 2, "p_hit")
    cdef const f64* wh = doubles(w_hit, 2, "w_hit")
    cdef const i64* tip = integers(ti, 1, "ti")
    cdef const i64* mjp = integers(mj, 1, "mj")
    cdef const f64* hpp = doubles(hit_pair, 2, "hit_pair")
    cdef const f64* pn = doubles(p_new, 1, "p_new")
    cdef const f64* ep = doubles(e, 1, "e")
    cdef const f64* wn = doubles(w_new, 1, "w_new")
    cdef Py_ssize_t n = dim(w, 0), N = dim(w, 1), lanes = dim(uw, 0), per_lane = dim(uw, 1)
    cdef Py_ssize_t mh = dim(p_hit, 1), mw = dim(w_hit, 1), pairs = dim(ti, 0)
    cdef Py_ssize_t m = dim(e, 0), base = lanes * per_lane, i, j, k, p, q, lane
    cdef double coef, scale, r_post
    post_ = new_doubles(1, n * N)
    head_ = new_doubles(1, N)
    rest_ = new_doubles(1, N)
    cdef f64* post = <f64*>cnp.PyArray_DATA(post_)
    cdef f64* head = <f64*>cnp.PyArray_DATA(head_)
    cdef f64* rest = <f64*>cnp.PyArray_DATA(rest_)
    for i in range(n):
        coef = pm[i] * rp[i] / py_max(wm[i], 1e-300)
        for k in range(N):
            post[i * N + k] = coef * wp[i * N + k] * missp[base + i * N + k]
    # A track's pairs are summed as np.add.reduceat summed them: the first pair's term plus
    # the running sum of the others' terms.
    p = 0
    while p < pairs:
        i = tip[p]
        q = p
        while q < pairs and tip[q] == i:
            j = mjp[q]
            scale = ph[i * mh + j] / py_max(wh[i * mw + j], 1e-300) * rp[i] * pd
            if q == p:
                for k in range(N):
                    head[k] = scale * hpp[q * N + k]
            elif q == p + 1:
                for k in range(N):
                    rest[k] = scale * hpp[q * N + k]
            else:
                for k in range(N):
                    rest[k] += scale * hpp[q * N + k]
            q += 1
        if q == p + 1:
            for k in range(N):
                post[i * N + k] += head[k]
        else:
            for k in range(N):
                post[i * N + k] += head[k] + rest[k]
        p = q
    for i in range(n):
        r_post = _row_sum_c(post + i * N, N)
        rp[i] = py_min(py_max(r_post, 0.0), 1.0)
        scale = r_post if r_post > 0 else 1.0
        for k in range(N):
            wp[i * N + k] = post[i * N + k] / scale
    for lane in range(lanes):
        for k in range(per_lane):
            uwp[lane * per_lane + k] *= missp[lane * per_lane + k]
    r_born_ = new_doubles(1, m)
    cdef f64* r_born = <f64*>cnp.PyArray_DATA(r_born_)
    for j in range(m):
        r_born[j] = pn[j] * ep[j] / py_max(wn[j], 1e-300)
    return r_born_


def _degenerate(object w, object r, double threshold):
    """Tracks whose effective sample size 1 / sum w^2 is below `threshold` (and r > 0)."""
    cdef const f64* wp = doubles(w, 2, "w")
    cdef const f64* rp = doubles(r, 1, "r")
    cdef Py_ssize_t n = dim(w, 0), N = dim(w, 1), i, k, count = 0
    sq_ = new_doubles(1, N)
    all_ = new_integers(1, n)
    cdef f64* sq = <f64*>cnp.PyArray_DATA(sq_)
    cdef i64* rows = <i64*>cnp.PyArray_DATA(all_)
    for i in range(n):
        for k in range(N):
            sq[k] = wp[i * N + k] * wp[i * N + k]
        if 1.0 / py_max(_row_sum_c(sq, N), 1e-300) < threshold and rp[i] > 0:
            rows[count] = i
            count += 1
    out = new_integers(1, count)
    cdef i64* op = <i64*>cnp.PyArray_DATA(out)
    for i in range(count):
        op[i] = rows[i]
    return out


def _recycle(object ux, object uw, Py_ssize_t nu, object u0):
    """The Poisson part's particles of each lane, resampled (systematic) to `nu` of equal
    weight, their total kept."""
    cdef f64* uxp = doubles(ux, 3, "ux")
    cdef f64* uwp = doubles(uw, 2, "uw")
    cdef const f64* up = doubles(u0, 1, "u0")
    cdef Py_ssize_t lanes = dim(uw, 0), per_lane = dim(uw, 1), lane, k, d, src
    cdef double total
    idx_ = new_integers(1, lanes * nu)
    xs_ = new_doubles(1, nu * 3)
    cdef i64* idx = <i64*>cnp.PyArray_DATA(idx_)
    cdef f64* xs = <f64*>cnp.PyArray_DATA(xs_)
    cdef f64* xl
    _systematic_c(uwp, lanes, per_lane, up, nu, idx)
    for lane in range(lanes):
        total = _row_sum_c(uwp + lane * per_lane, per_lane)
        xl = uxp + lane * per_lane * 3
        for k in range(nu):
            src = idx[lane * nu + k]
            for d in range(3):
                xs[k * 3 + d] = xl[src * 3 + d]
        for k in range(nu * 3):
            xl[k] = xs[k]
        for k in range(nu):
            uwp[lane * per_lane + k] = total / <double>nu


def _systematic(object weights, object u0, Py_ssize_t n_out):
    """Systematic resampling of each row with offset u0[row]: index k is drawn for the points
    (u0 + j) / n_out that fall in its slice of the cumulative weight."""
    cdef const f64* wp = doubles(weights, 2, "weights")
    cdef const f64* up = doubles(u0, 1, "u0")
    cdef Py_ssize_t rows = dim(weights, 0)
    idx = new_integers(2, rows, n_out)
    _systematic_c(wp, rows, dim(weights, 1), up, n_out, <i64*>cnp.PyArray_DATA(idx))
    return idx


def _reflect1(double v, double lo, double hi):
    """v reflected into [lo, hi] at the nearer bound (once each), then clipped."""
    return _reflect1_c(v, lo, hi)


def _liu_west(object x, object w, object idx, object eps, double h, object direction,
              double min_length, double max_length, double min_speed, double max_speed):
    """The Liu-West move of resampled particles (see HighwayTracker._resample_move): out[r, j]
    = a x[r, idx[r, j]] + (1 - a) mean_r + h chol(cov_r) eps[r, j], a = sqrt(1 - h^2), the
    length and the speed reflected into the prior's support. x (rows, n, 3) float64, w
    (rows, n), idx (rows, n_out) int64, eps (rows, n_out, 3) float32, direction (rows,)."""
    cdef const f64* xp = doubles(x, 3, "x")
    cdef const f64* wp = doubles(w, 2, "w")
    cdef const i64* ip = integers(idx, 2, "idx")
    cdef const f32* ep = _floats(eps, 3, "eps")
    cdef const f64* dp = doubles(direction, 1, "direction")
    cdef Py_ssize_t rows = dim(idx, 0), n_out = dim(idx, 1)
    out = new_doubles(3, rows, n_out, 3)
    _liu_west_c(xp, wp, dim(x, 1), ip, rows, n_out, ep, h, dp, min_length, max_length,
                min_speed, max_speed, <f64*>cnp.PyArray_DATA(out))
    return out


def _resample_move(object x, object w, object u0, object eps, double h, object direction,
                   double min_length, double max_length, double min_speed, double max_speed):
    """`_systematic` then `_liu_west`, in one call."""
    cdef const f64* xp = doubles(x, 3, "x")
    cdef const f64* wp = doubles(w, 2, "w")
    cdef const f64* up = doubles(u0, 1, "u0")
    cdef const f32* ep = _floats(eps, 3, "eps")
    cdef const f64* dp = doubles(direction, 1, "direction")
    cdef Py_ssize_t rows = dim(w, 0), n = dim(w, 1), n_out = dim(eps, 1)
    idx_ = new_integers(1, rows * n_out)
    cdef i64* idx = <i64*>cnp.PyArray_DATA(idx_)
    _systematic_c(wp, rows, n, up, n_out, idx)
    out = new_doubles(3, rows, n_out, 3)
    _liu_west_c(xp, wp, dim(x, 1), idx, rows, n_out, ep, h, dp, min_length, max_length,
                min_speed, max_speed, <f64*>cnp.PyArray_DATA(out))
    return out
