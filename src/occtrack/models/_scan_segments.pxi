# The compiled kernels of scan_segments.py: the segment fit statistics at a linearisation
# point (`_linearise`), the derived other-beam term (`_other_beams`) and the hit beams'
# Gaussian with the centre's posterior (`_gaussian_hits`).


cdef inline double _scan_phi(double x) noexcept nogil:
    """Phi(x), the standard normal distribution function (scan_segments' `_phi`)."""
    return 0.5 * erfc(-x / sqrt(2.0))


cdef inline double _scan_max(double a, double b) noexcept nogil:
    """Python's max(a, b) as numba computes it: b if b > a, else a."""
    return b if b > a else a


cdef inline double _scan_min(double a, double b) noexcept nogil:
    """Python's min(a, b) as numba computes it: b if b < a, else a."""
    return b if b < a else a


def _linearise(object at, object j, object start, object beam, object angle, object ranges,
               object origin, double radius, double max_slope):
    """`ScanMeasurement.linearise`, compiled: per pair, the beams of segment j[p] that meet
    the disc at at[p] at a slope <= max_slope (`_disc_hits`), summed into A, Hr, rr, n."""
    cdef Py_ssize_t P = dim(j, 0), B = dim(angle, 0)
    cdef const f64* a = doubles(at, 2, "at")
    cdef const i64* jj = integers(j, 1, "j")
    cdef const i64* st = integers(start, 1, "start")
    cdef const i64* bm = integers(beam, 1, "beam")
    cdef const f64* ang = doubles(angle, 1, "angle")
    cdef const f64* rng = doubles(ranges, 1, "ranges")
    cdef const f64* o = doubles(origin, 1, "origin")
    if dim(at, 0) < P or dim(at, 1) != 2 or dim(origin, 0) < 2:
        raise ValueError("at must be (P, 2) and origin (2,)")
    cdef cnp.ndarray A_ = zero_doubles(3, P, 2, 2), Hr_ = zero_doubles(2, P, 2)
    cdef cnp.ndarray rr_ = zero_doubles(1, P), n_ = zero_doubles(1, P)
    cdef f64* A = <f64*>cnp.PyArray_DATA(A_)
    cdef f64* Hr = <f64*>cnp.PyArray_DATA(Hr_)
    cdef f64* rr = <f64*>cnp.PyArray_DATA(rr_)
    cdef f64* n = <f64*>cnp.PyArray_DATA(n_)
    cdef cnp.ndarray cu_ = new_doubles(1, B), su_ = new_doubles(1, B)
    cdef cnp.ndarray known_ = zero_booleans(1, B)
    cdef f64* cu = <f64*>cnp.PyArray_DATA(cu_)
    cdef f64* su = <f64*>cnp.PyArray_DATA(su_)
    cdef b8* known = <b8*>cnp.PyArray_DATA(known_)
    cdef Py_ssize_t p, i, b
    cdef double px, py, ux, uy, t_c, d, half2, half, rho, slope, hx, hy, e
    with nogil:
        for p in range(P):
            px, py = a[p * 2] - o[0], a[p * 2 + 1] - o[1]
            for i in range(st[jj[p]], st[jj[p] + 1]):
                b = bm[i]
                beam_direction(ang, b, cu, su, known)
                ux, uy = cu[b], su[b]
                t_c = ux * px + uy * py
                d = -uy * px + ux * py
                half2 = radius * radius - d * d
                if half2 <= 0.0:
                    continue
                half = sqrt(half2)
                rho = t_c - half
                slope = d / half
                if rho <= 0.0 or fabs(slope) > max_slope:
                    continue
                hx, hy = ux - slope * uy, uy + slope * ux
                e = rng[b] - rho
                A[p * 4] += hx * hx
                A[p * 4 + 1] += hx * hy
                A[p * 4 + 2] += hy * hx
                A[p * 4 + 3] += hy * hy
                Hr[p * 2] += hx * e
                Hr[p * 2 + 1] += hy * e
                rr[p] += e * e
                n[p] += 1.0
    return A_, Hr_, rr_, n_


def _other_beams(object centre, object cov, object j, object origin, object angle,
                 object ranges, object segment_of_beam, double radius, double max_range,
                 double p_d, double sigma, double spread):
    """Per pair, sum over the beams that may reach the disc (centre[p], covariance cov[p])
    and are not segment j[p]'s of log(1 - reach (1 - m)), m = 1 - P_D Phi((z - rho) / s),
    s^2 = sigma^2 + H P H', reach = P(|d| < a) (`ScanMeasurement.component_beams` and
    `models.scan.beam_terms`, compiled)."""
    cdef Py_ssize_t P = dim(j, 0), B = dim(angle, 0)
    cdef const f64* c = doubles(centre, 2, "centre")
    cdef const f64* cv = doubles(cov, 3, "cov")
    cdef const i64* jj = integers(j, 1, "j")
    cdef const f64* o = doubles(origin, 1, "origin")
    cdef const f64* ang = doubles(angle, 1, "angle")
    cdef const f64* rng = doubles(ranges, 1, "ranges")
    cdef const i64* seg = integers(segment_of_beam, 1, "segment_of_beam")
    if (dim(centre, 0) < P or dim(centre, 1) != 2 or dim(cov, 0) < P or dim(cov, 1) != 2
            or dim(cov, 2) != 2 or dim(origin, 0) < 2):
        raise ValueError("centre must be (P, 2), cov (P, 2, 2) and origin (2,)")
    if dim(ranges, 0) < B or dim(segment_of_beam, 0) < B:
        raise ValueError("ranges and segment_of_beam need a value a beam")
    cdef cnp.ndarray out_ = zero_doubles(1, P)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef cnp.ndarray cu_ = new_doubles(1, B), su_ = new_doubles(1, B)
    cdef cnp.ndarray known_ = zero_booleans(1, B)
    cdef f64* cu = <f64*>cnp.PyArray_DATA(cu_)
    cdef f64* su = <f64*>cnp.PyArray_DATA(su_)
    cdef b8* known = <b8*>cnp.PyArray_DATA(known_)
    cdef Py_ssize_t p, w, b, lo, hi
    cdef double px, py, dist, c00, c01, c10, c11, widen, half, bearing, total
    cdef double ux, uy, t_c, nx, ny, d, chord, rho, lateral2, lateral, reach, slope
    cdef double hx, hy, var, s, zb, m
    cdef Window win
    with nogil:
        for p in range(P):
            px, py = c[p * 2] - o[0], c[p * 2 + 1] - o[1]
            dist = hypot(px, py)
            if dist - radius >= max_range or B == 0:
                continue
            c00, c01, c10, c11 = cv[p * 4], cv[p * 4 + 1], cv[p * 4 + 2], cv[p * 4 + 3]
            widen = spread * sqrt(_scan_max(c00, c11))
            half = asin(_scan_min(_scan_max((radius + widen) / _scan_max(dist, 1e-9), 0.0),
                                  1.0))
            bearing = atan2(py, px)
            win = beam_window_c(ang, B, bearing - half - 1e-9, bearing + half + 1e-9)
            total = 0.0
            for w in range(2):
                lo = win.lo0 if w == 0 else win.lo1
                hi = win.hi0 if w == 0 else win.hi1
                for b in range(lo, hi):
                    if seg[b] == jj[p]:
                        continue
                    beam_direction(ang, b, cu, su, known)
                    ux, uy = cu[b], su[b]
                    t_c = ux * px + uy * py
                    if t_c <= 0.0:
                        continue
                    nx, ny = -uy, ux
                    d = nx * px + ny * py
                    chord = sqrt(_scan_max(radius * radius - d * d, 0.0))
                    rho = t_c - chord
                    if rho <= 0.0:
                        continue
                    lateral2 = nx * nx * c00 + nx * ny * (c01 + c10) + ny * ny * c11
                    if lateral2 > 0.0:
                        lateral = sqrt(lateral2)
                        reach = (_scan_phi((radius - d) / lateral)
                                 - _scan_phi((-radius - d) / lateral))
                    else:
                        reach = 1.0 if fabs(d) < radius else 0.0
                    if reach <= 1e-12:
                        continue
                    slope = d / chord if chord > 0.0 else 0.0
                    hx, hy = ux + slope * nx, uy + slope * ny
                    var = hx * hx * c00 + hx * hy * (c01 + c10) + hy * hy * c11
                    s = sqrt(sigma * sigma + var)
                    zb = rng[b] if rng[b] < max_range else max_range
                    m = 1.0 - p_d * _scan_phi((zb - rho) / s)
                    total += log(1.0 - reach * (1.0 - m))
            out[p] = total
    return out_


def _gaussian_hits(object centre, object cov, object fit, object A, object Hr, object rr,
                   object n, double sigma2):
    """`scan_segments._gaussian_hits`, compiled: per pair, log N of the hit beams from the
    fit statistics (the Woodbury forms, M2 = sigma^2 I + P A inverted in closed form) and the
    centre's posterior mean and covariance (symmetrised, its variances at least 0)."""
    cdef Py_ssize_t P = dim(centre, 0)
    cdef const f64* c = doubles(centre, 2, "centre")
    cdef const f64* cv = doubles(cov, 3, "cov")
    cdef const f64* f = doubles(fit, 2, "fit")
    cdef const f64* a = doubles(A, 3, "A")
    cdef const f64* h = doubles(Hr, 2, "Hr")
    cdef const f64* r2 = doubles(rr, 1, "rr")
    cdef const f64* nn = doubles(n, 1, "n")
    if (dim(centre, 1) != 2 or dim(cov, 0) < P or dim(fit, 0) < P or dim(A, 0) < P
            or dim(Hr, 0) < P or dim(rr, 0) < P or dim(n, 0) < P):
        raise ValueError("centre, cov, fit, A, Hr, rr and n need a row a pair")
    cdef cnp.ndarray out_ = new_doubles(1, P), post_ = new_doubles(2, P, 2)
    cdef cnp.ndarray pcov_ = new_doubles(3, P, 2, 2)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef f64* post = <f64*>cnp.PyArray_DATA(post_)
    cdef f64* pc = <f64*>cnp.PyArray_DATA(pcov_)
    cdef Py_ssize_t p
    cdef double d0, d1, ad0, ad1, E, b0, b1, m00, m01, m10, m11, det, i00, i01, i10, i11
    cdef double pb0, pb1, w0, w1, quad, logdet, pa00, pa01, pa10, pa11, q00, q01, q10, q11
    cdef double s01
    cdef double log_2pi = log(2.0 * M_PI), log_s2 = log(sigma2)
    with nogil:
        for p in range(P):
            d0, d1 = c[p * 2] - f[p * 2], c[p * 2 + 1] - f[p * 2 + 1]
            ad0 = a[p * 4] * d0 + a[p * 4 + 1] * d1
            ad1 = a[p * 4 + 2] * d0 + a[p * 4 + 3] * d1
            E = r2[p] - 2.0 * (d0 * h[p * 2] + d1 * h[p * 2 + 1]) + (d0 * ad0 + d1 * ad1)
            b0, b1 = h[p * 2] - ad0, h[p * 2 + 1] - ad1
            # M2 = sigma^2 I + P A
            m00 = sigma2 + (cv[p * 4] * a[p * 4] + cv[p * 4 + 1] * a[p * 4 + 2])
            m01 = cv[p * 4] * a[p * 4 + 1] + cv[p * 4 + 1] * a[p * 4 + 3]
            m10 = cv[p * 4 + 2] * a[p * 4] + cv[p * 4 + 3] * a[p * 4 + 2]
            m11 = sigma2 + (cv[p * 4 + 2] * a[p * 4 + 1] + cv[p * 4 + 3] * a[p * 4 + 3])
            det = m00 * m11 - m01 * m10
            i00, i01, i10, i11 = m11 / det, -m01 / det, -m10 / det, m00 / det
            pb0 = cv[p * 4] * b0 + cv[p * 4 + 1] * b1
            pb1 = cv[p * 4 + 2] * b0 + cv[p * 4 + 3] * b1
            w0 = i00 * pb0 + i01 * pb1
            w1 = i10 * pb0 + i11 * pb1
            quad = (E - (b0 * w0 + b1 * w1)) / sigma2
            logdet = nn[p] * log_s2 + log(det / (sigma2 * sigma2))
            out[p] = -0.5 * (quad + logdet + nn[p] * log_2pi)
            post[p * 2], post[p * 2 + 1] = c[p * 2] + w0, c[p * 2 + 1] + w1
            # P - M2^-1 (P A P)
            pa00 = cv[p * 4] * a[p * 4] + cv[p * 4 + 1] * a[p * 4 + 2]
            pa01 = cv[p * 4] * a[p * 4 + 1] + cv[p * 4 + 1] * a[p * 4 + 3]
            pa10 = cv[p * 4 + 2] * a[p * 4] + cv[p * 4 + 3] * a[p * 4 + 2]
            pa11 = cv[p * 4 + 2] * a[p * 4 + 1] + cv[p * 4 + 3] * a[p * 4 + 3]
            q00 = pa00 * cv[p * 4] + pa01 * cv[p * 4 + 2]
            q01 = pa00 * cv[p * 4 + 1] + pa01 * cv[p * 4 + 3]
            q10 = pa10 * cv[p * 4] + pa11 * cv[p * 4 + 2]
            q11 = pa10 * cv[p * 4 + 1] + pa11 * cv[p * 4 + 3]
            pc[p * 4] = cv[p * 4] - (i00 * q00 + i01 * q10)
            pc[p * 4 + 1] = cv[p * 4 + 1] - (i00 * q01 + i01 * q11)
            pc[p * 4 + 2] = cv[p * 4 + 2] - (i10 * q00 + i11 * q10)
            pc[p * 4 + 3] = cv[p * 4 + 3] - (i10 * q01 + i11 * q11)
            s01 = 0.5 * (pc[p * 4 + 1] + pc[p * 4 + 2])
            pc[p * 4 + 1], pc[p * 4 + 2] = s01, s01
            pc[p * 4] = _scan_max(pc[p * 4], 0.0) if pc[p * 4] == pc[p * 4] else pc[p * 4]
            pc[p * 4 + 3] = (_scan_max(pc[p * 4 + 3], 0.0) if pc[p * 4 + 3] == pc[p * 4 + 3]
                             else pc[p * 4 + 3])
    return out_, post_, pcov_
