# ---- children.py: the update's children -------------------------------------------------------

def _children(mass, miss, rows, hit, pj, edge_of_pair, strong, p_hit, L_edge, p_new, w_new,
              p_miss, miss_obj):
    """The children's masses: the miss child of each component, w_k miss_k p_miss_i / miss_i
    (the Poisson part's: w_k miss_k), then the hit child of each pair, l_kj p_hit_ij / L_ij
    (Poisson: l_kj p_new_j / L_0j). p_hit is given on the `strong` edges, in order."""
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mi = doubles(miss, 1, "miss")
    cdef const i64* ro = integers(rows, 1, "rows")
    cdef const f64* hi = doubles(hit, 1, "hit")
    cdef const i64* j_ = integers(pj, 1, "pj")
    cdef const i64* ep = integers(edge_of_pair, 1, "edge_of_pair")
    cdef const b8* st = booleans(strong, 1, "strong")
    cdef const f64* ph = doubles(p_hit, 1, "p_hit")
    cdef const f64* Le = doubles(L_edge, 1, "L_edge")
    cdef const f64* pn = doubles(p_new, 1, "p_new")
    cdef const f64* wn = doubles(w_new, 1, "w_new")
    cdef const f64* pm = doubles(p_miss, 1, "p_miss")
    cdef const f64* mo = doubles(miss_obj, 1, "miss_obj")
    cdef Py_ssize_t n = dim(mass, 0), P = dim(hit, 0), A = dim(miss_obj, 0)
    cdef Py_ssize_t E = dim(L_edge, 0), e, s, k, p
    cdef cnp.ndarray edge_factor_ = zero_doubles(1, E)
    cdef f64* edge_factor = fdata(edge_factor_)
    s = 0
    for e in range(E):
        if st[e]:
            edge_factor[e] = ph[s] / Le[e]
            s += 1
    cdef cnp.ndarray out_ = new_doubles(1, n + P)
    cdef f64* out = fdata(out_)
    cdef double factor
    for k in range(n):
        factor = pm[ro[k]] / mo[ro[k]] if ro[k] < A else 1.0
        out[k] = m[k] * mi[k] * factor
    for p in range(P):
        e = ep[p]
        out[n + p] = hi[p] * (edge_factor[e] if e >= 0 else pn[j_[p]] / wn[j_[p]])
    return out_


cdef tuple _child_parents_c(const i64* keep_in, Py_ssize_t K, Py_ssize_t n, const i64* pk,
                            const i64* pj, i64 M, const f64* children):
    cdef cnp.ndarray parent_ = new_integers(1, K), j_ = new_integers(1, K)
    cdef cnp.ndarray key_ = new_integers(1, K), order_ = new_integers(1, K)
    cdef cnp.ndarray work_ = new_integers(1, K)
    cdef i64* parent = idata(parent_)
    cdef i64* j = idata(j_)
    cdef i64* key = idata(key_)
    cdef i64* order = idata(order_)
    cdef Py_ssize_t c
    for c in range(K):
        if keep_in[c] < n:
            parent[c], j[c] = keep_in[c], -1
        else:
            parent[c], j[c] = pk[keep_in[c] - n], pj[keep_in[c] - n]
        key[c] = parent[c] * (M + 1) + j[c] + 1
    argsort_stable(key, K, order, idata(work_))
    cdef cnp.ndarray keep_out_ = new_integers(1, K), parent_out_ = new_integers(1, K)
    cdef cnp.ndarray j_out_ = new_integers(1, K), mass_ = new_doubles(1, K)
    cdef i64* keep_out = idata(keep_out_)
    cdef i64* parent_out = idata(parent_out_)
    cdef i64* j_out = idata(j_out_)
    cdef f64* mass = fdata(mass_)
    for c in range(K):
        keep_out[c] = keep_in[order[c]]
        parent_out[c] = parent[order[c]]
        j_out[c] = j[order[c]]
    for c in range(K):
        mass[c] = children[keep_out[c]]
    return keep_out_, parent_out_, j_out_, mass_


def _child_parents(keep, Py_ssize_t n, pk, pj, i64 M, children):
    """(kept children, their parent component, their detection (-1: miss), their mass) in
    the order of the parents, a miss child before its hit children."""
    cdef const i64* ke = integers(keep, 1, "keep")
    cdef const i64* k_ = integers(pk, 1, "pk")
    cdef const i64* j_ = integers(pj, 1, "pj")
    cdef const f64* ch = doubles(children, 1, "children")
    return _child_parents_c(ke, dim(keep, 0), n, k_, j_, M, ch)


cdef cnp.ndarray _trim_c(f64* mass, const i64* label, const i64* measurement, Py_ssize_t n,
                         Py_ssize_t cap, i64 L):
    cdef cnp.ndarray key_ = new_integers(1, n)
    cdef i64* key = idata(key_)
    cdef i64 top = -1
    cdef Py_ssize_t c
    for c in range(n):
        key[c] = label[c] if label[c] >= 0 else (L + measurement[c] if measurement[c] >= 0
                                                 else -1)
        top = py_imax(top, key[c])
    cdef cnp.ndarray keep_ = new_booleans(1, n)
    cdef b8* keep = bdata(keep_)
    for c in range(n):
        keep[c] = True
    cdef cnp.ndarray counts_ = zero_integers(1, top + 2)
    cdef i64* counts = idata(counts_)
    cdef bint over = False
    for c in range(n):
        if key[c] >= 0:
            counts[key[c]] += 1
            over = over or counts[key[c]] > cap
    if not over:
        return keep_
    cdef cnp.ndarray scratch_ = new_integers(2, 4, n)
    cdef i64* order = idata(scratch_)
    cdef i64* work = order + n
    cdef i64* rank_order = order + 2 * n
    cdef i64* ranked = order + 3 * n
    cdef cnp.ndarray negative_ = new_doubles(1, n)
    cdef f64* negative = fdata(negative_)
    argsort_stable(key, n, order, work)
    cdef Py_ssize_t first = 0, last, size, rank, i
    cdef const i64* members
    cdef double total, kept_total, scale
    while first < n:
        last = first
        while last < n and key[order[last]] == key[order[first]]:
            last += 1
        if key[order[first]] >= 0 and last - first > cap:
            members = order + first
            size = last - first
            for i in range(size):
                negative[i] = -mass[members[i]]
            argsort_stable(negative, size, rank_order, work)
            for i in range(size):
                ranked[i] = members[rank_order[i]]
            total, kept_total = 0.0, 0.0
            for rank in range(size):
                total += mass[ranked[rank]]
                if rank < cap:
                    kept_total += mass[ranked[rank]]
                else:
                    keep[ranked[rank]] = False
            scale = total / py_max(kept_total, 1e-300)
            for i in range(size):
                mass[members[i]] *= scale
        first = last
    return keep_


def _trim(mass, label, measurement, Py_ssize_t cap, i64 L):
    """Which children to keep when each Bernoulli keeps at most `cap` (its heaviest): the
    mask, the kept ones' masses scaled in place so that its existence is unchanged (only its
    density loses the tail). An object is a label (< L), or, born this step, the Poisson
    part's hit children of one measurement, keyed L + j; the Poisson part's miss children
    (key -1) are an intensity and are not trimmed."""
    cdef f64* m = doubles(mass, 1, "mass")
    cdef const i64* lab = integers(label, 1, "label")
    cdef const i64* me = integers(measurement, 1, "measurement")
    return _trim_c(m, lab, me, dim(mass, 0), cap, L)


def _kept_children(children, selected, double prune_mass, Py_ssize_t n, pk, pj, i64 M, label,
                   Py_ssize_t cap, i64 L):
    """The children kept, as `_child_parents` gives them: those `selected` (None: those
    heavier than prune_mass), then, when cap > 0, at most cap per object (`_trim`, masses
    rescaled)."""
    cdef const f64* ch = doubles(children, 1, "children")
    cdef const i64* k_ = integers(pk, 1, "pk")
    cdef const i64* j_ = integers(pj, 1, "pj")
    cdef const i64* lab = integers(label, 1, "label")
    cdef Py_ssize_t N = dim(children, 0), K, c, i
    cdef cnp.ndarray keep_
    if selected is None:
        K = 0
        for c in range(N):
            K += ch[c] > prune_mass
        keep_ = new_integers(1, K)
        K = 0
        for c in range(N):
            if ch[c] > prune_mass:
                idata(keep_)[K] = c
                K += 1
    else:
        integers(selected, 1, "selected")
        keep_ = <cnp.ndarray>selected
    cdef cnp.ndarray parent_, jj_, mass_, label_of_, trim_
    keep_, parent_, jj_, mass_ = _child_parents_c(idata(keep_), dim(keep_, 0), n, k_, j_, M, ch)
    if cap:
        K = dim(parent_, 0)
        label_of_ = new_integers(1, K)
        for c in range(K):
            idata(label_of_)[c] = lab[idata(parent_)[c]]
        trim_ = _trim_c(fdata(mass_), idata(label_of_), idata(jj_), K, cap, L)
        i = 0
        for c in range(K):
            i += bdata(trim_)[c] != 0
        if i < K:
            keep_, parent_ = _compress_i64(keep_, bdata(trim_), K, i), _compress_i64(
                parent_, bdata(trim_), K, i)
            jj_ = _compress_i64(jj_, bdata(trim_), K, i)
            mass_ = _compress_f64(mass_, bdata(trim_), K, i)
    return keep_, parent_, jj_, mass_


cdef cnp.ndarray _compress_i64(cnp.ndarray a, const b8* mask, Py_ssize_t K, Py_ssize_t count):
    """a[mask] of an int64 array."""
    cdef cnp.ndarray out_ = new_integers(1, count)
    cdef Py_ssize_t c, i = 0
    for c in range(K):
        if mask[c]:
            idata(out_)[i] = idata(a)[c]
            i += 1
    return out_


cdef cnp.ndarray _compress_f64(cnp.ndarray a, const b8* mask, Py_ssize_t K, Py_ssize_t count):
    """a[mask] of a float64 array."""
    cdef cnp.ndarray out_ = new_doubles(1, count)
    cdef Py_ssize_t c, i = 0
    for c in range(K):
        if mask[c]:
            fdata(out_)[i] = fdata(a)[c]
            i += 1
    return out_


def _inherit(mean, cov, label, parent, j):
    """Each child's copy of its parent's mean, covariance and label, the hit children (j >= 0)
    and the detection each child of the Poisson part was born from (-1 for the others)."""
    doubles(mean, 3, "mean")
    doubles(cov, 4, "cov")
    cdef const i64* lab = integers(label, 1, "label")
    cdef const i64* pa = integers(parent, 1, "parent")
    cdef const i64* jj = integers(j, 1, "j")
    cdef Py_ssize_t K = dim(parent, 0), c, hits = 0
    cdef cnp.ndarray new_mean_ = take_rows(mean, pa, K), new_cov_ = take_rows(cov, pa, K)
    cdef cnp.ndarray new_label_ = new_integers(1, K), newborn_ = new_integers(1, K)
    cdef i64* new_label = idata(new_label_)
    cdef i64* newborn = idata(newborn_)
    for c in range(K):
        newborn[c] = -1
    for c in range(K):
        new_label[c] = lab[pa[c]]
        if jj[c] >= 0:
            hits += 1
            if new_label[c] < 0:
                newborn[c] = jj[c]
    cdef cnp.ndarray h_ = new_integers(1, hits)
    hits = 0
    for c in range(K):
        if jj[c] >= 0:
            idata(h_)[hits] = c
            hits += 1
    return new_mean_, new_cov_, new_label_, h_, newborn_


def _child_features(parent, j, det, occ, occ_all, established, v, q, miss, seen_hidden, coast,
                    double dt):
    """d, o and the coasting time of each child (of component parent[c], by detection j[c],
    -1 for the miss child), by Bayes. Missed: P(D=1 | miss) = d o (1 - v + v q) / miss and
    P(O=1 | miss) = o (1 - d + d (1 - v + v q)) / miss. Hit by z_j: D = 1 and
    P(O=1 | hit) = o v (1 - h_j) / (1 - o + o v (1 - h_j)). `occ` is 0 for the components of
    objects not confirmed, whose o (`occ_all`) is carried unchanged."""
    cdef const i64* pa = integers(parent, 1, "parent")
    cdef const i64* jj = integers(j, 1, "j")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* oa = doubles(occ_all, 1, "occ_all")
    cdef const b8* es = booleans(established, 1, "established")
    cdef const f64* v_ = doubles(v, 1, "v")
    cdef const f64* q_ = doubles(q, 1, "q")
    cdef const f64* mi = doubles(miss, 1, "miss")
    cdef const f64* sh = doubles(seen_hidden, 1, "seen_hidden")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef Py_ssize_t C = dim(parent, 0), c, k
    cdef cnp.ndarray new_det_ = new_doubles(1, C), new_occ_ = new_doubles(1, C)
    cdef cnp.ndarray new_coast_ = new_doubles(1, C)
    cdef f64* new_det = fdata(new_det_)
    cdef f64* new_occ = fdata(new_occ_)
    cdef f64* new_coast = fdata(new_coast_)
    cdef double d, o, vv, mm, hidden_if_occludable, escaped, seen_o, missed_o
    for c in range(C):
        k = pa[c]
        d, o, vv, mm = de[k], oc[k], v_[k], py_max(mi[k], 1e-300)
        hidden_if_occludable = 1.0 - vv + vv * q_[k]
        if jj[c] >= 0:
            new_det[c] = 1.0
            escaped = vv * (1.0 - sh[jj[c]])
            seen_o = o * escaped / py_max(1.0 - o + o * escaped, 1e-300)
            new_occ[c] = seen_o if es[k] else oa[k]
            new_coast[c] = 0.0
        else:
            new_det[c] = d * o * hidden_if_occludable / mm
            missed_o = o * (1.0 - d + d * hidden_if_occludable) / mm
            new_occ[c] = missed_o if es[k] else oa[k]
            new_coast[c] = co[k] + dt
    return new_det_, new_occ_, new_coast_
