# The kernels of occtrack.models.aspect (included by _models.pyx): the maths is in aspect.py.
# Layouts, C order: z and observed (M, 2, 2) -> [(j * 2 + axis) * 2 + side]; means (K, 2, 3)
# -> [(k * 2 + axis) * 3 + a]; covs (K, 2, 3, 3) -> [((k * 2 + axis) * 3 + a) * 3 + b].


def _count_aspects(object z, object observed, object stats):
    """Add log(width / height) of the detections with every edge measured to the running
    count, sum and sum of squares `stats` (3,)."""
    cdef const f64* zp = doubles(z, 3, "z")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef f64* s = doubles(stats, 1, "stats")
    cdef Py_ssize_t j, M = dim(z, 0)
    cdef double width, height, ratio
    if dim(z, 1) != 2 or dim(z, 2) != 2 or dim(observed, 0) < M or dim(stats, 0) < 3:
        raise ValueError("_count_aspects: z and observed (M, 2, 2), stats (3,) are needed")
    for j in range(M):
        if not (o[j * 4] and o[j * 4 + 1] and o[j * 4 + 2] and o[j * 4 + 3]):
            continue
        width, height = zp[j * 4 + 1] - zp[j * 4], zp[j * 4 + 3] - zp[j * 4 + 2]
        if width <= 0.0 or height <= 0.0:
            continue
        ratio = log(width / height)
        s[0] += 1.0
        s[1] += ratio
        s[2] += ratio * ratio


cdef void _aspect_update_c(f64* means, f64* covs, const i64* rows, Py_ssize_t n,
                           const b8* observed, const i64* measurement, double mu,
                           double sigma) noexcept nogil:
    """`_aspect_update` on pointers (n rows)."""
    cdef double g[3]
    cdef Py_ssize_t i, a, b, whole, cut
    cdef i64 k, j
    cdef bint whole_x, whole_y
    cdef double sign, half, scale, value, var, S, residual
    cdef f64* P
    for i in range(n):
        k, j = rows[i], measurement[i]
        whole_x = observed[j * 4] and observed[j * 4 + 1]
        whole_y = observed[j * 4 + 2] and observed[j * 4 + 3]
        if whole_x == whole_y:  # nothing cut, or both axes cut
            continue
        if whole_x:
            whole, cut = 0, 1
        else:
            whole, cut = 1, 0
        sign = -1.0 if cut == 1 else 1.0  # height = width exp(-mu), width = height exp(mu)
        half = means[(k * 2 + whole) * 3 + 2]
        if half <= 0.0:
            continue
        scale = exp(sign * mu)
        value = half * scale
        var = value * value * sigma * sigma + scale * scale * covs[(k * 2 + whole) * 9 + 8]
        P = covs + (k * 2 + cut) * 9
        S = P[8] + var
        residual = value - means[(k * 2 + cut) * 3 + 2]
        for a in range(3):
            g[a] = P[a * 3 + 2] / S
        for a in range(3):
            means[(k * 2 + cut) * 3 + a] += g[a] * residual
        for a in range(3):
            for b in range(3):
                P[a * 3 + b] -= g[a] * g[b] * S


def _aspect_update(object means, object covs, object rows, object observed,
                   object measurement, double mu, double sigma):
    """The scalar Kalman update of the module docstring, per row whose detection has one axis
    whole and the other cut: s = means[k, cut, 2], P its block, g = P[:, 2] / S,
    m += g (z - s), P -= g g' S."""
    cdef f64* m = doubles(means, 3, "means")
    cdef f64* P = doubles(covs, 4, "covs")
    cdef const i64* r = integers(rows, 1, "rows")
    cdef const b8* o = booleans(observed, 3, "observed")
    cdef const i64* j = integers(measurement, 1, "measurement")
    _aspect_update_c(m, P, r, dim(rows, 0), o, j, mu, sigma)
