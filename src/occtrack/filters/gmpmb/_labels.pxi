# ---- labels.py: the label slots and their Bernoullis ----------------------------------------

cdef cnp.ndarray _label_sums_c(const i64* label, const f64* mass, Py_ssize_t n, Py_ssize_t L):
    cdef cnp.ndarray r_ = zero_doubles(1, L)
    cdef f64* r = fdata(r_)
    cdef Py_ssize_t k
    for k in range(n):
        if label[k] >= 0:
            r[label[k]] += mass[k]
    return r_


def _label_sums(label, mass, Py_ssize_t L):
    """r_i = sum of w_k over the components with label i, for i < L (label -1: none)."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    return _label_sums_c(lab, m, dim(label, 0), L)


cdef tuple _rank_bernoullis_c(const i64* label, const f64* mass, const i64* newborn,
                              Py_ssize_t n, const b8* used, Py_ssize_t L, Py_ssize_t M,
                              double min_existence):
    cdef cnp.ndarray r_old_ = _label_sums_c(label, mass, n, L)
    cdef cnp.ndarray r_new_ = _label_sums_c(newborn, mass, n, M)
    cdef const f64* r_old = fdata(r_old_)
    cdef const f64* r_new = fdata(r_new_)
    cdef Py_ssize_t A = 0, B = 0, i, N, count
    for i in range(L):
        A += used[i] != 0
    for i in range(M):
        B += r_new[i] > 0
    cdef cnp.ndarray old_ = new_integers(1, A), new_ = new_integers(1, B)
    cdef i64* old = idata(old_)
    cdef i64* new = idata(new_)
    A = 0
    for i in range(L):
        if used[i]:
            old[A] = i
            A += 1
    B = 0
    for i in range(M):
        if r_new[i] > 0:
            new[B] = i
            B += 1
    N = A + B
    cdef cnp.ndarray r_all_ = new_doubles(1, N), negative_ = new_doubles(1, N)
    cdef cnp.ndarray order_ = new_integers(1, N), work_ = new_integers(1, N)
    cdef f64* r_all = fdata(r_all_)
    cdef f64* negative = fdata(negative_)
    cdef i64* order = idata(order_)
    for i in range(A):
        r_all[i] = r_old[old[i]]
    for i in range(B):
        r_all[A + i] = r_new[new[i]]
    for i in range(N):
        negative[i] = -r_all[i]
    argsort_stable(negative, N, order, idata(work_))
    count = 0
    for i in range(N):
        count += r_all[order[i]] >= min_existence
    cdef cnp.ndarray ranked_ = new_integers(1, count)
    cdef i64* ranked = idata(ranked_)
    count = 0
    for i in range(N):
        if r_all[order[i]] >= min_existence:
            ranked[count] = order[i]
            count += 1
    return old_, new_, r_all_, ranked_


def _rank_bernoullis(label, mass, newborn, used, Py_ssize_t M, double min_existence):
    """(used slots, measurements with a newborn Bernoulli, the existence of each of those
    in that order, their indices strongest first among those at min_existence or above)."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const i64* born = integers(newborn, 1, "newborn")
    cdef const b8* u = booleans(used, 1, "used")
    return _rank_bernoullis_c(lab, m, born, dim(label, 0), u, dim(used, 0), M, min_existence)


cdef tuple _split_ranked_c(const i64* ranked, Py_ssize_t R, Py_ssize_t n_old):
    cdef cnp.ndarray keep_old_ = zero_booleans(1, n_old)
    cdef b8* keep_old = bdata(keep_old_)
    cdef Py_ssize_t i, a, count = 0
    cdef i64 value
    for i in range(R):
        if ranked[i] < n_old:
            keep_old[ranked[i]] = True
        else:
            count += 1
    cdef cnp.ndarray keep_new_ = new_integers(1, count)
    cdef i64* keep_new = idata(keep_new_)
    count = 0
    for i in range(R):
        if ranked[i] >= n_old:
            keep_new[count] = ranked[i] - n_old
            count += 1
    for i in range(1, count):  # (keep_new.sort(): integers, one answer)
        value = keep_new[i]
        a = i
        while a > 0 and keep_new[a - 1] > value:
            keep_new[a] = keep_new[a - 1]
            a -= 1
        keep_new[a] = value
    return keep_old_, keep_new_


def _split_ranked(ranked, Py_ssize_t n_old):
    """Which of the n_old existing Bernoullis keep their label, and the new ones that get
    one (indices among the new, ascending)."""
    cdef const i64* r = integers(ranked, 1, "ranked")
    return _split_ranked_c(r, dim(ranked, 0), n_old)


def _keep_labels(label, mass, newborn, used, Py_ssize_t M, double min_existence,
                 Py_ssize_t limit):
    """`GaussianMixturePMB._assign_labels` up to the opening of new slots: the strongest
    Bernoullis at min_existence or above keep (or will get) a label, at most `limit` of them
    when limit > 0; the other used slots are freed in place and their components' labels set
    to -1. Returns (labels, the measurements whose newborn gets a slot (ascending), the
    existences cut by the limit, how many Bernoullis were at min_existence or above)."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const i64* born = integers(newborn, 1, "newborn")
    cdef b8* u = booleans(used, 1, "used")
    cdef Py_ssize_t n = dim(label, 0), L = dim(used, 0), i, k, R
    cdef cnp.ndarray old_, new_, r_all_, ranked_, keep_old_, keep_new_
    old_, new_, r_all_, ranked_ = _rank_bernoullis_c(lab, m, born, n, u, L, M, min_existence)
    cdef const i64* old = idata(old_)
    cdef const i64* new = idata(new_)
    cdef const f64* r_all = fdata(r_all_)
    cdef const i64* ranked = idata(ranked_)
    cdef Py_ssize_t held = dim(ranked_, 0), n_old = dim(old_, 0)
    R = held
    cdef cnp.ndarray lost_
    if limit and held > limit:
        lost_ = new_doubles(1, held - limit)
        for i in range(held - limit):
            fdata(lost_)[i] = r_all[ranked[limit + i]]
        R = limit
    else:
        lost_ = new_doubles(1, 0)
    keep_old_, keep_new_ = _split_ranked_c(ranked, R, n_old)
    cdef const b8* keep_old = bdata(keep_old_)
    cdef const i64* keep_new = idata(keep_new_)
    cdef cnp.ndarray gone_ = zero_booleans(1, L)
    cdef b8* gone = bdata(gone_)
    for i in range(n_old):
        if not keep_old[i]:
            u[old[i]] = False
            gone[old[i]] = True
    cdef cnp.ndarray out_ = new_integers(1, n)
    cdef i64* out = idata(out_)
    for k in range(n):
        out[k] = lab[k]
        if lab[k] >= 0 and gone[lab[k]]:
            out[k] = -1
    cdef Py_ssize_t K = dim(keep_new_, 0)
    cdef cnp.ndarray meas_ = new_integers(1, K)
    for i in range(K):
        idata(meas_)[i] = new[keep_new[i]]
    return out_, meas_, lost_, held


def _open_slots(label, newborn, meas, Py_ssize_t M, i64 serial0, used, serial, age, hits,
                coast, detection, cls, classes):
    """Give the newborn Bernoullis of measurements `meas` the first free slots (in place on
    the slot arrays): serials from serial0, one hit at age 1, their measurement's class
    (`classes`, empty: one class). Returns the components' labels."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const i64* born = integers(newborn, 1, "newborn")
    cdef const i64* ms = integers(meas, 1, "meas")
    cdef b8* u = booleans(used, 1, "used")
    cdef i64* ser = integers(serial, 1, "serial")
    cdef i64* ag = integers(age, 1, "age")
    cdef i64* hi = integers(hits, 1, "hits")
    cdef f64* co = doubles(coast, 1, "coast")
    cdef i64* de = integers(detection, 1, "detection")
    cdef i64* cl = integers(cls, 1, "cls")
    cdef const i64* cs = integers(classes, 1, "classes")
    cdef Py_ssize_t n = dim(label, 0), L = dim(used, 0), n_meas = dim(meas, 0), s, k
    cdef bint one_class = dim(classes, 0) == 0
    cdef cnp.ndarray slot_of_meas_ = new_integers(1, M)
    cdef i64* slot_of_meas = idata(slot_of_meas_)
    for k in range(M):
        slot_of_meas[k] = -1
    cdef Py_ssize_t i = 0
    for s in range(L):
        if i == n_meas:
            break
        if not u[s]:
            u[s] = True
            slot_of_meas[ms[i]] = s
            ser[s] = serial0 + i
            ag[s] = 1
            hi[s] = 1
            co[s] = 0.0
            de[s] = ms[i]
            cl[s] = 0 if one_class else cs[ms[i]]
            i += 1
    cdef cnp.ndarray out_ = new_integers(1, n)
    cdef i64* out = idata(out_)
    for k in range(n):
        out[k] = lab[k]
        if born[k] >= 0:
            out[k] = slot_of_meas[born[k]]
    return out_


def _count_in_place(detection, age, hits, coast, used, slots, row, col, p_hit, double dt):
    """`GaussianMixturePMB._count_detections` on the slot arrays, in place."""
    cdef i64* de = integers(detection, 1, "detection")
    cdef i64* ag = integers(age, 1, "age")
    cdef i64* hi = integers(hits, 1, "hits")
    cdef f64* co = doubles(coast, 1, "coast")
    cdef const b8* u = booleans(used, 1, "used")
    cdef const i64* sl = integers(slots, 1, "slots")
    cdef const i64* r = integers(row, 1, "row")
    cdef const i64* c = integers(col, 1, "col")
    cdef const f64* p = doubles(p_hit, 1, "p_hit")
    cdef Py_ssize_t e, i
    cdef bint hit
    for i in range(dim(detection, 0)):
        de[i] = -1
    for e in range(dim(p_hit, 0)):
        if p[e] > 0.5:
            de[sl[r[e]]] = c[e]
    for i in range(dim(used, 0)):
        hit = de[i] >= 0
        if u[i]:
            ag[i] += 1
            if not hit:
                co[i] += dt
        if hit:
            hi[i] += 1
            co[i] = 0.0


def _confirm_in_place(used, age, hits, label, i64 window, i64 needed):
    """`GaussianMixturePMB._confirm_or_delete`: frees the doomed slots in place and returns
    which components are kept."""
    cdef b8* u = booleans(used, 1, "used")
    cdef const i64* ag = integers(age, 1, "age")
    cdef const i64* hi = integers(hits, 1, "hits")
    cdef const i64* lab = integers(label, 1, "label")
    cdef Py_ssize_t L = dim(used, 0), n = dim(label, 0), i, k
    cdef cnp.ndarray doomed_ = zero_booleans(1, L)
    cdef b8* doomed = bdata(doomed_)
    cdef bint any_doomed = False
    for i in range(L):
        if u[i] and hi[i] + py_imax(window - ag[i], 0) < needed:
            doomed[i] = True
            u[i] = False
            any_doomed = True
    cdef cnp.ndarray keep_ = new_booleans(1, n)
    cdef b8* keep = bdata(keep_)
    for k in range(n):
        keep[k] = True
    if any_doomed:
        for k in range(n):
            if lab[k] >= 0 and doomed[lab[k]]:
                keep[k] = False
    return keep_


def _cap_in_place(mass, label, Py_ssize_t L):
    """`GaussianMixturePMB._cap_existence` in place: an object whose masses sum above 1
    (rounding) has them scaled by 1 / r."""
    cdef f64* m = doubles(mass, 1, "mass")
    cdef const i64* lab = integers(label, 1, "label")
    cdef Py_ssize_t n = dim(label, 0), k
    cdef i64 i
    cdef cnp.ndarray r_ = _label_sums_c(lab, m, n, L)
    cdef const f64* r = fdata(r_)
    for k in range(n):
        i = lab[k]
        if i >= 0 and r[i] > 1.0:
            m[k] *= 1.0 / py_max(r[i], 1e-300)


cdef tuple _object_moments_c(const i64* lab, const f64* m, const f64* mu, const f64* P,
                             Py_ssize_t n, Py_ssize_t B, Py_ssize_t d, Py_ssize_t L):
    cdef Py_ssize_t k, b, c, a
    cdef i64 i
    cdef double share, dev
    cdef cnp.ndarray r_ = _label_sums_c(lab, m, n, L)
    cdef const f64* r = fdata(r_)
    cdef cnp.ndarray means_ = zero_doubles(3, L, B, d), var_ = zero_doubles(2, L, 2)
    cdef f64* means = fdata(means_)
    cdef f64* var = fdata(var_)
    for k in range(n):
        i = lab[k]
        if i >= 0:
            share = m[k] / py_max(r[i], 1e-300)
            for b in range(B):
                for c in range(d):
                    means[(i * B + b) * d + c] += share * mu[(k * B + b) * d + c]
    for k in range(n):
        i = lab[k]
        if i >= 0:
            share = m[k] / py_max(r[i], 1e-300)
            for a in range(2):
                dev = mu[(k * B + a) * d] - means[(i * B + a) * d]
                var[i * 2 + a] += share * (P[((k * B + a) * d) * d] + dev * dev)
    cdef cnp.ndarray sd_ = new_doubles(2, L, 2)
    for k in range(2 * L):
        fdata(sd_)[k] = sqrt(var[k])
    return r_, means_, sd_


def _object_moments(label, mass, mean, cov, Py_ssize_t L):
    """`GaussianMixturePMB.object_moments` of components with these labels: per slot the
    existence, the mass-weighted mean state and the centre's standard deviation."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const f64* P = doubles(cov, 4, "cov")
    return _object_moments_c(lab, m, mu, P, dim(label, 0), dim(mean, 1), dim(mean, 2), L)


def _recycle_unplaced(label, mass, mean, cov, used, coast, double spread):
    """`GaussianMixturePMB._recycle_unplaced` in place: every used slot undetected at its last
    update (coast > 0) whose centre's standard deviation (`_object_moments`) exceeds spread
    times its mean half-size on an axis is freed and its components' labels set to -1 (the
    Poisson part). Returns how many slots were freed."""
    cdef i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const f64* P = doubles(cov, 4, "cov")
    cdef b8* u = booleans(used, 1, "used")
    cdef const f64* unseen = doubles(coast, 1, "coast")
    cdef Py_ssize_t n = dim(label, 0), L = dim(used, 0), B = dim(mean, 1), d = dim(mean, 2)
    cdef Py_ssize_t k, a, freed = 0
    cdef i64 i
    length(coast, L, "coast")
    for i in range(L):
        if u[i] and unseen[i] > 0.0:
            break
    else:
        return 0
    r_, means_, sd_ = _object_moments_c(lab, m, mu, P, n, B, d, L)
    cdef const f64* r = fdata(r_)
    cdef const f64* means = fdata(means_)
    cdef const f64* sd = fdata(sd_)
    cdef cnp.ndarray lost_ = zero_booleans(1, L)
    cdef b8* lost = bdata(lost_)
    for i in range(L):
        if u[i] and unseen[i] > 0.0 and r[i] > 0.0:
            for a in range(2):
                if sd[i * 2 + a] > spread * means[(i * B + a) * d + 2]:
                    lost[i] = True
            if lost[i]:
                u[i] = False
                freed += 1
    if freed:
        for k in range(n):
            if lab[k] >= 0 and lost[lab[k]]:
                lab[k] = -1
    return freed
