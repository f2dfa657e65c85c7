# The compiled kernel of scan_hand_made.py (the hand-made other-beam term).


def _other_beams_hand_made(object centre, object j, object origin, object angle,
                           object ranges, object segment_of_beam, double radius,
                           double max_range, double sigma, double passed, double band):
    """Per pair, sum of log f over the beams through the disc at centre[p] (at its mean)
    that are not segment j[p]'s."""
    cdef Py_ssize_t P = dim(j, 0), B = dim(angle, 0)
    cdef const f64* c = doubles(centre, 2, "centre")
    cdef const i64* jj = integers(j, 1, "j")
    cdef const f64* o = doubles(origin, 1, "origin")
    cdef const f64* ang = doubles(angle, 1, "angle")
    cdef const f64* rng = doubles(ranges, 1, "ranges")
    cdef const i64* seg = integers(segment_of_beam, 1, "segment_of_beam")
    if dim(centre, 0) < P or dim(centre, 1) != 2 or dim(origin, 0) < 2:
        raise ValueError("centre must be (P, 2) and origin (2,)")
    if dim(ranges, 0) < B or dim(segment_of_beam, 0) < B:
        raise ValueError("ranges and segment_of_beam need a value a beam")
    cdef cnp.ndarray out_ = zero_doubles(1, P)
    cdef f64* out = <f64*>cnp.PyArray_DATA(out_)
    cdef double log_passed = log(passed)
    cdef double px, py, dist, half, bearing, total, rho, zb
    cdef cnp.ndarray cu_ = new_doubles(1, B), su_ = new_doubles(1, B)
    cdef cnp.ndarray known_ = zero_booleans(1, B)
    cdef f64* cu = <f64*>cnp.PyArray_DATA(cu_)
    cdef f64* su = <f64*>cnp.PyArray_DATA(su_)
    cdef b8* known = <b8*>cnp.PyArray_DATA(known_)
    cdef Py_ssize_t p, w, b, lo, hi
    cdef Window win
    with nogil:
        for p in range(P):
            px, py = c[p * 2] - o[0], c[p * 2 + 1] - o[1]
            dist = hypot(px, py)
            if dist <= radius or dist - radius >= max_range or B == 0:
                continue
            half = asin(radius / dist)
            bearing = atan2(py, px)
            win = beam_window_c(ang, B, bearing - half, bearing + half)
            total = 0.0
            for w in range(2):
                lo = win.lo0 if w == 0 else win.lo1
                hi = win.hi0 if w == 0 else win.hi1
                for b in range(lo, hi):
                    if seg[b] == jj[p]:
                        continue
                    beam_direction(ang, b, cu, su, known)
                    rho = near_range_uv(cu[b], su[b], px, py, radius)
                    if rho <= 0.0:
                        continue
                    zb = rng[b] if rng[b] < max_range else max_range
                    if zb - rho > band * sigma:
                        total += log_passed
            out[p] = total
    return out_
