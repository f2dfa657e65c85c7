# ---- weights.py: the update's weights ------------------------------------------------------

LOG_FLOOR = -300.0
cdef double HIT_FLOOR = math.exp(LOG_FLOOR)  # (libm's exp, as numba's math.exp)


def _occludable(label, mass, occ_all, used, hits, i64 confirm_hits, double stationary):
    """(established, o, o_seen, r per slot, w_k / r of its object) of each component:
    occlusion is for the components of confirmed objects (`GaussianMixturePMB.confirmed`: used
    slots with `confirm_hits` hits; o = 0 for the others; o_seen, the
    o that weighs a detection's source, is the `stationary` occludability for them); the
    Poisson part's components keep w_k."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* oa = doubles(occ_all, 1, "occ_all")
    cdef const b8* u = booleans(used, 1, "used")
    cdef const i64* hi = integers(hits, 1, "hits")
    cdef Py_ssize_t n = dim(label, 0), k
    cdef i64 i
    cdef cnp.ndarray r_ = _label_sums_c(lab, m, n, dim(used, 0))
    cdef const f64* r = fdata(r_)
    cdef cnp.ndarray established_ = zero_booleans(1, n), occ_ = zero_doubles(1, n)
    cdef cnp.ndarray o_seen_ = new_doubles(1, n), within_ = new_doubles(1, n)
    cdef b8* established = bdata(established_)
    cdef f64* occ = fdata(occ_)
    cdef f64* o_seen = fdata(o_seen_)
    cdef f64* within = fdata(within_)
    for k in range(n):
        o_seen[k] = stationary
    for k in range(n):
        i = lab[k]
        if i >= 0:
            established[k] = u[i] and hi[i] >= confirm_hits
            if established[k]:
                occ[k] = oa[k]
                o_seen[k] = oa[k]
            within[k] = m[k] / py_max(r[i], 1e-300)
        else:
            within[k] = m[k]
    return established_, occ_, o_seen_, r_, within_


def _miss_terms(det, occ, visible, hidden):
    """(v, q, P_D, miss) per component, v and q clipped to [0, 1]: P_D = d (1 - o + o v) and
    miss = 1 - P_D + d o v q (the occlusion line of `occtrack.filters.gmpmb`'s docstring)."""
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* vis = doubles(visible, 1, "visible")
    cdef const f64* hid = doubles(hidden, 1, "hidden")
    cdef Py_ssize_t n = dim(det, 0), k
    cdef cnp.ndarray v_ = new_doubles(1, n), q_ = new_doubles(1, n)
    cdef cnp.ndarray pd_ = new_doubles(1, n), miss_ = new_doubles(1, n)
    cdef f64* v = fdata(v_)
    cdef f64* q = fdata(q_)
    cdef f64* pd = fdata(pd_)
    cdef f64* miss = fdata(miss_)
    for k in range(n):
        v[k] = py_min(py_max(vis[k], 0.0), 1.0)
        q[k] = py_min(py_max(hid[k], 0.0), 1.0)
        pd[k] = de[k] * (1.0 - oc[k] + oc[k] * v[k])
        miss[k] = 1.0 - pd[k] + de[k] * oc[k] * v[k] * q[k]
    return v_, q_, pd_, miss_


def _clipped(x, double low, double high):
    """np.clip(x, low, high) as a new array (numpy's clip costs more than the loop here)."""
    cdef const f64* xx = doubles(x, 1, "x")
    cdef Py_ssize_t n = dim(x, 0), i
    cdef cnp.ndarray out_ = new_doubles(1, n)
    cdef f64* out = fdata(out_)
    for i in range(n):
        out[i] = py_min(py_max(xx[i], low), high)
    return out_


def _object_rows(label, used):
    """(the used slots, each component's object row): rows 0..A-1 are the used slots in
    order, row A the Poisson part."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const b8* u = booleans(used, 1, "used")
    cdef Py_ssize_t L = dim(used, 0), n = dim(label, 0), A = 0, s, k
    for s in range(L):
        A += u[s] != 0
    cdef cnp.ndarray slots_ = new_integers(1, A), row_of_slot_ = new_integers(1, L)
    cdef i64* slots = idata(slots_)
    cdef i64* row_of_slot = idata(row_of_slot_)
    cdef Py_ssize_t a = 0
    for s in range(L):
        row_of_slot[s] = A
        if u[s]:
            slots[a] = s
            row_of_slot[s] = a
            a += 1
    cdef cnp.ndarray rows_ = new_integers(1, n)
    cdef i64* rows = idata(rows_)
    for k in range(n):
        rows[k] = row_of_slot[lab[k]] if lab[k] >= 0 else A
    return slots_, rows_


def _all_pairs(Py_ssize_t n, Py_ssize_t M, rows, Py_ssize_t A):
    """Every (component, detection) pair, component-major (pk, pj), and every (object row,
    detection) pair of the A object rows as a candidate edge: (row, column, candidate of each
    pair; the Poisson part's pairs point past the A M candidates, where nothing reads)."""
    cdef const i64* ro = integers(rows, 1, "rows")
    cdef cnp.ndarray pk_ = new_integers(1, n * M), pj_ = new_integers(1, n * M)
    cdef cnp.ndarray cand_of_pair_ = new_integers(1, n * M)
    cdef i64* pk = idata(pk_)
    cdef i64* pj = idata(pj_)
    cdef i64* cand_of_pair = idata(cand_of_pair_)
    cdef Py_ssize_t k, j, i
    for k in range(n):
        for j in range(M):
            pk[k * M + j] = k
            pj[k * M + j] = j
            cand_of_pair[k * M + j] = ro[k] * M + j
    cdef cnp.ndarray cand_row_ = new_integers(1, A * M), cand_col_ = new_integers(1, A * M)
    cdef i64* cand_row = idata(cand_row_)
    cdef i64* cand_col = idata(cand_col_)
    for i in range(A):
        for j in range(M):
            cand_row[i * M + j] = i
            cand_col[i * M + j] = j
    return pk_, pj_, (cand_row_, cand_col_, cand_of_pair_)


def _hit_edges(pk, pj, log_hit, cand_of_pair, cand_row, cand_col, rows, i64 A, Py_ssize_t M,
               mass, det, o_seen, v, seen_hidden, pd, bint use_seen, label, slot_class,
               classes):
    """The hit weights l_kj = w_k d_k (1 - o_k + o_k v_k (1 - h_j)) p(z_j | x_k) of the pairs
    that are possible (l_kj > e^LOG_FLOOR: below, a pair is impossible, and cutting there
    keeps slow subnormal numbers out; and an object never takes a detection of another
    class, `classes` empty: one class), summed into the association's weights: L_0j of the
    Poisson part, and L_ij on the candidate edges (object row, detection) that any pair
    reaches. Returns the kept pairs (pk, pj, l, edge of each pair, -1 for the Poisson part's),
    L_0j and the edges (row, column, L_ij)."""
    cdef const i64* k_ = integers(pk, 1, "pk")
    cdef const i64* j_ = integers(pj, 1, "pj")
    cdef const f64* lh = doubles(log_hit, 1, "log_hit")
    cdef const i64* cp = integers(cand_of_pair, 1, "cand_of_pair")
    cdef const i64* cr = integers(cand_row, 1, "cand_row")
    cdef const i64* cc = integers(cand_col, 1, "cand_col")
    cdef const i64* ro = integers(rows, 1, "rows")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* os = doubles(o_seen, 1, "o_seen")
    cdef const f64* vv = doubles(v, 1, "v")
    cdef const f64* sh = doubles(seen_hidden, 1, "seen_hidden")
    cdef const f64* p_d = doubles(pd, 1, "pd")
    cdef const i64* lab = integers(label, 1, "label")
    cdef const i64* sc = integers(slot_class, 1, "slot_class")
    cdef const i64* cl = integers(classes, 1, "classes")
    cdef Py_ssize_t P = dim(pk, 0), C = dim(cand_row, 0), e, i, k, j, E, K
    cdef bint one_class = dim(classes, 0) == 0
    cdef cnp.ndarray keep_ = zero_booleans(1, P), hit_ = new_doubles(1, P)
    cdef b8* keep = bdata(keep_)
    cdef f64* hit = fdata(hit_)
    cdef double o, weight, value
    for e in range(P):
        k, j = k_[e], j_[e]
        if use_seen:
            o = os[k]
            weight = m[k] * de[k] * (1.0 - o + o * vv[k] * (1.0 - sh[j]))
        else:
            weight = m[k] * p_d[k]
        value = exp(lh[e]) * py_max(weight, 1e-300)
        if value > HIT_FLOOR and (one_class or lab[k] < 0 or sc[lab[k]] == cl[j]):
            keep[e] = True
            hit[e] = value
    cdef cnp.ndarray poisson_hit_ = zero_doubles(1, M), L_cand_ = zero_doubles(1, C)
    cdef f64* poisson_hit = fdata(poisson_hit_)
    cdef f64* L_cand = fdata(L_cand_)
    for e in range(P):
        if keep[e]:
            if ro[k_[e]] < A:
                L_cand[cp[e]] += hit[e]
            else:
                poisson_hit[j_[e]] += hit[e]
    cdef cnp.ndarray edge_of_cand_ = new_integers(1, C)
    cdef i64* edge_of_cand = idata(edge_of_cand_)
    E = 0
    for i in range(C):
        edge_of_cand[i] = -1
        if L_cand[i] > 0:
            edge_of_cand[i] = E
            E += 1
    cdef cnp.ndarray e_row_ = new_integers(1, E), e_col_ = new_integers(1, E)
    cdef cnp.ndarray L_edge_ = new_doubles(1, E)
    cdef i64* e_row = idata(e_row_)
    cdef i64* e_col = idata(e_col_)
    cdef f64* L_edge = fdata(L_edge_)
    for i in range(C):
        if edge_of_cand[i] >= 0:
            e_row[edge_of_cand[i]] = cr[i]
            e_col[edge_of_cand[i]] = cc[i]
            L_edge[edge_of_cand[i]] = L_cand[i]
    K = 0
    for e in range(P):
        K += keep[e]
    cdef cnp.ndarray out_k_ = new_integers(1, K), out_j_ = new_integers(1, K)
    cdef cnp.ndarray out_hit_ = new_doubles(1, K), out_edge_ = new_integers(1, K)
    cdef i64* out_k = idata(out_k_)
    cdef i64* out_j = idata(out_j_)
    cdef f64* out_hit = fdata(out_hit_)
    cdef i64* out_edge = idata(out_edge_)
    i = 0
    for e in range(P):
        if keep[e]:
            out_k[i], out_j[i], out_hit[i] = k_[e], j_[e], hit[e]
            out_edge[i] = edge_of_cand[cp[e]] if ro[k_[e]] < A else -1
            i += 1
    return out_k_, out_j_, out_hit_, out_edge_, poisson_hit_, e_row_, e_col_, L_edge_


cdef cnp.ndarray _object_misses_c(const i64* rows, Py_ssize_t n, Py_ssize_t A, const f64* mass,
                                  const f64* miss, const f64* det, const f64* occ,
                                  const f64* v, const f64* q, const i64* slots,
                                  f64* slot_hidden, Py_ssize_t L):
    cdef cnp.ndarray sums_ = zero_doubles(2, 3, A + 1)
    cdef f64* r = fdata(sums_)
    cdef f64* miss_mass = r + (A + 1)
    cdef f64* hidden_mass = r + 2 * (A + 1)
    cdef Py_ssize_t k, a
    for k in range(n):
        r[rows[k]] += mass[k]
        miss_mass[rows[k]] += mass[k] * miss[k]
        hidden_mass[rows[k]] += mass[k] * (det[k] * occ[k] * (1.0 - v[k] + v[k] * q[k]))
    for k in range(L):
        slot_hidden[k] = 0.0
    cdef cnp.ndarray miss_obj_ = new_doubles(1, A)
    cdef f64* miss_obj = fdata(miss_obj_)
    for a in range(A):
        slot_hidden[slots[a]] = hidden_mass[a] / py_max(miss_mass[a], 1e-300)
        miss_obj[a] = py_max(1.0 - r[a] + miss_mass[a], 1e-300)
    return miss_obj_


def _object_misses(rows, Py_ssize_t A, mass, miss, det, occ, v, q, slots, slot_hidden):
    """miss_i = 1 - r_i + sum_{k in i} w_k miss_k of each object row (floored at 1e-300),
    and, in place, each slot's probability that occlusion caused a miss:
    sum w_k d_k o_k (1 - v_k + v_k q_k) / sum w_k miss_k."""
    cdef const i64* ro = integers(rows, 1, "rows")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mi = doubles(miss, 1, "miss")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* vv = doubles(v, 1, "v")
    cdef const f64* qq = doubles(q, 1, "q")
    cdef const i64* sl = integers(slots, 1, "slots")
    cdef f64* sh = doubles(slot_hidden, 1, "slot_hidden")
    return _object_misses_c(ro, dim(rows, 0), A, m, mi, de, oc, vv, qq, sl, sh,
                            dim(slot_hidden, 0))


cdef cnp.ndarray _new_weights_c(const f64* clutter, Py_ssize_t M, const f64* seen_hidden,
                                const f64* poisson_hit, double occludability):
    cdef cnp.ndarray w_new_ = new_doubles(1, M)
    cdef f64* w_new = fdata(w_new_)
    cdef Py_ssize_t j
    for j in range(M):
        w_new[j] = clutter[j] * (1.0 - occludability * seen_hidden[j]) + poisson_hit[j]
    return w_new_


def _new_weights(clutter, seen_hidden, poisson_hit, double occludability):
    """L_0j = kappa p_F(z_j) (1 - o h_j) + the Poisson part's hit weights, kappa p_F(z_j)
    given as `clutter` (the measurement model's clutter density)."""
    cdef const f64* cl = doubles(clutter, 1, "clutter")
    cdef const f64* sh = doubles(seen_hidden, 1, "seen_hidden")
    cdef const f64* ph = doubles(poisson_hit, 1, "poisson_hit")
    return _new_weights_c(cl, dim(clutter, 0), sh, ph, occludability)


cdef tuple _strong_edges_c(const i64* row, const i64* col, const f64* L_edge, Py_ssize_t E,
                           const f64* miss_obj, const f64* w_new, double floor_):
    cdef cnp.ndarray strong_ = new_booleans(1, E)
    cdef b8* strong = bdata(strong_)
    cdef Py_ssize_t e, i, count = 0
    for e in range(E):
        strong[e] = floor_ == 0.0 or L_edge[e] >= floor_ * miss_obj[row[e]] * w_new[col[e]]
        count += strong[e]
    cdef cnp.ndarray s_row_ = new_integers(1, count), s_col_ = new_integers(1, count)
    cdef cnp.ndarray s_L_ = new_doubles(1, count)
    cdef i64* s_row = idata(s_row_)
    cdef i64* s_col = idata(s_col_)
    cdef f64* s_L = fdata(s_L_)
    i = 0
    for e in range(E):
        if strong[e]:
            s_row[i], s_col[i], s_L[i] = row[e], col[e], L_edge[e]
            i += 1
    return strong_, s_row_, s_col_, s_L_


def _strong_edges(row, col, L_edge, miss_obj, w_new, double floor):
    """The edges with L_ij >= floor miss_i w_new_j (floor 0: every edge): (mask, their rows,
    columns and L_ij)."""
    cdef const i64* r = integers(row, 1, "row")
    cdef const i64* c = integers(col, 1, "col")
    cdef const f64* L = doubles(L_edge, 1, "L_edge")
    cdef const f64* mo = doubles(miss_obj, 1, "miss_obj")
    cdef const f64* wn = doubles(w_new, 1, "w_new")
    return _strong_edges_c(r, c, L, dim(L_edge, 0), mo, wn, floor)


def _association_weights(rows, Py_ssize_t A, mass, miss, det, occ, v, q, slots, slot_hidden,
                         clutter, seen_hidden, poisson_hit, double occludability, e_row, e_col,
                         L_edge, double floor):
    """`_object_misses`, `_new_weights` and `_strong_edges` in one call: (miss_i, L_0j, and
    the strong edges: mask, rows, columns, L_ij). `clutter` is kappa p_F(z_j) of each
    measurement, from the measurement model (`BoxMeasurement.clutter_density`
    for boxes)."""
    cdef const i64* ro = integers(rows, 1, "rows")
    cdef const f64* m = doubles(mass, 1, "mass")
    cdef const f64* mi = doubles(miss, 1, "miss")
    cdef const f64* de = doubles(det, 1, "det")
    cdef const f64* oc = doubles(occ, 1, "occ")
    cdef const f64* vv = doubles(v, 1, "v")
    cdef const f64* qq = doubles(q, 1, "q")
    cdef const i64* sl = integers(slots, 1, "slots")
    cdef f64* sh = doubles(slot_hidden, 1, "slot_hidden")
    cdef const f64* cl = doubles(clutter, 1, "clutter")
    cdef const f64* seen = doubles(seen_hidden, 1, "seen_hidden")
    cdef const f64* ph = doubles(poisson_hit, 1, "poisson_hit")
    cdef const i64* er = integers(e_row, 1, "e_row")
    cdef const i64* ec = integers(e_col, 1, "e_col")
    cdef const f64* L = doubles(L_edge, 1, "L_edge")
    cdef cnp.ndarray miss_obj_ = _object_misses_c(ro, dim(rows, 0), A, m, mi, de, oc, vv, qq,
                                                  sl, sh, dim(slot_hidden, 0))
    cdef cnp.ndarray w_new_ = _new_weights_c(cl, dim(clutter, 0), seen, ph, occludability)
    strong, s_row, s_col, s_L = _strong_edges_c(er, ec, L, dim(L_edge, 0), fdata(miss_obj_),
                                                fdata(w_new_), floor)
    return miss_obj_, w_new_, strong, s_row, s_col, s_L


def _hidden_evidence(label, within, v, q, r, used, hits, i64 confirm_hits, detection,
                     double detectability, double hidden):
    """One frame's sums (A, B) of `models.occludability.OccludabilityLearner`: over the
    confirmed objects i (used slots with `confirm_hits` hits) whose hidden share
    u_i = 1 - sum_{k in i} (w_k / r_i) v_k (1 - q_k) is at least `hidden`, A = sum r_i u_i
    (1 - h_i / d) and B = sum r_i u_i^2, h_i whether slot i took a detection (`detection`
    >= 0) and d the `detectability` (> 0), summed in slot order."""
    cdef const i64* lab = integers(label, 1, "label")
    cdef const f64* wi = doubles(within, 1, "within")
    cdef const f64* vv = doubles(v, 1, "v")
    cdef const f64* qq = doubles(q, 1, "q")
    cdef const f64* rr = doubles(r, 1, "r")
    cdef const b8* us = booleans(used, 1, "used")
    cdef const i64* hi = integers(hits, 1, "hits")
    cdef const i64* de = integers(detection, 1, "detection")
    cdef Py_ssize_t n = dim(label, 0), L = dim(used, 0), k, i
    if dim(within, 0) != n or dim(v, 0) != n or dim(q, 0) != n or dim(r, 0) < L \
            or dim(hits, 0) < L or dim(detection, 0) < L:
        raise ValueError("_hidden_evidence: one weight, v and q a component, one r, hit count "
                         "and detection a slot")
    cdef cnp.ndarray seen_ = zero_doubles(1, L)
    cdef f64* seen = fdata(seen_)
    for k in range(n):
        if lab[k] >= L:
            raise ValueError("_hidden_evidence: a component's label is past the slots")
        if lab[k] >= 0:
            seen[lab[k]] += wi[k] * vv[k] * (1.0 - qq[k])
    cdef double A = 0.0, B = 0.0, u
    for i in range(L):
        if us[i] and hi[i] >= confirm_hits:
            u = 1.0 - seen[i]
            if u >= hidden:
                A += rr[i] * u * (1.0 - (1.0 if de[i] >= 0 else 0.0) / detectability)
                B += rr[i] * u * u
    return A, B
