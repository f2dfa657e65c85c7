# Kernels of occtrack.tracker.tracker (included by _tracker.pyx): which slots are reported,
# and their rows. Slot means (L, 2, 3): m[(k * 2 + axis) * 3 + j], j = centre, speed, half-size.


def _report_rows(object shown, object r, object means, object took, object detections,
                 object hidden, object classes, double occluded_above, object observed):
    """The `Tracks` fields after the ids, for the slots `shown`: boxes (the detection's
    when one was taken, else the state's), existence, velocities, detection index, class and
    whether occlusion (probability above `occluded_above`) explains a miss. A detection's
    unmeasured edge (`observed`, (M, 2, 2) as the measurement model's: one on the image
    border) is where the image ends, not the person: the state's edge is reported there when
    it lies farther out (the detector clips, the true box runs on)."""
    cdef const i64* sh = integers(shown, 1, "shown")
    cdef const f64* rr = doubles(r, 1, "r")
    cdef const f64* mm = doubles(means, 3, "means")
    cdef const i64* tk = integers(took, 1, "took")
    cdef const f64* dt = doubles(detections, 2, "detections")
    cdef const f64* hd = doubles(hidden, 1, "hidden")
    cdef const i64* cl = integers(classes, 1, "classes")
    cdef const b8* ob = booleans(observed, 3, "observed")
    cdef Py_ssize_t K = dim(shown, 0), L = dim(r, 0), a, k, axis, t
    cdef double lo, size, state_lo, state_hi
    length(means, L, "means")
    length(took, L, "took")
    length(hidden, L, "hidden")
    length(classes, L, "classes")
    if (dim(detections, 1) != 4 or dim(observed, 0) != dim(detections, 0)
            or dim(observed, 1) != 2 or dim(observed, 2) != 2):
        raise ValueError("detections (M, 4) and observed (M, 2, 2) are needed")
    boxes_, velocities_ = new_doubles(2, K, 4), new_doubles(2, K, 2)
    existence_, index_ = new_doubles(1, K), new_integers(1, K)
    cls_, occluded_ = new_integers(1, K), zero_booleans(1, K)
    cdef f64* boxes = fdata(boxes_)
    cdef f64* velocities = fdata(velocities_)
    cdef f64* existence = fdata(existence_)
    cdef i64* index = idata(index_)
    cdef i64* cls = idata(cls_)
    cdef b8* occluded = bdata(occluded_)
    for a in range(K):
        k = sh[a]
        existence[a], index[a], cls[a] = rr[k], tk[k], cl[k]
        for axis in range(2):
            velocities[a * 2 + axis] = mm[(k * 2 + axis) * 3 + 1]
            boxes[a * 4 + axis] = mm[(k * 2 + axis) * 3 + 0] - mm[(k * 2 + axis) * 3 + 2]
            boxes[a * 4 + 2 + axis] = 2.0 * mm[(k * 2 + axis) * 3 + 2]
        if tk[k] >= 0:
            t = tk[k]
            for axis in range(2):  # (a detection off the border is copied exactly)
                lo, size = dt[t * 4 + axis], dt[t * 4 + 2 + axis]
                state_lo = boxes[a * 4 + axis]
                state_hi = boxes[a * 4 + axis] + boxes[a * 4 + 2 + axis]
                if not ob[(t * 2 + axis) * 2] and state_lo < lo:
                    lo, size = state_lo, size + (lo - state_lo)
                if not ob[(t * 2 + axis) * 2 + 1] and state_hi > lo + size:
                    size = state_hi - lo
                boxes[a * 4 + axis], boxes[a * 4 + 2 + axis] = lo, size
        else:
            occluded[a] = hd[k] > occluded_above
    return boxes_, existence_, velocities_, index_, cls_, occluded_


def _reported(object r, object means, object centre_std, object used, object took,
              object coast, object serial, object reported_serial, object report_id,
              i64 next_id, double min_existence, double coast_time, double max_centre_std):
    """`Tracker.tracks`' rule, slot by slot: (the slots reported now in id order, the next
    free id). A slot reported for the first time since it got its serial (a new object in
    it) gets the next ids, in image order (centre x, then y), written into `report_id` and
    `reported_serial` in place."""
    cdef const f64* rr = doubles(r, 1, "r")
    cdef const f64* mm = doubles(means, 3, "means")
    cdef const f64* cs = doubles(centre_std, 2, "centre_std")
    cdef const b8* us = booleans(used, 1, "used")
    cdef const i64* tk = integers(took, 1, "took")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef const i64* se = integers(serial, 1, "serial")
    cdef i64* rs = integers(reported_serial, 1, "reported_serial")
    cdef i64* ri = integers(report_id, 1, "report_id")
    cdef Py_ssize_t L = dim(r, 0), n = 0, fresh = 0, k, i, t
    cdef double height
    length(means, L, "means")
    length(centre_std, L, "centre_std")
    length(used, L, "used")
    length(took, L, "took")
    length(coast, L, "coast")
    length(serial, L, "serial")
    length(reported_serial, L, "reported_serial")
    length(report_id, L, "report_id")
    shown_ = new_integers(1, L)
    cdef i64* shown = idata(shown_)
    for k in range(L):
        if not us[k] or not rr[k] > min_existence:
            continue
        if tk[k] < 0:
            height = py_max(2.0 * mm[(k * 2 + 1) * 3 + 2], 1.0)
            if not (co[k] <= coast_time + 1e-9 and cs[k * 2 + 0] < max_centre_std * height
                    and cs[k * 2 + 1] < max_centre_std * height):
                continue
        shown[n] = k
        n += 1
        if rs[k] != se[k]:
            fresh += 1
    order_, work_ = new_integers(1, n), new_integers(1, n)
    cdef i64* order = idata(order_)
    cdef i64* work = idata(work_)
    cdef f64* key
    cdef i64* new
    cdef i64* by_y
    cdef i64* by_x
    if fresh:
        new_, key_ = new_integers(1, fresh), new_doubles(1, fresh)
        by_y_, by_x_ = new_integers(1, fresh), new_integers(1, fresh)
        new, key, by_y, by_x = idata(new_), fdata(key_), idata(by_y_), idata(by_x_)
        i = 0
        for t in range(n):
            k = shown[t]
            if rs[k] != se[k]:
                new[i] = k
                i += 1
        for t in range(fresh):
            key[t] = mm[(new[t] * 2 + 1) * 3 + 0]
        argsort_stable(key, fresh, by_y, work)
        for t in range(fresh):
            key[t] = mm[(new[by_y[t]] * 2 + 0) * 3 + 0]
        argsort_stable(key, fresh, by_x, work)
        for i in range(fresh):
            k = new[by_y[by_x[i]]]
            ri[k] = next_id + i
            rs[k] = se[k]
    # (numba's default-kind argsort here: the ids of the reported slots are distinct, so any
    # sort agrees)
    ids_ = new_integers(1, n)
    cdef i64* ids = idata(ids_)
    for t in range(n):
        ids[t] = ri[shown[t]]
    argsort_stable(ids, n, order, work)
    out_ = new_integers(1, n)
    cdef i64* out = idata(out_)
    for t in range(n):
        out[t] = shown[order[t]]
    return out_, next_id + fresh
