# score_model.py's per-frame counting (`_score_update`) and look-up (`_score_lookup`) for
# probability bins: bin b = min(int(clip(s, 0, 1) bins), bins - 1) of each score s (the
# log-odds bins stay in numpy). The sums are numpy's: the discount, then a bincount of the
# frame's weights added to it. A NaN score has no bin: refused (numpy's index was out of range).


cdef inline Py_ssize_t _score_bin(double s, Py_ssize_t bins) noexcept nogil:
    if s < 0.0:
        s = 0.0
    elif s > 1.0:
        s = 1.0
    cdef Py_ssize_t b = <Py_ssize_t>(s * bins)
    return b if b < bins - 1 else bins - 1


cdef int _check_scores(const f64* s, Py_ssize_t m) except -1:
    cdef Py_ssize_t j
    for j in range(m):
        if s[j] != s[j]:
            raise ValueError(f"scores must be numbers, not NaN (score {j})")
    return 0


def _score_update(object scores, object clutter_probability, double keep, object clutter,
                  object objects):
    """`ScoreLearner.update`'s sums in place: clutter *= keep, objects *= keep, then the
    bincounts of pi_j and 1 - pi_j over the detections' bins added."""
    cdef const f64* s = doubles(scores, 1, "scores")
    cdef const f64* pi = doubles(clutter_probability, 1, "clutter_probability")
    cdef f64* c = doubles(clutter, 1, "clutter")
    cdef f64* o = doubles(objects, 1, "objects")
    cdef Py_ssize_t m = dim(scores, 0), bins = dim(clutter, 0), j, b
    if dim(clutter_probability, 0) != m or dim(objects, 0) != bins or bins < 1:
        raise ValueError("_score_update: one probability a score, one object sum a bin")
    _check_scores(s, m)
    cdef cnp.ndarray add_ = zero_doubles(1, 2 * bins)
    cdef f64* add = fdata(add_)
    for j in range(m):
        b = _score_bin(s[j], bins)
        add[b] += pi[j]
        add[bins + b] += 1.0 - pi[j]
    for b in range(bins):
        c[b] = c[b] * keep
        o[b] = o[b] * keep
    if m:
        for b in range(bins):
            c[b] = c[b] + add[b]
            o[b] = o[b] + add[bins + b]


def _score_lookup(object scores, object table):
    """table[bin of s_j] of each score (`ScoreLearner.score_term`)."""
    cdef const f64* s = doubles(scores, 1, "scores")
    cdef const f64* t = doubles(table, 1, "table")
    cdef Py_ssize_t m = dim(scores, 0), bins = dim(table, 0), j
    if bins < 1:
        raise ValueError("_score_lookup: an empty table")
    _check_scores(s, m)
    cdef cnp.ndarray out_ = new_doubles(1, m)
    cdef f64* out = fdata(out_)
    for j in range(m):
        out[j] = t[_score_bin(s[j], bins)]
    return out_
