# cython: language_level=3
"""Compiled kernels of occtrack.filters.gmpmb: the loops over a frame's few hundred
components, pairs, cells and label slots, too small for numpy's per-call overhead to pay off.

The maths and the calls are in the Python modules, which import these kernels under the same
names: labels.py (`_labels.pxi`: label slots and their Bernoullis), pool.py (`_pool.pxi`: the
pool's order, merging and births), weights.py (`_weights.pxi`: the update's weights),
children.py (`_children.pxi`: the update's children) and prediction.py (`_prediction.pxi`).
Each kernel is written as its numba version read: every sum in the same order, no fused
multiply-add (the build's -ffp-contract=off), Python's max and min (NaN kept as the first
argument, as `max(a, b)` is `b if b > a else a`), numpy's stable argsort as a merge sort, so
the numbers are the same to the last bit. A `def` entry checks each array once (dtype,
dimensions, C order) and runs its loops on pointers; a kernel that calls another calls its
`cdef` version.
"""

cimport numpy as cnp
from libc.math cimport exp, exp2, floor, log2, rint, sqrt
from libc.stdint cimport uint64_t
from libc.string cimport memcpy

from occtrack._arrays cimport bdata, fdata, idata, length
from occtrack._arrays cimport py_imax, py_imin, py_max, py_min
from occtrack._arrays cimport (
    argsort_stable,
    b8,
    booleans,
    dim,
    doubles,
    f64,
    i64,
    integers,
    new_booleans,
    new_doubles,
    new_integers,
    zero_booleans,
    zero_doubles,
    zero_integers,
)

import math

from occtrack.models.box import MIN_HEIGHT as _MIN_HEIGHT

cnp.import_array()

cdef double MIN_HEIGHT = _MIN_HEIGHT  # px: the scale of a degenerate box (models/box.py)


# ---- shared: Python's max and min, numpy's maximum, the data of a new array, rows --------

cdef inline double npmaximum(double a, double b) noexcept nogil:
    """np.maximum(a, b) (numba's): a NaN of either wins, the first if both."""
    if a != a or b != b:
        return a if a != a else b
    return a if a >= b else b


cdef Py_ssize_t row_bytes(object a) noexcept:
    """Bytes of one a[i] of a (checked, C-contiguous) array."""
    cdef cnp.ndarray arr = <cnp.ndarray>a
    cdef Py_ssize_t size = cnp.PyArray_ITEMSIZE(arr)
    cdef int axis
    for axis in range(1, cnp.PyArray_NDIM(arr)):
        size *= cnp.PyArray_DIM(arr, axis)
    return size


cdef cnp.ndarray take_rows(object a, const i64* index, Py_ssize_t K):
    """a[index] of a (checked, C-contiguous) array: the rows copied, any dtype."""
    cdef cnp.ndarray arr = <cnp.ndarray>a
    cdef int nd = cnp.PyArray_NDIM(arr), axis
    cdef cnp.npy_intp shape[8]
    if nd > 8:
        raise ValueError("at most 8 dimensions")
    shape[0] = K
    for axis in range(1, nd):
        shape[axis] = cnp.PyArray_DIM(arr, axis)
    cdef cnp.ndarray out = cnp.PyArray_EMPTY(nd, shape, cnp.PyArray_TYPE(arr), 0)
    cdef Py_ssize_t size = row_bytes(arr), i
    cdef char* src = <char*>cnp.PyArray_DATA(arr)
    cdef char* dst = <char*>cnp.PyArray_DATA(out)
    for i in range(K):
        memcpy(dst + i * size, src + index[i] * size, size)
    return out


cdef cnp.ndarray contiguous(object a, str name):
    """a, if it is a C-contiguous numpy array of at least one dimension (any dtype)."""
    if not cnp.PyArray_Check(a):
        raise TypeError(f"{name}: a numpy array is needed, not {type(a).__name__}")
    cdef cnp.ndarray arr = <cnp.ndarray>a
    if cnp.PyArray_NDIM(arr) < 1 or not cnp.PyArray_IS_C_CONTIGUOUS(arr):
        raise TypeError(f"{name}: a C-contiguous array of at least one dimension is needed")
    return arr


include "_labels.pxi"
include "_pool.pxi"
include "_weights.pxi"
include "_children.pxi"
include "_prediction.pxi"
