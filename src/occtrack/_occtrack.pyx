# cython: language_level=3
"""Compiled kernels of the package occtrack itself (issue 23): `_sweep`, the candidate test
of `occtrack.spatial.overlapping_pairs` (the maths and the call are in spatial.py).

Written as the numba loop it replaces read, on pointers: a `def` entry checks each array once
(dtype, dimensions, C order: `occtrack._arrays`).
"""

cimport numpy as cnp

from occtrack._arrays cimport bdata, fdata, idata, length
from occtrack._arrays cimport dim, doubles, f64, i64, integers, new_integers

cnp.import_array()


def _sweep(a_x0, a_y0, a_y1, s_x1, s_y0, s_y1, order, start, stop):
    """The pairs (i, order[k]) with k in [start[i], stop[i]) whose boxes overlap (below stop,
    the low x edge is below the high one of box i), i ascending, then k."""
    cdef const f64* ax0 = doubles(a_x0, 1, "a_x0")
    cdef const f64* ay0 = doubles(a_y0, 1, "a_y0")
    cdef const f64* ay1 = doubles(a_y1, 1, "a_y1")
    cdef const f64* sx1 = doubles(s_x1, 1, "s_x1")
    cdef const f64* sy0 = doubles(s_y0, 1, "s_y0")
    cdef const f64* sy1 = doubles(s_y1, 1, "s_y1")
    cdef const i64* o = integers(order, 1, "order")
    cdef const i64* lo = integers(start, 1, "start")
    cdef const i64* hi = integers(stop, 1, "stop")
    cdef Py_ssize_t N = dim(start, 0), S = dim(order, 0), i, k, found = 0, total = 0
    length(stop, N, "stop")
    length(a_x0, N, "a_x0")
    length(a_y0, N, "a_y0")
    length(a_y1, N, "a_y1")
    length(s_x1, S, "s_x1")
    length(s_y0, S, "s_y0")
    length(s_y1, S, "s_y1")
    for i in range(N):
        if hi[i] > lo[i] and (lo[i] < 0 or hi[i] > S):
            raise IndexError(f"start, stop: [{lo[i]}, {hi[i]}) is not within {S}")
        if hi[i] - lo[i] > 0:
            total += hi[i] - lo[i]
    out_i_, out_j_ = new_integers(1, total), new_integers(1, total)
    cdef i64* out_i = <i64*>cnp.PyArray_DATA(out_i_)
    cdef i64* out_j = <i64*>cnp.PyArray_DATA(out_j_)
    for i in range(N):
        for k in range(lo[i], hi[i]):
            if ax0[i] < sx1[k] and ay0[i] < sy1[k] and sy0[k] < ay1[i]:
                out_i[found] = i
                out_j[found] = o[k]
                found += 1
    return out_i_[:found], out_j_[:found]
