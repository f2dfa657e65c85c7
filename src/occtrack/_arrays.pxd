# cython: language_level=3
"""The crossing between Python and the compiled kernels (issue 23), shared by every
extension of occtrack: an argument array is checked once (dtype, dimensions, C order) and
read through a pointer; new arrays are made with numpy's C API. Inline, so nothing is
linked between extensions.

    from occtrack._arrays cimport f64, i64, b8, doubles, integers, booleans, dim
    cdef f64* x = doubles(a, 2, "a")      # a: C-contiguous float64, 2-d; x[i * dim(a, 1) + j]
    out = new_doubles(1, n)               # numpy.empty(n)

Also Python's max and min of two numbers as numba compiled them (`py_max`, `py_min`,
`py_imax`, `py_imin`) and numpy's stable argsort (`argsort_stable`, for float64 or int64 keys),
which every extension shares.
"""

cimport numpy as cnp

ctypedef cnp.float64_t f64
ctypedef cnp.int64_t i64
ctypedef cnp.npy_bool b8


# Python's (and numba's) max(a, b) and min(a, b) of two floats: b only when b > a (b < a), so
# a NaN second argument gives a. On x86-64 SSE2's maxsd / minsd, which are exactly that: gcc
# otherwise makes max(x, 0.0) a branch, which real boxes mispredict (the overlap and occlusion
# loops ran 13-40 % slower than numba's LLVM, which emits maxsd).
cdef extern from *:
    """
    #if defined(__SSE2__)
    #include <emmintrin.h>
    static inline double occtrack_py_max(double a, double b) {
        return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(b), _mm_set_sd(a)));
    }
    static inline double occtrack_py_min(double a, double b) {
        return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(b), _mm_set_sd(a)));
    }
    #else
    static inline double occtrack_py_max(double a, double b) { return b > a ? b : a; }
    static inline double occtrack_py_min(double a, double b) { return b < a ? b : a; }
    #endif
    """
    double py_max "occtrack_py_max"(double a, double b) noexcept nogil
    double py_min "occtrack_py_min"(double a, double b) noexcept nogil


cdef inline i64 py_imax(i64 a, i64 b) noexcept nogil:
    """Python's max(a, b) of two integers."""
    return b if b > a else a


cdef inline i64 py_imin(i64 a, i64 b) noexcept nogil:
    """Python's min(a, b) of two integers."""
    return b if b < a else a


cdef inline void* _data(object a, int typenum, int ndim, str name, str kind) except NULL:
    if not cnp.PyArray_Check(a):
        raise TypeError(f"{name}: a numpy array is needed, not {type(a).__name__}")
    cdef cnp.ndarray arr = <cnp.ndarray>a
    if (cnp.PyArray_TYPE(arr) != typenum or cnp.PyArray_NDIM(arr) != ndim
            or not cnp.PyArray_IS_C_CONTIGUOUS(arr)):
        raise TypeError(f"{name}: a C-contiguous {ndim}-d {kind} array is needed, not "
                        f"{arr.dtype} {arr.ndim}-d"
                        f"{'' if cnp.PyArray_IS_C_CONTIGUOUS(arr) else ' (not contiguous)'}")
    return cnp.PyArray_DATA(arr)


cdef inline f64* doubles(object a, int ndim, str name) except NULL:
    """a's data, if a is a C-contiguous float64 array of `ndim` dimensions."""
    return <f64*>_data(a, cnp.NPY_FLOAT64, ndim, name, "float64")


cdef inline i64* integers(object a, int ndim, str name) except NULL:
    """a's data, if a is a C-contiguous int64 array of `ndim` dimensions."""
    return <i64*>_data(a, cnp.NPY_INT64, ndim, name, "int64")


cdef inline b8* booleans(object a, int ndim, str name) except NULL:
    """a's data, if a is a C-contiguous bool array of `ndim` dimensions."""
    return <b8*>_data(a, cnp.NPY_BOOL, ndim, name, "bool")


cdef inline f64* fdata(object a) noexcept:
    """The data of a float64 array already checked (or made here)."""
    return <f64*>cnp.PyArray_DATA(<cnp.ndarray>a)


cdef inline i64* idata(object a) noexcept:
    """The data of an int64 array already checked (or made here)."""
    return <i64*>cnp.PyArray_DATA(<cnp.ndarray>a)


cdef inline b8* bdata(object a) noexcept:
    """The data of a bool array already checked (or made here)."""
    return <b8*>cnp.PyArray_DATA(<cnp.ndarray>a)


cdef inline Py_ssize_t length(object a, Py_ssize_t n, str name) except -1:
    """n, if the (checked) array a has n rows (n values, for a 1-d array)."""
    cdef Py_ssize_t m = cnp.PyArray_DIM(<cnp.ndarray>a, 0)
    if m != n:
        raise ValueError(f"{name}: {n} rows are needed, not {m}")
    return n


cdef inline Py_ssize_t dim(object a, int axis) noexcept:
    """The length of (checked) array a along `axis`."""
    return cnp.PyArray_DIM(<cnp.ndarray>a, axis)


cdef inline cnp.ndarray _new(int typenum, int ndim, Py_ssize_t n0, Py_ssize_t n1,
                             Py_ssize_t n2, Py_ssize_t n3, bint zero):
    cdef cnp.npy_intp shape[4]
    shape[0] = n0
    shape[1] = n1
    shape[2] = n2
    shape[3] = n3
    if zero:
        return cnp.PyArray_ZEROS(ndim, shape, typenum, 0)
    return cnp.PyArray_EMPTY(ndim, shape, typenum, 0)


cdef inline cnp.ndarray new_doubles(int ndim, Py_ssize_t n0, Py_ssize_t n1=0,
                                    Py_ssize_t n2=0, Py_ssize_t n3=0):
    """numpy.empty((n0[, n1[, n2[, n3]]])) of float64."""
    return _new(cnp.NPY_FLOAT64, ndim, n0, n1, n2, n3, False)


cdef inline cnp.ndarray zero_doubles(int ndim, Py_ssize_t n0, Py_ssize_t n1=0,
                                     Py_ssize_t n2=0, Py_ssize_t n3=0):
    """numpy.zeros((n0[, n1[, n2[, n3]]])) of float64."""
    return _new(cnp.NPY_FLOAT64, ndim, n0, n1, n2, n3, True)


cdef inline cnp.ndarray new_integers(int ndim, Py_ssize_t n0, Py_ssize_t n1=0,
                                     Py_ssize_t n2=0):
    return _new(cnp.NPY_INT64, ndim, n0, n1, n2, 0, False)


cdef inline cnp.ndarray zero_integers(int ndim, Py_ssize_t n0, Py_ssize_t n1=0,
                                      Py_ssize_t n2=0):
    return _new(cnp.NPY_INT64, ndim, n0, n1, n2, 0, True)


cdef inline cnp.ndarray new_booleans(int ndim, Py_ssize_t n0, Py_ssize_t n1=0):
    return _new(cnp.NPY_BOOL, ndim, n0, n1, 0, 0, False)


cdef inline cnp.ndarray zero_booleans(int ndim, Py_ssize_t n0, Py_ssize_t n1=0):
    return _new(cnp.NPY_BOOL, ndim, n0, n1, 0, 0, True)


ctypedef fused sort_key:
    f64
    i64


cdef inline void argsort_stable(const sort_key* key, Py_ssize_t n, i64* order,
                                i64* work) noexcept nogil:
    """order = numpy.argsort(key[:n], kind="stable") of float64 or int64 keys (NaN keys last),
    by a bottom-up merge sort of indices; `work` holds n int64. A stable sort has one
    answer, so this equals numba's and numpy's mergesort to the index."""
    cdef Py_ssize_t i, width, lo, mid, hi, a, b, k
    cdef i64* src = order
    cdef i64* dst = work
    cdef i64* tmp
    for i in range(n):
        order[i] = i
    width = 1
    while width < n:
        lo = 0
        while lo < n:
            mid = lo + width if lo + width < n else n
            hi = lo + 2 * width if lo + 2 * width < n else n
            a, b, k = lo, mid, lo
            while a < mid and b < hi:
                # take from the right only when strictly smaller (stability); NaN is largest
                if key[src[b]] < key[src[a]] or (key[src[a]] != key[src[a]]
                                                 and key[src[b]] == key[src[b]]):
                    dst[k] = src[b]
                    b += 1
                else:
                    dst[k] = src[a]
                    a += 1
                k += 1
            while a < mid:
                dst[k] = src[a]
                a += 1
                k += 1
            while b < hi:
                dst[k] = src[b]
                b += 1
                k += 1
            lo = hi
        tmp = src
        src = dst
        dst = tmp
        width *= 2
    if src != order:
        for i in range(n):
            order[i] = src[i]
