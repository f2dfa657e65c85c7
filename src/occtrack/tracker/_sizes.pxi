# sizes.py's bookkeeping of the detections each track takes (`_record_sizes`). Slot arrays:
# serial (L,), when (L, D), half (L, D, 2), height (L, D), valid (L, D, 2) as uint8, D the
# ring's depth; boxes (M, 4) left, top, width, height; observed (M, 2, 2) booleans.


def _record_sizes(object serial_hist, object when, object half, object height, object valid,
                  object serial, object took, object boxes, object observed, i64 t, i64 lag):
    """`SizeHistory.record` in place for tracked frame `t`: returns the relative half-size
    changes over 1 and `lag` frames (two 1-d arrays), for the axes whose edges were all
    measured at both ends."""
    cdef i64* sh = integers(serial_hist, 1, "serial_hist")
    cdef i64* wh = integers(when, 2, "when")
    cdef f64* hf = doubles(half, 3, "half")
    cdef f64* ht = doubles(height, 2, "height")
    cdef b8* vd = booleans(valid, 3, "valid")
    cdef const i64* se = integers(serial, 1, "serial")
    cdef const i64* tk = integers(took, 1, "took")
    cdef const f64* bx = doubles(boxes, 2, "boxes")
    cdef const b8* ob = booleans(observed, 3, "observed")
    cdef Py_ssize_t L = dim(took, 0), D = dim(when, 1), M = dim(boxes, 0), i, a, k, c
    cdef Py_ssize_t n1 = 0, nl = 0, idx, now = t % D
    cdef i64 j, back
    cdef double h, hb, hh
    cdef bint ok
    if dim(serial_hist, 0) < L or dim(serial, 0) < L:
        raise ValueError("_record_sizes: a history row per slot is needed")
    out1_, outl_ = new_doubles(1, 2 * L), new_doubles(1, 2 * L)
    cdef f64* out1 = fdata(out1_)
    cdef f64* outl = fdata(outl_)
    for i in range(L):
        j = tk[i]
        if j < 0 or j >= M:
            continue
        if sh[i] != se[i]:  # a new Bernoulli in this slot: its history starts here
            for c in range(D):
                wh[i * D + c] = -1
            sh[i] = se[i]
        h = bx[j * 4 + 3] if bx[j * 4 + 3] > 1e-9 else 1e-9
        for k in range(2):
            back = 1 if k == 0 else lag
            idx = (t - back) % D
            if wh[i * D + idx] != t - back:
                continue
            hb = ht[i * D + idx]
            hh = (h + hb) / 2.0
            for a in range(2):
                ok = (ob[(j * 2 + a) * 2] and ob[(j * 2 + a) * 2 + 1]
                      and vd[(i * D + idx) * 2 + a])
                if ok:
                    if k == 0:
                        out1[n1] = (bx[j * 4 + 2 + a] / 2.0 - hf[(i * D + idx) * 2 + a]) / hh
                        n1 += 1
                    else:
                        outl[nl] = (bx[j * 4 + 2 + a] / 2.0 - hf[(i * D + idx) * 2 + a]) / hh
                        nl += 1
        wh[i * D + now] = t
        ht[i * D + now] = h
        for a in range(2):
            hf[(i * D + now) * 2 + a] = bx[j * 4 + 2 + a] / 2.0
            vd[(i * D + now) * 2 + a] = ob[(j * 2 + a) * 2] and ob[(j * 2 + a) * 2 + 1]
    return out1_[:n1], outl_[:nl]
