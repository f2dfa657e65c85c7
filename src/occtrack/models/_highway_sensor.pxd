# cython: language_level=3
"""The highway sensor's end terms (occtrack.models.highway_sensor), inline, for the compiled
loops of other extensions to call (the particle tracker's, `occtrack.filters.particle_tomb`):

    from occtrack.models._highway_sensor cimport _both_orders_c

The maths is in highway_sensor.py; `_models.pyx` (its `_highway_sensor.pxi`) holds the loops
and the Python entries (`_both_orders` among them).
"""

from libc.math cimport erfc, exp


cdef inline double _ndtr_c(double x) noexcept nogil:
    """Phi(x). Beyond 9 (below -39) erfc rounds Phi to exactly 1 (0) in double precision, so
    those are returned without calling it: the same numbers, for less work where a hidden
    part is wide against sigma."""
    if x > 9.0:
        return 1.0
    if x < -39.0:
        return 0.0
    return 0.5 * erfc(-x * 0.7071067811865476)  # sqrt(1 / 2)


cdef inline double _end_term_c(double e, double z_lo, double z_hi, bint hidden,
                               double inv_sigma, double tail) noexcept nogil:
    """f(e): N(z; e, sigma^2) for a seen end, P(e + noise in [z_lo, z_hi]) for a hidden one;
    0 beyond `tail` standard deviations."""
    cdef double lo = (z_lo - e) * inv_sigma
    cdef double hi
    if hidden:
        hi = (z_hi - e) * inv_sigma
        if hi < -tail or lo > tail:
            return 0.0
        return _ndtr_c(hi) - _ndtr_c(lo)
    if lo * lo > tail * tail:
        return 0.0
    return exp(-0.5 * lo * lo) * 0.3989422804014327 * inv_sigma  # 1 / sqrt(2 pi)


cdef inline bint _near_c(double e, double z_lo, double z_hi, bint hidden, double inv_sigma,
                         double tail) noexcept nogil:
    """Whether `_end_term_c` is computed rather than taken as 0 (within `tail` sigma)."""
    cdef double lo = (z_lo - e) * inv_sigma
    if hidden:
        return not ((z_hi - e) * inv_sigma < -tail or lo > tail)
    return not lo * lo > tail * tail


cdef inline double _both_orders_c(double lo, double hi, double zl0, double zl1, bint lh,
                                  double zr0, double zr1, bint rh, double inv,
                                  double tail) noexcept nogil:
    """p(z | ends lo, hi) summed over the two orders of the two ends; a product is computed
    only where both its ends are near (most particles are far from most measurements, and
    the reversed order is far for all but the shortest shapes)."""
    cdef double total = 0.0
    if _near_c(lo, zl0, zl1, lh, inv, tail) and _near_c(hi, zr0, zr1, rh, inv, tail):
        total += (_end_term_c(lo, zl0, zl1, lh, inv, tail)
                  * _end_term_c(hi, zr0, zr1, rh, inv, tail))
    if _near_c(hi, zl0, zl1, lh, inv, tail) and _near_c(lo, zr0, zr1, rh, inv, tail):
        total += (_end_term_c(hi, zl0, zl1, lh, inv, tail)
                  * _end_term_c(lo, zr0, zr1, rh, inv, tail))
    return total
