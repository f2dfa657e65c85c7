# The kernels of occtrack.models.box (included by _models.pyx): the maths is in box.py.
# Layouts, C order: edges z, zhat, observed (M, 2, 2) -> [(j * 2 + axis) * 2 + side]; S
# (K, 2, 2, 2) -> [((k * 2 + axis) * 2 + r) * 2 + c]; means (K, 2, 3) -> [(k * 2 + axis) * 3
# + a]; covs (K, 2, 3, 3) -> [((k * 2 + axis) * 3 + a) * 3 + b]; border (2, 2) -> [axis * 2 +
# side].

cdef double _BOX_MIN_HEIGHT = 4.0  # box.MIN_HEIGHT
cdef double _BOX_LOG_2PI = 1.8378770664093453  # densities.gaussian.LOG_2PI: log(2 pi)


cdef int _box_shape(object a, int ndim, str name, Py_ssize_t d1, Py_ssize_t d2=0,
                    Py_ssize_t d3=0) except -1:
    """Check a's (checked) dimensions after the first: (., d1[, d2[, d3]])."""
    cdef Py_ssize_t want[3]
    cdef int i
    want[0], want[1], want[2] = d1, d2, d3
    for i in range(1, ndim):
        if dim(a, i) != want[i - 1]:
            raise ValueError(f"{name}: shape {a.shape} has the wrong trailing dimensions")
    return 0


cdef inline double _box_var(const f64* means, i64 k, double edge_noise) noexcept nogil:
    """(e h_k)^2: the edge noise variance of component k, h_k = max(2 s_vertical, MIN_HEIGHT)."""
    cdef double sd = edge_noise * max(2.0 * means[k * 6 + 5], _BOX_MIN_HEIGHT)
    return sd * sd


cdef void _censored_c(const b8* observed, Py_ssize_t M, b8* out) noexcept nogil:
    """`_censored` into out (4,)."""
    cdef Py_ssize_t j, e
    for e in range(4):
        out[e] = False
    for j in range(M):
        for e in range(4):
            if not observed[j * 4 + e]:
                out[e] = True


cdef bint _every_edge_measured_c(const b8* observed, Py_ssize_t M) noexcept nogil:
    cdef b8 censored[4]
    _censored_c(observed, M, censored)
    return not (censored[0] or censored[1] or censored[2] or censored[3])


def _loglik_pairs(object zhat, object S, object z, object observed, object k, object j,
                  object log_phi, object log_peak, double tail_weight=0.0,
                  double tail_scale=1.0, object d2_out=None, object m_out=None,
                  object tail_of=None):
    """log N of the measured edges of z_j under component k, per pair, plus the log
    probability log_phi[k, c] + log_peak[k] of each edge on the border, c the edge's column
    among the censored ones (`_censored(observed)`, in (axis, low or high) order); S^-1 and
    the log-determinants in closed form per component and axis, once. With a tail weight eps
    > 0, plus the heavy tail's log(1 - eps + eps kappa^-m exp(d^2 (1 - kappa^-2) / 2))
    (`models.edge_tail`), d^2 the Mahalanobis distance of the m measured edges, for the
    components where tail_of (K,) is True (None: all); d2_out and m_out (E,), when given,
    receive d^2 and m."""
    cdef const f64* zh = doubles(zhat, 3, "zhat")
    cdef const f64* Sp = doubles(S, 4, "S")
    cdef const f64* zp = doubles(z, 3, "z")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* kp = integers(k, 1, "k")
    cdef const i64* jp = integers(j, 1, "j")
    cdef const f64* phi = doubles(log_phi, 2, "log_phi")
    cdef const f64* peak = doubles(log_peak, 1, "log_peak")
    _box_shape(zhat, 3, "zhat", 2, 2)
    _box_shape(S, 4, "S", 2, 2, 2)
    _box_shape(z, 3, "z", 2, 2)
    _box_shape(observed, 3, "observed", 2, 2)
    cdef Py_ssize_t K = dim(zhat, 0), M = dim(observed, 0), E = dim(k, 0)
    cdef Py_ssize_t width = dim(log_phi, 1)
    cdef b8 censored[4]
    cdef i64 column[4]
    cdef i64 count = 0
    cdef Py_ssize_t i, axis, side, e
    cdef i64 ke, je
    cdef double a, b, c, r0, r1, total, d2, m, x, y
    cdef bint o0, o1
    cdef f64* d2p = NULL
    cdef f64* mp = NULL
    if d2_out is not None:
        d2p = <f64*>doubles(d2_out, 1, "d2_out")
        mp = <f64*>doubles(m_out, 1, "m_out")
        length(d2_out, dim(k, 0), "d2_out")
        length(m_out, dim(k, 0), "m_out")
    cdef bint tail = tail_weight > 0.0
    cdef const b8* tail_ok = NULL
    if tail_of is not None:
        tail_ok = booleans(tail_of, 1, "tail_of")
        length(tail_of, dim(zhat, 0), "tail_of")
    cdef double log_keep = log1p(-tail_weight) if tail else 0.0
    cdef double log_weight = log(tail_weight) if tail else 0.0
    cdef double log_scale = log(tail_scale) if tail else 0.0
    cdef double stretch = 0.5 * (1.0 - 1.0 / (tail_scale * tail_scale)) if tail else 0.0
    _censored_c(o, M, censored)
    for axis in range(2):
        for side in range(2):
            column[axis * 2 + side] = 0
            if censored[axis * 2 + side]:
                column[axis * 2 + side] = count
                count += 1
    cdef cnp.ndarray log_det_ = new_doubles(2, K, 2)
    cdef cnp.ndarray log_a_ = new_doubles(2, K, 2)
    cdef cnp.ndarray log_c_ = new_doubles(2, K, 2)
    cdef f64* log_det = <f64*>cnp.PyArray_DATA(log_det_)
    cdef f64* log_a = <f64*>cnp.PyArray_DATA(log_a_)
    cdef f64* log_c = <f64*>cnp.PyArray_DATA(log_c_)
    for i in range(K):
        for axis in range(2):
            a = Sp[(i * 2 + axis) * 4]
            b = Sp[(i * 2 + axis) * 4 + 1]
            c = Sp[(i * 2 + axis) * 4 + 3]
            log_det[i * 2 + axis] = log(a * c - b * b) + 2.0 * _BOX_LOG_2PI
            log_a[i * 2 + axis] = log(a) + _BOX_LOG_2PI
            log_c[i * 2 + axis] = log(c) + _BOX_LOG_2PI
    cdef cnp.ndarray out_ = new_doubles(1, E)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    for e in range(E):
        ke, je = kp[e], jp[e]
        total = 0.0
        d2 = 0.0
        m = 0.0
        for axis in range(2):
            a = Sp[(ke * 2 + axis) * 4]
            b = Sp[(ke * 2 + axis) * 4 + 1]
            c = Sp[(ke * 2 + axis) * 4 + 3]
            o0, o1 = o[(je * 2 + axis) * 2], o[(je * 2 + axis) * 2 + 1]
            r0 = zp[(je * 2 + axis) * 2] - zh[(ke * 2 + axis) * 2]
            r1 = zp[(je * 2 + axis) * 2 + 1] - zh[(ke * 2 + axis) * 2 + 1]
            if o0 and o1:
                x = (c * r0 * r0 - 2.0 * b * r0 * r1 + a * r1 * r1) / (a * c - b * b)
                d2 += x
                m += 2.0
                total += x + log_det[ke * 2 + axis]
                continue
            if o0:
                d2 += r0 * r0 / a
                m += 1.0
                total += r0 * r0 / a + log_a[ke * 2 + axis]
            else:
                total -= 2.0 * (phi[ke * width + column[axis * 2]] + peak[ke])
            if o1:
                d2 += r1 * r1 / c
                m += 1.0
                total += r1 * r1 / c + log_c[ke * 2 + axis]
            else:
                total -= 2.0 * (phi[ke * width + column[axis * 2 + 1]] + peak[ke])
        out[e] = -0.5 * total
        if tail and (tail_ok == NULL or tail_ok[ke]):  # log(e^y + e^x), the larger taken out
            x = log_weight - m * log_scale + stretch * d2
            y = log_keep
            out[e] += (x if x > y else y) + log1p(exp(-fabs(x - y)))
        if d2p != NULL:
            d2p[e] = d2
            mp[e] = m
    return out_


cdef void _update_pairs_c(f64* means, f64* covs, const i64* rows, Py_ssize_t n,
                          const f64* z, const b8* observed, const i64* measurement,
                          double edge_noise) noexcept nogil:
    """`_update_pairs` on pointers (n rows)."""
    cdef double u[3]
    cdef double w[3]
    cdef double g0[3]
    cdef double g1[3]
    cdef double h0[3]
    cdef double h1[3]
    cdef double P[9]
    cdef double m[3]
    cdef Py_ssize_t i, axis, a, b
    cdef i64 k, j
    cdef double var, m0, m1, s00, s11, s01, det, r0, r1, value
    cdef f64* mk
    cdef f64* Pk
    for i in range(n):
        k, j = rows[i], measurement[i]
        var = _box_var(means, k, edge_noise)
        for axis in range(2):
            mk = means + (k * 2 + axis) * 3
            Pk = covs + (k * 2 + axis) * 9
            for a in range(9):
                P[a] = Pk[a]
            for a in range(3):
                m[a] = mk[a]
            m0 = 1.0 if observed[(j * 2 + axis) * 2] else 0.0
            m1 = 1.0 if observed[(j * 2 + axis) * 2 + 1] else 0.0
            for a in range(3):
                u[a] = (P[a * 3] - P[a * 3 + 2]) * m0
                w[a] = (P[a * 3] + P[a * 3 + 2]) * m1
            s00 = m0 * (P[0] - 2.0 * P[2] + P[8] + var) + (1.0 - m0)
            s11 = m1 * (P[0] + 2.0 * P[2] + P[8] + var) + (1.0 - m1)
            s01 = m0 * m1 * (P[0] - P[8])
            det = s00 * s11 - s01 * s01
            for a in range(3):
                g0[a] = (u[a] * s11 - w[a] * s01) / det
                g1[a] = (w[a] * s00 - u[a] * s01) / det
                h0[a] = g0[a] * s00 + g1[a] * s01
                h1[a] = g0[a] * s01 + g1[a] * s11
            r0 = (z[(j * 2 + axis) * 2] - m[0] + m[2]) * m0
            r1 = (z[(j * 2 + axis) * 2 + 1] - m[0] - m[2]) * m1
            for a in range(3):
                mk[a] = m[a] + g0[a] * r0 + g1[a] * r1
                for b in range(a, 3):
                    value = (P[a * 3 + b] - g0[a] * u[b] - u[a] * g0[b] - g1[a] * w[b]
                             - w[a] * g1[b] + g0[a] * h0[b] + g1[a] * h1[b])
                    Pk[a * 3 + b] = value
                    Pk[b * 3 + a] = value


def _update_pairs(object means, object covs, object rows, object z, object observed,
                  object measurement, double edge_noise):
    """Kalman update, in place, of component rows[i] by measurement j = measurement[i], per
    axis. With u = P h0', w = P h1' (h0 = [1, 0, -1], h1 = [1, 0, 1] the edge rows, zero when
    the edge is not measured), S the innovation covariance and gains g0, g1 (the columns of
    P H' S^-1), the Joseph form (I - G H) P (I - G H)' + G R G' expands to
    P - g0 u' - u g0' - g1 w' - w g1' + g0 h0' + g1 h1',  h0 = S00 g0 + S01 g1,
    h1 = S01 g0 + S11 g1, which spares thousands of tiny matrix products in a crowd."""
    cdef f64* m = doubles(means, 3, "means")
    cdef f64* P = doubles(covs, 4, "covs")
    cdef const i64* r = integers(rows, 1, "rows")
    cdef const f64* zp = doubles(z, 3, "z")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* j = integers(measurement, 1, "measurement")
    _box_shape(means, 3, "means", 2, 3)
    _box_shape(covs, 4, "covs", 2, 3, 3)
    _box_shape(z, 3, "z", 2, 2)
    _box_shape(observed, 3, "observed", 2, 2)
    _update_pairs_c(m, P, r, dim(rows, 0), zp, o, j, edge_noise)


def _edges_of_boxes(object boxes):
    """(M, 4) left, top, width, height -> (M, 2, 2) edges [[left, right], [top, bottom]]."""
    cdef const f64* x = doubles(boxes, 2, "boxes")
    _box_shape(boxes, 2, "boxes", 4)
    cdef Py_ssize_t M = dim(boxes, 0), j, axis
    cdef cnp.ndarray out_ = new_doubles(3, M, 2, 2)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    for j in range(M):
        for axis in range(2):
            out[(j * 2 + axis) * 2] = x[j * 4 + axis]
            out[(j * 2 + axis) * 2 + 1] = x[j * 4 + axis] + x[j * 4 + 2 + axis]
    return out_


def _measured_edges(object z, double margin, double width, double height, bint extrapolated):
    """Which edges of z (M, 2, 2) are measured: every edge but one on the image border, within
    `margin` of it (a detector that clips its boxes puts the cut edge there). With
    `extrapolated`, an edge beyond the border by more than the margin is measured too (the
    detector placed it there: its estimate of the part the image does not show); without, it
    counts as on the border."""
    cdef const f64* zp = doubles(z, 3, "z")
    _box_shape(z, 3, "z", 2, 2)
    cdef Py_ssize_t M = dim(z, 0), j
    cdef cnp.npy_intp shape[3]
    shape[0], shape[1], shape[2] = M, 2, 2
    cdef cnp.ndarray out_ = cnp.PyArray_EMPTY(3, shape, cnp.NPY_BOOL, 0)
    cdef b8* out = <b8*>cnp.PyArray_DATA(out_)
    for j in range(M):
        out[j * 4] = zp[j * 4] > margin or (extrapolated and zp[j * 4] < -margin)
        out[j * 4 + 2] = zp[j * 4 + 2] > margin or (extrapolated and zp[j * 4 + 2] < -margin)
        out[j * 4 + 1] = (zp[j * 4 + 1] < width - margin
                          or (extrapolated and zp[j * 4 + 1] > width + margin))
        out[j * 4 + 3] = (zp[j * 4 + 3] < height - margin
                          or (extrapolated and zp[j * 4 + 3] > height + margin))
    return out_


def _censored(object observed):
    """(2, 2): which edges (axis, low or high) some detection of `observed` (M, 2, 2) has on
    the border."""
    cdef const b8* o = booleans(observed, 3, "observed")
    _box_shape(observed, 3, "observed", 2, 2)
    cdef cnp.ndarray out_ = new_booleans(2, 2, 2)
    _censored_c(o, dim(observed, 0), <b8*>cnp.PyArray_DATA(out_))
    return out_


def _every_edge_measured(object observed):
    """Whether no detection of `observed` (M, 2, 2) has an edge on the border."""
    cdef const b8* o = booleans(observed, 3, "observed")
    _box_shape(observed, 3, "observed", 2, 2)
    return _every_edge_measured_c(o, dim(observed, 0))


def _beyond_scores(object zhat, object S, double margin, double right, double bottom,
                   object observed):
    """Standard scores (K, c) of the image border under the c censored edges
    (`_censored(observed)`, in (axis, low or high) order) of each predicted box: the edge lies
    beyond the border with probability Phi(score): (margin - zhat) / sd for a low edge,
    (zhat - right or bottom) / sd for a high one, sd the edge's standard deviation."""
    cdef const f64* zh = doubles(zhat, 3, "zhat")
    cdef const f64* Sp = doubles(S, 4, "S")
    cdef const b8* o = booleans(observed, 3, "observed")
    _box_shape(zhat, 3, "zhat", 2, 2)
    _box_shape(S, 4, "S", 2, 2, 2)
    _box_shape(observed, 3, "observed", 2, 2)
    cdef b8 censored[4]
    _censored_c(o, dim(observed, 0), censored)
    cdef Py_ssize_t K = dim(zhat, 0), width = 0, k, c, axis
    for c in range(4):
        if censored[c]:
            width += 1
    cdef double high
    cdef cnp.ndarray out_ = new_doubles(2, K, width)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    for k in range(K):
        c = 0
        for axis in range(2):
            high = right if axis == 0 else bottom
            if censored[axis * 2]:
                out[k * width + c] = (margin - zh[(k * 2 + axis) * 2]) / sqrt(
                    Sp[(k * 2 + axis) * 4])
                c += 1
            if censored[axis * 2 + 1]:
                out[k * width + c] = -(high - zh[(k * 2 + axis) * 2 + 1]) / sqrt(
                    Sp[(k * 2 + axis) * 4 + 3])
                c += 1
    return out_


def _edges(object means):
    """H m per component and axis, H = [[1, 0, -1], [1, 0, 1]]: low edge c - s, high c + s."""
    cdef const f64* m = doubles(means, 3, "means")
    _box_shape(means, 3, "means", 2, 3)
    cdef Py_ssize_t K = dim(means, 0), k, axis
    cdef cnp.ndarray out_ = new_doubles(3, K, 2, 2)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    for k in range(K):
        for axis in range(2):
            out[(k * 2 + axis) * 2] = m[(k * 2 + axis) * 3] - m[(k * 2 + axis) * 3 + 2]
            out[(k * 2 + axis) * 2 + 1] = m[(k * 2 + axis) * 3] + m[(k * 2 + axis) * 3 + 2]
    return out_


def _innovation(object means, object covs, double edge_noise):
    """zhat = H m and S = H P H' + R per component and axis, with H = [[1, 0, -1], [1, 0, 1]]
    (low edge c - s, high edge c + s) and R = (e h_k)^2 I."""
    cdef const f64* mp = doubles(means, 3, "means")
    cdef const f64* Pp = doubles(covs, 4, "covs")
    _box_shape(means, 3, "means", 2, 3)
    _box_shape(covs, 4, "covs", 2, 3, 3)
    cdef Py_ssize_t K = dim(means, 0), k, axis
    cdef cnp.ndarray zhat_ = new_doubles(3, K, 2, 2)
    cdef cnp.ndarray S_ = new_doubles(4, K, 2, 2, 2)
    cdef f64* zhat = <f64*>cnp.PyArray_DATA(zhat_)
    cdef f64* S = <f64*>cnp.PyArray_DATA(S_)
    cdef const f64* m
    cdef const f64* P
    cdef f64* Sk
    cdef double var
    for k in range(K):
        var = _box_var(mp, k, edge_noise)
        for axis in range(2):
            m = mp + (k * 2 + axis) * 3
            P = Pp + (k * 2 + axis) * 9
            Sk = S + (k * 2 + axis) * 4
            zhat[(k * 2 + axis) * 2] = m[0] - m[2]
            zhat[(k * 2 + axis) * 2 + 1] = m[0] + m[2]
            Sk[0] = P[0] - P[2] - P[6] + P[8] + var
            Sk[3] = P[0] + P[2] + P[6] + P[8] + var
            Sk[1] = P[0] + P[2] - P[6] - P[8]
            Sk[2] = P[0] - P[2] + P[6] - P[8]
    return zhat_, S_


cdef void _beyond_update_c(f64* means, f64* covs, const i64* rows, Py_ssize_t n,
                           const b8* observed, const i64* measurement, double edge_noise,
                           const f64* border) noexcept nogil:
    """`_beyond_update` on pointers (n rows)."""
    cdef double u[3]
    cdef Py_ssize_t i, axis, side, a, b
    cdef i64 k, j
    cdef double R, sign, s2, s, alpha, tail, lam, shrink
    cdef f64* P
    cdef f64* m
    for i in range(n):
        k, j = rows[i], measurement[i]
        R = _box_var(means, k, edge_noise)
        for axis in range(2):
            for side in range(2):
                if observed[(j * 2 + axis) * 2 + side]:
                    continue
                P = covs + (k * 2 + axis) * 9
                m = means + (k * 2 + axis) * 3
                sign = 1.0 if side == 1 else -1.0  # h = [1, 0, sign]
                for a in range(3):
                    u[a] = P[a * 3] + sign * P[a * 3 + 2]  # P h'
                s2 = u[0] + sign * u[2] + R
                s = sqrt(s2)
                alpha = sign * (border[axis * 2 + side] - (m[0] + sign * m[2])) / s
                tail = 0.5 * erfc(alpha / sqrt(2.0))  # Phi(-alpha)
                if tail < 1e-300:
                    continue
                lam = exp(-0.5 * alpha * alpha) / sqrt(2.0 * M_PI) / tail
                shrink = lam * (lam - alpha) / s2
                for a in range(3):
                    m[a] += sign * u[a] * lam / s
                for a in range(3):
                    for b in range(3):
                        P[a * 3 + b] -= u[a] * u[b] * shrink


def _beyond_update(object means, object covs, object rows, object observed,
                   object measurement, double edge_noise, object border):
    """The moments of N(x; m, P) Phi(+-(h x - b) / sqrt(R)) for each border edge of measurement
    j (h its row of H, b the border it lies beyond: `border` (axis, low or high); + for a high
    edge, - for a low one), applied edge after edge. With s^2 = h P h' + R and
    alpha = +-(b - h m) / s, lambda = phi(alpha) / Phi(-alpha) (the inverse Mills ratio):
    m' = m +- P h' lambda / s and P' = P - P h' h P lambda (lambda - alpha) / s^2 (the probit
    update; Phi(-alpha) is the border edge's likelihood in `loglik`)."""
    cdef f64* m = doubles(means, 3, "means")
    cdef f64* P = doubles(covs, 4, "covs")
    cdef const i64* r = integers(rows, 1, "rows")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* j = integers(measurement, 1, "measurement")
    cdef const f64* bp = doubles(border, 2, "border")
    _box_shape(means, 3, "means", 2, 3)
    _box_shape(covs, 4, "covs", 2, 3, 3)
    _box_shape(observed, 3, "observed", 2, 2)
    _box_shape(border, 2, "border", 2)
    _beyond_update_c(m, P, r, dim(rows, 0), o, j, edge_noise, bp)


cdef void _cut_update_c(f64* means, f64* covs, const i64* rows, Py_ssize_t n,
                        const b8* observed, Py_ssize_t M, const i64* measurement,
                        double edge_noise, const f64* border, bint use_aspect, double mu,
                        double sigma) noexcept nogil:
    """`_cut_update` on pointers (n rows, M detections in `observed`)."""
    if _every_edge_measured_c(observed, M):
        return
    if use_aspect:
        _aspect_update_c(means, covs, rows, n, observed, measurement, mu, sigma)
    _beyond_update_c(means, covs, rows, n, observed, measurement, edge_noise, border)


def _cut_update(object means, object covs, object rows, object observed, object measurement,
                double edge_noise, object border, bint use_aspect, double mu, double sigma):
    """`update_rows`' steps after the edges: the aspect ratio's
    (`occtrack.models.aspect._aspect_update`, when `use_aspect`), then `_beyond_update`."""
    cdef f64* m = doubles(means, 3, "means")
    cdef f64* P = doubles(covs, 4, "covs")
    cdef const i64* r = integers(rows, 1, "rows")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* j = integers(measurement, 1, "measurement")
    cdef const f64* bp = doubles(border, 2, "border")
    _box_shape(means, 3, "means", 2, 3)
    _box_shape(covs, 4, "covs", 2, 3, 3)
    _box_shape(observed, 3, "observed", 2, 2)
    _box_shape(border, 2, "border", 2)
    _cut_update_c(m, P, r, dim(rows, 0), o, dim(observed, 0), j, edge_noise, bp, use_aspect,
                  mu, sigma)


def _update_rows(object means, object covs, object rows, object z, object observed,
                 object measurement, double edge_noise, object border, bint use_aspect,
                 double mu, double sigma):
    """`update_rows` in one call: the measured edges (`_update_pairs`), then `_cut_update`."""
    cdef f64* m = doubles(means, 3, "means")
    cdef f64* P = doubles(covs, 4, "covs")
    cdef const i64* r = integers(rows, 1, "rows")
    cdef const f64* zp = doubles(z, 3, "z")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* j = integers(measurement, 1, "measurement")
    cdef const f64* bp = doubles(border, 2, "border")
    _box_shape(means, 3, "means", 2, 3)
    _box_shape(covs, 4, "covs", 2, 3, 3)
    _box_shape(z, 3, "z", 2, 2)
    _box_shape(observed, 3, "observed", 2, 2)
    _box_shape(border, 2, "border", 2)
    cdef Py_ssize_t n = dim(rows, 0)
    _update_pairs_c(m, P, r, n, zp, o, j, edge_noise)
    _cut_update_c(m, P, r, n, o, dim(observed, 0), j, edge_noise, bp, use_aspect, mu, sigma)


def _box_clutter(object z, object score_term, double rate, double area):
    """`BoxMeasurement.clutter_density`: rate / (W H w h) * score_term per detection, W H
    the image's `area` and score^-power given as `score_term`."""
    cdef const f64* zp = doubles(z, 3, "z")
    cdef const f64* term = doubles(score_term, 1, "score_term")
    _box_shape(z, 3, "z", 2, 2)
    cdef Py_ssize_t M = dim(z, 0), j
    if dim(score_term, 0) < M:
        raise ValueError("_box_clutter: a score term per detection is needed")
    cdef cnp.ndarray out_ = new_doubles(1, M)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef double size
    for j in range(M):
        size = max((zp[j * 4 + 1] - zp[j * 4]) * (zp[j * 4 + 3] - zp[j * 4 + 2]), 1.0)
        out[j] = rate / (area * size) * term[j]
    return out_


def _clip(object x, double low, double high):
    """np.clip(x, low, high) as a new array (numpy's clip costs more than the loop here)."""
    cdef const f64* xp = doubles(x, 1, "x")
    cdef Py_ssize_t n = dim(x, 0), i
    cdef cnp.ndarray out_ = new_doubles(1, n)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    for i in range(n):
        out[i] = min(max(xp[i], low), high)
    return out_
