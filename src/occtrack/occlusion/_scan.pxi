# The compiled kernel of scan.py (the lidar scan's measurement-wise hidden probability).


def _hidden_at(object centre, object origin, object angle, object ranges, double max_range,
               double sigma, double radius):
    """`ScanMeasurementWise.hidden_at`, compiled: for each disc the beams inside its angular
    span (sorted angles, by bisection, modulo a turn), the range rho to its near surface on
    each, and the product of 1 - Phi((z_b - rho) / sigma) (z_b = max_range for no return)."""
    cdef Py_ssize_t K = dim(centre, 0), B = dim(angle, 0)
    cdef const f64* c = doubles(centre, 2, "centre")
    cdef const f64* o = doubles(origin, 1, "origin")
    cdef const f64* ang = doubles(angle, 1, "angle")
    cdef const f64* rng = doubles(ranges, 1, "ranges")
    if dim(centre, 1) != 2 or dim(origin, 0) < 2:
        raise ValueError("centre must be (K, 2) and origin (2,)")
    if dim(ranges, 0) < B:
        raise ValueError("ranges need a value a beam")
    cdef cnp.ndarray out_ = zero_doubles(1, K)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef cnp.ndarray cu_ = new_doubles(1, B), su_ = new_doubles(1, B)
    cdef cnp.ndarray known_ = zero_booleans(1, B)
    cdef f64* cu = <f64*>cnp.PyArray_DATA(cu_)
    cdef f64* su = <f64*>cnp.PyArray_DATA(su_)
    cdef b8* known = <b8*>cnp.PyArray_DATA(known_)
    cdef Py_ssize_t k, w, b, lo, hi
    cdef double px, py, dist, bearing, half, log_q, rho, zb, phi
    cdef bint reached
    cdef Window win
    with nogil:
        for k in range(K):
            px, py = c[k * 2] - o[0], c[k * 2 + 1] - o[1]
            dist = hypot(px, py)
            if dist <= radius or dist - radius >= max_range or B == 0:
                continue
            bearing = atan2(py, px)
            half = asin(radius / dist)
            win = beam_window_c(ang, B, bearing - half, bearing + half)
            log_q, reached = 0.0, False
            for w in range(2):
                lo = win.lo0 if w == 0 else win.lo1
                hi = win.hi0 if w == 0 else win.hi1
                for b in range(lo, hi):
                    beam_direction(ang, b, cu, su, known)
                    rho = near_range_uv(cu[b], su[b], px, py, radius)
                    if rho <= 0.0:
                        continue
                    reached = True
                    zb = rng[b] if rng[b] < max_range else max_range
                    phi = 0.5 * erfc(-(zb - rho) / (sigma * sqrt(2.0)))
                    if phi >= 1.0:
                        log_q = -INFINITY
                        break  # this window only, as the numba loop did
                    log_q += log1p(-phi)
            out[k] = exp(log_q) if reached else 0.0
    return out_
