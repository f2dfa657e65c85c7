# Kernels of occtrack.tracker.boxes (included by _tracker.pyx).


def _checked_ltwh(object boxes, object scores):
    """(all finite and no size negative, the boxes with sizes floored at 1 px)."""
    cdef const f64* b = doubles(boxes, 2, "boxes")
    cdef const f64* s = doubles(scores, 1, "scores")
    cdef Py_ssize_t M = dim(boxes, 0), j, c
    if dim(boxes, 1) != 4 or dim(scores, 0) != M:
        raise ValueError("boxes (M, 4) and scores (M,) are needed")
    out = new_doubles(2, M, 4)
    cdef f64* o = fdata(out)
    for j in range(M):
        if not isfinite(s[j]):
            return False, out
        for c in range(4):
            if not isfinite(b[j * 4 + c]):
                return False, out
        if b[j * 4 + 2] < 0.0 or b[j * 4 + 3] < 0.0:
            return False, out
        o[j * 4 + 0], o[j * 4 + 1] = b[j * 4 + 0], b[j * 4 + 1]
        o[j * 4 + 2], o[j * 4 + 3] = py_max(b[j * 4 + 2], 1.0), py_max(b[j * 4 + 3], 1.0)
    return True, out
