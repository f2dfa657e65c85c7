# motion.py's median of squares (`_median_of_squares`): one quickselect on a copy of the
# squares. A median is an order statistic, so any exact selection gives numpy's value.


cdef void _select_c(f64* a, Py_ssize_t n, Py_ssize_t k) noexcept nogil:
    """Reorder a[0:n] (finite) so that a[k] is its k-th smallest value, nothing before it
    larger and nothing after it smaller (Hoare's quickselect, median-of-three pivot)."""
    cdef Py_ssize_t lo = 0, hi = n - 1, i, j, mid
    cdef double pivot, t
    while hi > lo:
        mid = lo + (hi - lo) // 2
        if a[mid] < a[lo]:
            t = a[mid]; a[mid] = a[lo]; a[lo] = t
        if a[hi] < a[lo]:
            t = a[hi]; a[hi] = a[lo]; a[lo] = t
        if a[hi] < a[mid]:
            t = a[hi]; a[hi] = a[mid]; a[mid] = t
        pivot = a[mid]
        i, j = lo, hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                t = a[i]; a[i] = a[j]; a[j] = t
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return


def _median_of_squares(object x):
    """np.median(np.square(x)) of a 1-d array of finite numbers, to the last bit: the middle
    square, or the mean of the two middle squares."""
    cdef const f64* v = doubles(x, 1, "x")
    cdef Py_ssize_t n = dim(x, 0), i, k = n // 2
    if n == 0:
        raise ValueError("_median_of_squares: no values")
    cdef cnp.ndarray sq_ = new_doubles(1, n)
    cdef f64* sq = fdata(sq_)
    for i in range(n):
        sq[i] = v[i] * v[i]
    _select_c(sq, n, k)
    if n % 2:
        return sq[k]
    cdef double below = sq[0]
    for i in range(1, k):
        if sq[i] > below:
            below = sq[i]
    return (below + sq[k]) / 2.0
