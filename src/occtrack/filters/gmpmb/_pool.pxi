# ---- pool.py: the pool's order, the merging of components, births ---------------------------

from libc.stdlib cimport free, malloc


cdef int _rotate_c(char* a, Py_ssize_t n, Py_ssize_t size, Py_ssize_t p,
                   Py_ssize_t t) except -1:
    """Rows (of `size` bytes) a[p:] become a[t:] followed by a[p:t]."""
    if n - p <= 0 or size == 0:
        return 0
    cdef char* tail = <char*>malloc((n - p) * size)
    if tail == NULL:
        raise MemoryError()
    memcpy(tail, a + p * size, (n - p) * size)
    memcpy(a + p * size, tail + (t - p) * size, (n - t) * size)
    memcpy(a + (p + n - t) * size, tail, (t - p) * size)
    free(tail)
    return 0


cdef int _permute_c(char* a, Py_ssize_t n, Py_ssize_t size, const i64* order) except -1:
    """a[:] = a[order] for rows of `size` bytes."""
    if n == 0 or size == 0:
        return 0
    cdef char* copy = <char*>malloc(n * size)
    cdef Py_ssize_t i
    if copy == NULL:
        raise MemoryError()
    memcpy(copy, a, n * size)
    for i in range(n):
        memcpy(a + i * size, copy + order[i] * size, size)
    free(copy)
    return 0


def _sort_pool(mass, mean, cov, det, occ, coast, label):
    """Stable sort of the pool's arrays (views of its first n entries) by label, in place.
    The usual pool is sorted but for the births appended at its end (label -1): then the
    stable sort is a rotation that moves them in front of the labelled components."""
    cdef char* arrays[7]
    cdef Py_ssize_t sizes[7]
    arrays[0] = <char*>doubles(mass, 1, "mass")
    arrays[1] = <char*>doubles(mean, 3, "mean")
    arrays[2] = <char*>doubles(cov, 4, "cov")
    arrays[3] = <char*>doubles(det, 1, "det")
    arrays[4] = <char*>doubles(occ, 1, "occ")
    arrays[5] = <char*>doubles(coast, 1, "coast")
    cdef i64* lab = integers(label, 1, "label")
    arrays[6] = <char*>lab
    sizes[0], sizes[1], sizes[2] = 8, row_bytes(mean), row_bytes(cov)
    sizes[3], sizes[4], sizes[5], sizes[6] = 8, 8, 8, 8
    cdef Py_ssize_t n = dim(label, 0), t, p, k, i, a
    t = n
    while t > 0 and lab[t - 1] == -1:
        t -= 1
    p = 0
    while p < t and lab[p] == -1:
        p += 1
    cdef bint sorted_ = True
    for k in range(p + 1, t):
        if lab[k] < lab[k - 1]:
            sorted_ = False
            break
    if sorted_:
        if p < t < n:
            for a in range(7):
                _rotate_c(arrays[a], n, sizes[a], p, t)
        return
    cdef cnp.ndarray order_ = new_integers(1, n), work_ = new_integers(1, n)
    cdef i64* order = idata(order_)
    argsort_stable(lab, n, order, idata(work_))
    for i in range(n):
        if order[i] != i:
            break
    else:
        return
    for a in range(7):
        _permute_c(arrays[a], n, sizes[a], order)


def _rotate(a, Py_ssize_t p, Py_ssize_t t):
    """a[p:] becomes a[t:] followed by a[p:t]."""
    cdef cnp.ndarray arr = contiguous(a, "a")
    _rotate_c(<char*>cnp.PyArray_DATA(arr), cnp.PyArray_DIM(arr, 0), row_bytes(arr), p, t)


cdef cnp.ndarray _cell_keys_c(const f64* mean, const i64* label, const f64* cell, Py_ssize_t n,
                              Py_ssize_t B, Py_ssize_t d):
    cdef cnp.ndarray key_ = new_integers(2, n, 8)
    cdef i64* key = idata(key_)
    cdef Py_ssize_t k, axis, r
    cdef double octave, scale
    for k in range(n):
        octave = rint(log2(py_max(2.0 * mean[(k * B + 1) * d + 2], MIN_HEIGHT)))
        scale = exp2(octave)
        key[k * 8], key[k * 8 + 1] = label[k], <i64>octave
        for axis in range(2):
            for r in range(3):
                key[k * 8 + 2 + 3 * axis + r] = <i64>floor(
                    mean[(k * B + axis) * d + r] / (cell[3 * axis + r] * scale))
    return key_


def _cell_keys(mean, label, cell):
    """Per component (label, octave, the six cell indices): octave = round(log2 h) of its box
    height h, cell index = floor(state / (cell width 2^octave))."""
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* c = doubles(cell, 1, "cell")
    return _cell_keys_c(mu, lab, c, dim(mean, 0), dim(mean, 1), dim(mean, 2))


cdef tuple _packed_order_c(const i64* key, Py_ssize_t n, Py_ssize_t width):
    cdef cnp.ndarray low_ = new_integers(1, width), high_ = new_integers(1, width)
    cdef cnp.ndarray span_ = new_integers(1, width)
    cdef i64* low = idata(low_)
    cdef i64* high = idata(high_)
    cdef i64* span = idata(span_)
    cdef Py_ssize_t k, c, i
    if n == 0:
        return True, new_integers(1, 0), new_booleans(1, 0)
    for c in range(width):
        low[c] = key[c]
        high[c] = key[c]
    for k in range(n):
        for c in range(width):
            low[c] = py_imin(low[c], key[k * width + c])
            high[c] = py_imax(high[c], key[k * width + c])
    cdef double bits = 0.0
    for c in range(width):
        # (numba's int64 arithmetic wraps: so does this one)
        span[c] = <i64>(<uint64_t>high[c] - <uint64_t>low[c] + 1)
        bits += log2(<double>span[c])
    if not bits < 62:
        return False, zero_integers(1, 0), zero_booleans(1, 0)
    cdef cnp.ndarray packed_ = zero_integers(1, n)
    cdef i64* packed = idata(packed_)
    for k in range(n):
        for c in range(width):
            packed[k] = packed[k] * span[c] + (key[k * width + c] - low[c])
    cdef cnp.ndarray order_ = new_integers(1, n), work_ = new_integers(1, n)
    cdef i64* order = idata(order_)
    argsort_stable(packed, n, order, idata(work_))
    cdef cnp.ndarray start_ = new_booleans(1, n)
    cdef b8* start = bdata(start_)
    start[0] = True
    for i in range(1, n):
        start[i] = packed[order[i]] != packed[order[i - 1]]
    return True, order_, start_


def _packed_order(key):
    """(fits, order, start): the rows of `key` sorted (stable) by packing each into one
    integer of mixed radix, and where a new key starts; fits is False when the packed
    integers would not fit in 62 bits."""
    cdef const i64* k = integers(key, 2, "key")
    return _packed_order_c(k, dim(key, 0), dim(key, 1))


cdef tuple _pool_cells_c(const i64* order, const b8* start, Py_ssize_t N, const f64* mass,
                         const f64* mean, const f64* cov, const f64* det, const f64* occ,
                         const f64* coast, const i64* label, Py_ssize_t B, Py_ssize_t d):
    cdef Py_ssize_t G = 0, i, g, k, b, r, c
    for i in range(N):
        G += start[i]
    if N and not start[0]:
        raise ValueError("start: the first entry opens a cell")
    cdef cnp.ndarray out_mass_ = zero_doubles(1, G), out_mean_ = zero_doubles(3, G, B, d)
    cdef cnp.ndarray out_cov_ = zero_doubles(4, G, B, d, d)
    cdef cnp.ndarray out_det_ = zero_doubles(1, G), out_occ_ = zero_doubles(1, G)
    cdef cnp.ndarray out_coast_ = zero_doubles(1, G), out_label_ = new_integers(1, G)
    cdef cnp.ndarray first_ = new_integers(1, G + 1)
    cdef f64* out_mass = fdata(out_mass_)
    cdef f64* out_mean = fdata(out_mean_)
    cdef f64* out_cov = fdata(out_cov_)
    cdef f64* out_det = fdata(out_det_)
    cdef f64* out_occ = fdata(out_occ_)
    cdef f64* out_coast = fdata(out_coast_)
    cdef i64* out_label = idata(out_label_)
    cdef i64* first = idata(first_)
    cdef double total, share, dev_r, dev_c
    g = -1
    for i in range(N):
        if start[i]:
            g += 1
            first[g] = i
        out_mass[g] += mass[order[i]]
    first[G] = N
    for g in range(G):
        total = out_mass[g]
        out_label[g] = label[order[first[g]]]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    out_mean[(g * B + b) * d + r] += share * mean[(k * B + b) * d + r]
            out_det[g] += share * det[k]
            out_occ[g] += share * occ[k]
            out_coast[g] += share * coast[k]
        for i in range(first[g], first[g + 1]):
            k = order[i]
            share = mass[k] / total
            for b in range(B):
                for r in range(d):
                    dev_r = mean[(k * B + b) * d + r] - out_mean[(g * B + b) * d + r]
                    for c in range(d):
                        dev_c = mean[(k * B + b) * d + c] - out_mean[(g * B + b) * d + c]
                        out_cov[((g * B + b) * d + r) * d + c] += share * (
                            cov[((k * B + b) * d + r) * d + c] + dev_r * dev_c)
    return out_mass_, out_mean_, out_cov_, out_det_, out_occ_, out_coast_, out_label_


def _pool_cells(order, start, mass, mean, cov, det, occ, coast, label):
    """Moment matching of the runs of `order` that `start` opens (one run a cell): mass
    W = sum w_k, mean mu = sum s_k m_k and covariance sum s_k (P_k + (m_k - mu)(m_k - mu)')
    with shares s_k = w_k / W; d, o and the coasting time are share-weighted means. A
    component alone in its cell comes out unchanged."""
    cdef const i64* o = integers(order, 1, "order")
    cdef const b8* s = booleans(start, 1, "start")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const f64* P = doubles(cov, 4, "cov")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef const i64* lab = integers(label, 1, "label")
    return _pool_cells_c(o, s, dim(order, 0), m, mu, P, de, oc, co, lab, dim(mean, 1),
                         dim(mean, 2))


def _merge_packed(mean, label, cell, mass, cov, det, occ, coast):
    """(fits, cell keys, the pool merged): `_cell_keys`, then `_packed_order` and
    `_pool_cells` when the packed keys fit (else the pool comes back as given, for the
    lexsort path), and the pool as given when no two components share a cell."""
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* ce = doubles(cell, 1, "cell")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* P = doubles(cov, 4, "cov")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef Py_ssize_t n = dim(mean, 0), B = dim(mean, 1), d = dim(mean, 2), i
    cdef cnp.ndarray key_ = _cell_keys_c(mu, lab, ce, n, B, d)
    cdef cnp.ndarray order_, start_
    fits, order_, start_ = _packed_order_c(idata(key_), n, 8)
    cdef const b8* start = bdata(start_)
    if fits:
        for i in range(dim(start_, 0)):
            if not start[i]:
                return True, key_, _pool_cells_c(idata(order_), start, dim(order_, 0), m, mu, P,
                                                 de, oc, co, lab, B, d)
    return fits, key_, (mass, mean, cov, det, occ, coast, label)


cdef inline void _learnt_sizes_c(const f64* count, const f64* total, const f64* squares,
                                 Py_ssize_t n, f64* mean, f64* std) noexcept nogil:
    cdef Py_ssize_t i
    for i in range(n):
        mean[i] = total[i] / count[i]
    for i in range(n):
        std[i] = sqrt(npmaximum(squares[i] / count[i] - mean[i] * mean[i], 1.0))


def _learnt_sizes(count, total, squares):
    """Mean half-size of the detections counted and its standard deviation (at least 1 px)."""
    cdef const f64* c = doubles(count, 1, "count")
    cdef const f64* t = doubles(total, 1, "total")
    cdef const f64* s = doubles(squares, 1, "squares")
    cdef Py_ssize_t n = dim(total, 0)
    cdef cnp.ndarray mean_ = new_doubles(1, n), std_ = new_doubles(1, n)
    _learnt_sizes_c(c, t, s, n, fdata(mean_), fdata(std_))
    return mean_, std_


def _prior_sizes(stats, setting_mean, setting_std):
    """`GaussianMixturePMB._size_prior` from the running count, sum and sum of squares
    `stats` (3, 2) and the configured mean and std (empty: not set)."""
    cdef const f64* st = doubles(stats, 2, "stats")
    cdef const f64* sm = doubles(setting_mean, 1, "setting_mean")
    cdef const f64* ss = doubles(setting_std, 1, "setting_std")
    cdef Py_ssize_t S = dim(stats, 1), n_mean = dim(setting_mean, 0)
    cdef Py_ssize_t n_std = dim(setting_std, 0), i, n_out
    cdef bint learnt = st[0] >= 2
    cdef cnp.ndarray learnt_mean_ = zero_doubles(1, 2), learnt_std_ = zero_doubles(1, 2)
    if learnt:
        learnt_mean_, learnt_std_ = new_doubles(1, S), new_doubles(1, S)
        _learnt_sizes_c(st, st + S, st + 2 * S, S, fdata(learnt_mean_), fdata(learnt_std_))
    cdef cnp.ndarray mean_
    if n_mean:
        mean_ = new_doubles(1, n_mean)
        for i in range(n_mean):
            fdata(mean_)[i] = sm[i]
    elif learnt:
        mean_ = learnt_mean_
    else:
        mean_ = new_doubles(1, 2)
        fdata(mean_)[0], fdata(mean_)[1] = 30.0, 90.0
    cdef const f64* mean = fdata(mean_)
    cdef const f64* std = NULL  # (NULL: a third of the mean)
    if n_std:
        std, n_out = ss, n_std
    elif learnt:
        std, n_out = fdata(learnt_std_), dim(learnt_std_, 0)
    else:
        n_out = dim(mean_, 0)
    cdef cnp.ndarray out_ = new_doubles(1, n_out)
    for i in range(n_out):
        fdata(out_)[i] = npmaximum(std[i] if std != NULL else mean[i] / 3.0, 1.0)
    return mean_, out_


def _count_sizes(z, observed, stats):
    """Add the half-sizes of the detections with every edge measured to the running count,
    sum and sum of squares `stats` (3, 2)."""
    cdef const f64* zz = doubles(z, 3, "z")
    cdef const b8* ob = booleans(observed, 3, "observed")
    cdef f64* st = doubles(stats, 2, "stats")
    cdef Py_ssize_t M = dim(z, 0), Z1 = dim(z, 1), Z2 = dim(z, 2), S = dim(stats, 1)
    cdef Py_ssize_t O1 = dim(observed, 1), O2 = dim(observed, 2), j, axis
    cdef bint full
    cdef double half
    for j in range(M):
        full = True
        for axis in range(2):
            full = full and ob[(j * O1 + axis) * O2] and ob[(j * O1 + axis) * O2 + 1]
        if full:
            for axis in range(2):
                half = 0.5 * (zz[(j * Z1 + axis) * Z2 + 1] - zz[(j * Z1 + axis) * Z2])
                st[axis] += 1.0
                st[S + axis] += half
                st[2 * S + axis] += half * half


def _append_births(Py_ssize_t n, mass, means, covs, double det, double occ, pool_mass,
                   pool_mean, pool_cov, pool_det, pool_occ, pool_label, pool_coast):
    """Append the birth components of positive mass to the pool after its first n (the
    Poisson part: label -1, never missed, d and o the births'); returns the new n."""
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mu = doubles(means, 3, "means")
    cdef const f64* P = doubles(covs, 4, "covs")
    cdef f64* pm = doubles(pool_mass, 1, "pool_mass")
    cdef f64* pmu = doubles(pool_mean, 3, "pool_mean")
    cdef f64* pP = doubles(pool_cov, 4, "pool_cov")
    cdef f64* pd = doubles(pool_det, 1, "pool_det")
    cdef f64* po = doubles(pool_occ, 1, "pool_occ")
    cdef i64* pl = integers(pool_label, 1, "pool_label")
    cdef f64* pc = doubles(pool_coast, 1, "pool_coast")
    cdef Py_ssize_t size_mean = row_bytes(pool_mean), size_cov = row_bytes(pool_cov), b
    if row_bytes(means) != size_mean or row_bytes(covs) != size_cov:
        raise ValueError("means, covs: the pool's state shape is needed")
    cdef Py_ssize_t w_mean = size_mean // 8, w_cov = size_cov // 8
    for b in range(dim(mass, 0)):
        if m[b] > 0:
            pm[n] = m[b]
            memcpy(pmu + n * w_mean, mu + b * w_mean, size_mean)
            memcpy(pP + n * w_cov, P + b * w_cov, size_cov)
            pd[n], po[n], pl[n], pc[n] = det, occ, -1, 0.0
            n += 1
    return n
