# cython: language_level=3
"""The two beam-and-disc helpers of `occtrack.models.scan_geometry` that the compiled scan
kernels call inside their loops, as inline C functions: cimport them anywhere with

    from occtrack.models._scan_geometry cimport (Window, beam_window_c, near_range_c,
                                                 near_range_uv, beam_direction)

(the models' `.pxi` kernels and `occlusion/_scan.pxi`). The maths is in scan_geometry.py; the
Python-callable `beam_window` and `near_range` are the `def` wrappers of
`models/_scan_geometry.pxi`. Inline, so nothing is linked between extensions.
"""

from libc.math cimport cos, sin, sqrt, floor, M_PI


ctypedef struct Window:
    # the beams of a window: [lo0, hi0) at the turn of angle[0], [lo1, hi1) at the next
    Py_ssize_t lo0, hi0, lo1, hi1


cdef inline Py_ssize_t _search_left(const double* a, Py_ssize_t n, double v) noexcept nogil:
    """numpy.searchsorted(a[:n], v, side="left") as numba computes it (NaN sorts last)."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    cdef double x
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        x = a[mid]
        if x < v or (v != v and x == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


cdef inline Py_ssize_t _search_right(const double* a, Py_ssize_t n, double v) noexcept nogil:
    """numpy.searchsorted(a[:n], v, side="right") as numba computes it (NaN sorts last)."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        if v != v or a[mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    return lo


cdef inline Window beam_window_c(const double* angle, Py_ssize_t B, double low,
                                 double high) noexcept nogil:
    """`scan_geometry.beam_window` on angle[:B] (sorted over one turn); B = 0 gives empty
    ranges (the callers skip an empty scan before)."""
    cdef Window w
    cdef double turn = 2.0 * M_PI
    cdef double base
    if B == 0:
        w.lo0 = w.hi0 = w.lo1 = w.hi1 = 0
        return w
    base = floor((low - angle[0]) / turn) * turn
    w.lo0 = _search_left(angle, B, low - base - turn)
    w.hi0 = _search_right(angle, B, high - base - turn)
    w.lo1 = _search_left(angle, B, low - base + turn - turn)
    w.hi1 = _search_right(angle, B, high - base + turn - turn)
    return w


cdef inline double near_range_uv(double ux, double uy, double px, double py,
                                 double radius) noexcept nogil:
    """`near_range_c` of the beam of direction (ux, uy) = (cos, sin) of its angle."""
    cdef double t_c = ux * px + uy * py
    cdef double d = -uy * px + ux * py
    cdef double h2 = radius * radius - d * d
    cdef double rho
    if h2 <= 0.0:
        return -1.0
    rho = t_c - sqrt(h2)
    return rho if rho > 0.0 else -1.0


cdef inline double near_range_c(double beam_angle, double px, double py,
                                double radius) noexcept nogil:
    """`scan_geometry.near_range`: the range to the near surface of the disc, or -1."""
    return near_range_uv(cos(beam_angle), sin(beam_angle), px, py, radius)


cdef inline void beam_direction(const double* angle, Py_ssize_t b, double* cu, double* su,
                                unsigned char* known) noexcept nogil:
    """cu[b], su[b] = cos(angle[b]), sin(angle[b]), computed the first time beam b is asked
    for (known[b] then set): a kernel that visits a beam for many discs takes its cos and
    sin once (the same values, so the same results as computing them each time)."""
    if not known[b]:
        cu[b] = cos(angle[b])
        su[b] = sin(angle[b])
        known[b] = 1
