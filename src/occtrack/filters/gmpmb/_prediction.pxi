# ---- prediction.py: motion, the Markov features, survival, the camera ----------------------

cdef void _predict_c(f64* mean, f64* cov, Py_ssize_t n, Py_ssize_t B, Py_ssize_t d,
                     const b8* coasting, const f64* coast, double coasting_after,
                     const f64* F, const f64* Q, const f64* F_coast, const f64* Q_coast,
                     f64* m, f64* FP) noexcept nogil:
    """`_predict_in_place` on pointers; a component coasts where coasting[k] (NULL:
    where coast[k] > coasting_after). m (d) and FP (d, d) are scratch."""
    cdef Py_ssize_t k, b, r, c, i
    cdef const f64* A
    cdef const f64* Qk
    cdef bint coasts
    cdef double unit2, total
    for k in range(n):
        coasts = coasting[k] != 0 if coasting != NULL else coast[k] > coasting_after
        if coasts:
            A, Qk = F_coast, Q_coast
        else:
            A, Qk = F, Q
        unit2 = py_max(2.0 * mean[(k * B + 1) * d + 2], MIN_HEIGHT)
        unit2 = unit2 * unit2
        for b in range(B):
            for r in range(d):
                m[r] = 0.0
                for c in range(d):
                    m[r] += A[r * d + c] * mean[(k * B + b) * d + c]
                    FP[r * d + c] = 0.0
                    for i in range(d):
                        FP[r * d + c] += A[r * d + i] * cov[((k * B + b) * d + i) * d + c]
            for r in range(d):
                mean[(k * B + b) * d + r] = m[r]
                for c in range(d):
                    total = 0.0
                    for i in range(d):
                        total += FP[r * d + i] * A[c * d + i]
                    cov[((k * B + b) * d + r) * d + c] = total + unit2 * Qk[r * d + c]


cdef int _check_square(object a, Py_ssize_t d, str name) except -1:
    if dim(a, 0) != d or dim(a, 1) != d:
        raise ValueError(f"{name}: a {d} x {d} matrix is needed")
    return 0


def _predict_in_place(mean, cov, coasting, F, Q, F_coast, Q_coast):
    """m <- F m, P <- F P F' + h^2 Q per component and axis, with h its box height (the
    unit of the motion noises, `ConstantVelocity.predict`) and (F, Q) the coasting model's
    for a component whose object was missed."""
    cdef f64* mu = doubles(mean, 3, "mean")
    cdef f64* P = doubles(cov, 4, "cov")
    cdef const b8* co = booleans(coasting, 1, "coasting")
    cdef const f64* F_ = doubles(F, 2, "F")
    cdef const f64* Q_ = doubles(Q, 2, "Q")
    cdef const f64* Fc = doubles(F_coast, 2, "F_coast")
    cdef const f64* Qc = doubles(Q_coast, 2, "Q_coast")
    cdef Py_ssize_t d = dim(mean, 2)
    for a, name in ((F, "F"), (Q, "Q"), (F_coast, "F_coast"), (Q_coast, "Q_coast")):
        _check_square(a, d, name)
    cdef cnp.ndarray scratch_ = new_doubles(1, d + d * d)
    _predict_c(mu, P, dim(mean, 0), dim(mean, 1), d, co, NULL, 0.0, F_, Q_, Fc, Qc,
               fdata(scratch_), fdata(scratch_) + d)


cdef inline void _relax_c(f64* p, Py_ssize_t n, double stationary,
                          double memory) noexcept nogil:
    cdef Py_ssize_t k
    for k in range(n):
        p[k] = stationary + memory * (p[k] - stationary)


def _relax_in_place(p, double stationary, double memory):
    """`TwoStateMarkov.predict`: p <- stationary + memory (p - stationary)."""
    cdef f64* pp = doubles(p, 1, "p")
    _relax_c(pp, dim(p, 0), stationary, memory)


cdef void _survive_c(f64* mass, Py_ssize_t n, const f64* mean, Py_ssize_t B, Py_ssize_t d,
                     const f64* image_size, double survival_inside,
                     double exit_survival) noexcept nogil:
    cdef Py_ssize_t k, axis
    cdef bint inside
    cdef double centre
    for k in range(n):
        inside = True
        for axis in range(2):
            centre = mean[(k * B + axis) * d]
            if not (centre >= 0 and centre <= image_size[axis]
                    and mean[(k * B + axis) * d + 2] >= 1.0):
                inside = False
        mass[k] *= survival_inside if inside else exit_survival


def _survive_in_place(mass, mean, image_size, double survival_inside, double exit_survival):
    """Masses times the survival of a component whose centre is in the image (and whose box
    is at least 2 px wide and tall), else times `exit_survival`."""
    cdef f64* m = doubles(mass, 1, "mass")
    cdef const f64* mu = doubles(mean, 3, "mean")
    cdef const f64* size = doubles(image_size, 1, "image_size")
    _survive_c(m, dim(mass, 0), mu, dim(mean, 1), dim(mean, 2), size, survival_inside,
               exit_survival)


def _predict_pool(mass, mean, cov, det, occ, coast, double coasting_after, F, Q, F_coast,
                  Q_coast, double det_stationary, double det_memory, double occ_stationary,
                  double occ_memory, image_size, double survival_inside, double exit_survival):
    """The prediction of every component, in place: motion (the coasting model for one
    unseen longer than `coasting_after` s), the Markov features d and o, survival."""
    cdef f64* m = doubles(mass, 1, "mass")
    cdef f64* mu = doubles(mean, 3, "mean")
    cdef f64* P = doubles(cov, 4, "cov")
    cdef f64* de = doubles(det, 1, "det")
    cdef f64* oc = doubles(occ, 1, "occ")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef const f64* F_ = doubles(F, 2, "F")
    cdef const f64* Q_ = doubles(Q, 2, "Q")
    cdef const f64* Fc = doubles(F_coast, 2, "F_coast")
    cdef const f64* Qc = doubles(Q_coast, 2, "Q_coast")
    cdef const f64* size = doubles(image_size, 1, "image_size")
    cdef Py_ssize_t n = dim(mean, 0), B = dim(mean, 1), d = dim(mean, 2)
    _check_square(F, d, "F")
    _check_square(Q, d, "Q")
    _check_square(F_coast, d, "F_coast")
    _check_square(Q_coast, d, "Q_coast")
    cdef f64 scratch[64]
    cdef cnp.ndarray scratch_
    cdef f64* s = scratch
    if d + d * d > 64:
        scratch_ = new_doubles(1, d + d * d)
        s = fdata(scratch_)
    _predict_c(mu, P, n, B, d, NULL, co, coasting_after, F_, Q_, Fc, Qc, s, s + d)
    _relax_c(de, dim(det, 0), det_stationary, det_memory)
    _relax_c(oc, dim(occ, 0), occ_stationary, occ_memory)
    _survive_c(m, dim(mass, 0), mu, B, d, size, survival_inside, exit_survival)


def _move_in_place(mean, cov, scale, shift, shift_variance):
    """x -> scale x + shift per axis: centres move, velocities and half-sizes scale,
    covariances scale by scale^2; the shift's own variance adds to every centre's."""
    cdef f64* mu = doubles(mean, 3, "mean")
    cdef f64* P = doubles(cov, 4, "cov")
    cdef const f64* sc = doubles(scale, 1, "scale")
    cdef const f64* sh = doubles(shift, 1, "shift")
    cdef const f64* sv = doubles(shift_variance, 1, "shift_variance")
    cdef Py_ssize_t n = dim(mean, 0), B = dim(mean, 1), d = dim(mean, 2), k, axis, r, c
    cdef double s2
    for k in range(n):
        for axis in range(2):
            for r in range(d):
                mu[(k * B + axis) * d + r] *= sc[axis]
                for c in range(d):
                    s2 = sc[axis] * sc[axis]
                    P[((k * B + axis) * d + r) * d + c] *= s2
            mu[(k * B + axis) * d] += sh[axis]
            P[((k * B + axis) * d) * d] += sv[axis]
