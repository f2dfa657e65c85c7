# Kernels of occtrack.tracker.confidence (included by _tracker.pyx): the probability that a
# reported box is right. Components: mean (K, 2, 3) m[(k * 2 + a) * 3 + j], cov (K, 2, 3, 3)
# c[((k * 2 + a) * 3 + i) * 3 + j]; per axis (centre, half-size) covariances (n, 2, 2, 2)
# s[((i * 2 + a) * 2 + r) * 2 + c]; draws z (S, 2, 2) and reaches (B, 2, 2) alike.


cdef cnp.ndarray new4(Py_ssize_t n, bint zero):
    """numpy.zeros / numpy.empty((n, 2, 2, 2)) of float64."""
    cdef cnp.npy_intp shape[4]
    shape[0], shape[1], shape[2], shape[3] = n, 2, 2, 2
    if zero:
        return cnp.PyArray_ZEROS(4, shape, cnp.NPY_FLOAT64, 0)
    return cnp.PyArray_EMPTY(4, shape, cnp.NPY_FLOAT64, 0)


cdef void box_covariances_c(const i64* label, const f64* mass, const f64* mean,
                            const f64* cov, Py_ssize_t K, const f64* r, const f64* means,
                            f64* out) noexcept nogil:
    """`box_covariances` into out (L, 2, 2, 2), zeros on entry."""
    cdef Py_ssize_t k, a, i
    cdef double share, d0, d2
    for k in range(K):
        i = label[k]
        if i < 0:
            continue
        share = mass[k] / py_max(r[i], 1e-300)
        for a in range(2):
            d0 = mean[(k * 2 + a) * 3 + 0] - means[(i * 2 + a) * 3 + 0]
            d2 = mean[(k * 2 + a) * 3 + 2] - means[(i * 2 + a) * 3 + 2]
            out[((i * 2 + a) * 2 + 0) * 2 + 0] += share * (cov[((k * 2 + a) * 3 + 0) * 3 + 0]
                                                           + d0 * d0)
            out[((i * 2 + a) * 2 + 0) * 2 + 1] += share * (cov[((k * 2 + a) * 3 + 0) * 3 + 2]
                                                           + d0 * d2)
            out[((i * 2 + a) * 2 + 1) * 2 + 1] += share * (cov[((k * 2 + a) * 3 + 2) * 3 + 2]
                                                           + d2 * d2)
        for a in range(2):
            out[((i * 2 + a) * 2 + 1) * 2 + 0] = out[((i * 2 + a) * 2 + 0) * 2 + 1]


cdef int check_components(object label, object mass, object mean, object cov, object r,
                          object means) except -1:
    """The filter's components (K of them) and its slots' moments (L): dtypes and shapes."""
    integers(label, 1, "label")
    doubles(mass, 1, "mass")
    doubles(mean, 3, "mean")
    doubles(cov, 4, "cov")
    doubles(r, 1, "r")
    doubles(means, 3, "means")
    cdef Py_ssize_t K = dim(label, 0)
    length(mass, K, "mass")
    length(mean, K, "mean")
    length(cov, K, "cov")
    length(means, dim(r, 0), "means")
    if (dim(mean, 1) != 2 or dim(mean, 2) != 3 or dim(cov, 1) != 2 or dim(cov, 2) != 3
            or dim(cov, 3) != 3 or dim(means, 1) != 2 or dim(means, 2) != 3):
        raise ValueError("mean (K, 2, 3), cov (K, 2, 3, 3) and means (L, 2, 3) are needed")
    return 0


def box_covariances(object label, object mass, object mean, object cov, object r,
                    object means, Py_ssize_t L):
    """Per label slot and image axis the 2 x 2 covariance of (centre, half-size) of its
    mixture (state entries 0 and 2), the spread of the component means included: (L, 2, 2, 2).
    `r` and `means` are the slots' existence and mean states (`object_moments`)."""
    check_components(label, mass, mean, cov, r, means)
    out = new4(L, True)
    box_covariances_c(idata(label), fdata(mass), fdata(mean), fdata(cov), dim(label, 0),
                      fdata(r), fdata(means), fdata(out))
    return out


cdef inline void drift_variance_c(const f64* mean, double unseen, double power,
                                  const f64* image_centre, Py_ssize_t axis, double* add_centre,
                                  double* add_half) noexcept nogil:
    cdef double lever = 2.0 * mean[1 * 3 + 2] * unseen
    cdef double x = lever * (mean[axis * 3 + 0] - image_centre[axis])
    cdef double y = lever * mean[axis * 3 + 2]
    add_centre[0] = power * (x * x)
    add_half[0] = power * (y * y)


def drift_variance(object mean, double unseen, double power, object image_centre,
                   Py_ssize_t axis):
    """The variances (centre, half-size) on `axis` that a coasting box's confidence adds for the
    camera's expansion (`occtrack.tracker.camera.estimate_expansion`): the filter follows the
    one shift a frame, and a box unseen for t s drifts from its prediction by k h (x - centre) t,
    k the expansion rate (1 / (px s)), h its height; k^2 is taken as the camera's recent
    `power`, and the half-size grows alike (k h s t). On any camera, resolution and frame rate:
    k is measured from that video's detections in its own units, and a still camera's is 0."""
    cdef const f64* m = doubles(mean, 2, "mean")
    cdef const f64* c = doubles(image_centre, 1, "image_centre")
    cdef double add_centre, add_half
    if dim(mean, 0) != 2 or dim(mean, 1) != 3 or dim(image_centre, 0) != 2:
        raise ValueError("mean (2, 3) and image_centre (2,) are needed")
    if not 0 <= axis < 2:
        raise IndexError("axis must be 0 or 1")
    drift_variance_c(m, unseen, power, c, axis, &add_centre, &add_half)
    return add_centre, add_half


def _report_confidence(object label, object mass, object mean, object cov, object r,
                       object means, object shown, object boxes, object detected,
                       bint on_detection, object coast, double power, object image_centre,
                       double floor_value, double threshold, object z, object reach):
    check_components(label, mass, mean, cov, r, means)
    cdef const i64* sh = integers(shown, 1, "shown")
    cdef const f64* bx = doubles(boxes, 2, "boxes")
    cdef const b8* det = booleans(detected, 1, "detected")
    cdef const f64* co = doubles(coast, 1, "coast")
    cdef const f64* ic = doubles(image_centre, 1, "image_centre")
    cdef Py_ssize_t L = dim(r, 0), K = dim(shown, 0), a, k, axis, t
    length(boxes, K, "boxes")
    length(detected, K, "detected")
    length(coast, L, "coast")
    cdef const f64* rr = fdata(r)
    cdef const f64* mm = fdata(means)
    cdef double add_centre, add_half
    covariances_ = new4(L, True)
    cdef f64* covariances = fdata(covariances_)
    box_covariances_c(idata(label), fdata(mass), fdata(mean), fdata(cov), dim(label, 0), rr, mm,
                      covariances)
    centre_, half_ = new_doubles(2, K, 2), new_doubles(2, K, 2)
    spread_, existence_ = new4(K, False), new_doubles(1, K)
    cdef f64* centre = fdata(centre_)
    cdef f64* half = fdata(half_)
    cdef f64* spread = fdata(spread_)
    cdef f64* existence = fdata(existence_)
    for a in range(K):
        k = sh[a]
        existence[a] = rr[k]
        for t in range(8):
            spread[a * 8 + t] = covariances[k * 8 + t]
        if power > 0.0 and not det[a]:
            for axis in range(2):
                drift_variance_c(mm + k * 6, co[k], power, ic, axis, &add_centre, &add_half)
                spread[((a * 2 + axis) * 2 + 0) * 2 + 0] += add_centre
                spread[((a * 2 + axis) * 2 + 1) * 2 + 1] += add_half
        for axis in range(2):
            if on_detection and det[a]:
                half[a * 2 + axis] = bx[a * 4 + 2 + axis] / 2.0
                centre[a * 2 + axis] = bx[a * 4 + axis] + half[a * 2 + axis]
            else:
                centre[a * 2 + axis] = mm[(k * 2 + axis) * 3 + 0]
                half[a * 2 + axis] = mm[(k * 2 + axis) * 3 + 2]
    # a box whose existence cannot carry it to `floor` needs only to be known below it
    need_ = zero_doubles(1, K)
    cdef f64* need = fdata(need_)
    if floor_value > 0.0:
        for a in range(K):
            need[a] = floor_value / py_max(existence[a], 1e-300)
    out_ = _overlap_probability(centre_, half_, spread_, boxes, threshold, z, reach, need_)
    cdef f64* out = fdata(out_)
    for a in range(K):
        out[a] = existence[a] * out[a]
    return out_


cdef inline double _overlap_c(double c, double s, double lo, double hi) noexcept nogil:
    """Length of [c - s, c + s] within [lo, hi]."""
    return py_max(py_min(c + s, hi) - py_max(c - s, lo), 0.0)


def _overlap(double c, double s, double lo, double hi):
    """Length of [c - s, c + s] within [lo, hi]."""
    return _overlap_c(c, s, lo, hi)


def _overlap_probability(object centre, object half, object covariance, object reported,
                         double threshold, object z, object reach, object need):
    """`overlap_probability`, block by block (`_decided`); box i stops as soon as even every
    draw left could not lift its count to `need[i]` (a probability; 0: never), and then its
    value is that bound, below need[i] (the reporting rule drops it whatever it is)."""
    cdef const f64* ce = doubles(centre, 2, "centre")
    cdef const f64* ha = doubles(half, 2, "half")
    cdef const f64* cv = doubles(covariance, 4, "covariance")
    cdef const f64* rp = doubles(reported, 2, "reported")
    cdef const f64* zz = doubles(z, 3, "z")
    cdef const f64* re = doubles(reach, 3, "reach")
    cdef const f64* ne = doubles(need, 1, "need")
    cdef Py_ssize_t n = dim(centre, 0), S = dim(z, 0), B = dim(reach, 0)
    length(half, n, "half")
    length(covariance, n, "covariance")
    length(reported, n, "reported")
    length(need, n, "need")
    if (dim(centre, 1) != 2 or dim(half, 1) != 2 or dim(reported, 1) != 4
            or dim(covariance, 1) != 2 or dim(covariance, 2) != 2 or dim(covariance, 3) != 2
            or dim(z, 1) != 2 or dim(z, 2) != 2 or dim(reach, 1) != 2 or dim(reach, 2) != 2):
        raise ValueError("centre, half (n, 2), covariance (n, 2, 2, 2), reported (n, 4), "
                         "z (S, 2, 2) and reach (B, 2, 2) are needed")
    if B < 1 or S % B:
        raise ValueError("the draws must come in B >= 1 whole blocks")
    out = new_doubles(1, n)
    cdef f64* o = fdata(out)
    with nogil:
        _overlap_probability_c(ce, ha, cv, rp, n, threshold, zz, S, re, B, ne, o)
    return out


cdef extern from *:
    """
    /* The draws d < n of z (n, axis, 2) that hit: per axis
           c = centre + root0 z0,  s = max(half + root1 z0 + root2 z1, 0),
           overlap = max(min(c + s, hi) - max(c - s, lo), 0),
       inter = overlap_x overlap_y, size = 2 s_x 2 s_y, union = size + area - inter, a hit when
       union > 0 and inter >= threshold union (`_overlap_probability`'s loop). With SSE2 the
       two axes are the two lanes of one register: the same operations lane by lane (max(x, 0)
       as maxpd(0, x) = 0 > x ? 0 : x, min(x, hi) as minpd(hi, x) = hi < x ? hi : x, Python's
       and numba's choice on ties and NaN), so the same numbers. */
    #if defined(__SSE2__)
    #include <emmintrin.h>
    static inline long occtrack_draw_hits(const double* z, long n, const double* centre,
                                          const double* half, const double* root,
                                          const double* reported, double area,
                                          double threshold) {
        const __m128d zero = _mm_setzero_pd(), two = _mm_set1_pd(2.0);
        const __m128d vc = _mm_loadu_pd(centre), vh = _mm_loadu_pd(half);
        const __m128d r0 = _mm_set_pd(root[3], root[0]), r1 = _mm_set_pd(root[4], root[1]);
        const __m128d r2 = _mm_set_pd(root[5], root[2]);
        const __m128d lo = _mm_loadu_pd(reported);
        const __m128d hi = _mm_add_pd(lo, _mm_loadu_pd(reported + 2));
        long d, hits = 0;
        for (d = 0; d < n; d++) {
            __m128d za = _mm_loadu_pd(z + 4 * d), zb = _mm_loadu_pd(z + 4 * d + 2);
            __m128d z0 = _mm_unpacklo_pd(za, zb), z1 = _mm_unpackhi_pd(za, zb);
            __m128d c = _mm_add_pd(vc, _mm_mul_pd(r0, z0));
            __m128d s = _mm_add_pd(_mm_add_pd(vh, _mm_mul_pd(r1, z0)), _mm_mul_pd(r2, z1));
            s = _mm_max_pd(zero, s);
            __m128d overlap = _mm_max_pd(zero, _mm_sub_pd(_mm_min_pd(hi, _mm_add_pd(c, s)),
                                                          _mm_max_pd(lo, _mm_sub_pd(c, s))));
            __m128d s2 = _mm_mul_pd(two, s);
            double inter = _mm_cvtsd_f64(overlap) * _mm_cvtsd_f64(_mm_unpackhi_pd(overlap,
                                                                                 overlap));
            double size = _mm_cvtsd_f64(s2) * _mm_cvtsd_f64(_mm_unpackhi_pd(s2, s2));
            double u = size + area - inter;
            hits += (u > 0) & (inter >= threshold * u);
        }
        return hits;
    }
    #else
    static inline long occtrack_draw_hits(const double* z, long n, const double* centre,
                                          const double* half, const double* root,
                                          const double* reported, double area,
                                          double threshold) {
        long d, a, hits = 0;
        for (d = 0; d < n; d++) {
            double inter = 1.0, size = 1.0, u;
            for (a = 0; a < 2; a++) {
                double z0 = z[4 * d + 2 * a], z1 = z[4 * d + 2 * a + 1];
                double c = centre[a] + root[3 * a] * z0;
                double s = half[a] + root[3 * a + 1] * z0 + root[3 * a + 2] * z1;
                double lo = reported[a], hi = reported[a] + reported[2 + a], top, bottom, o;
                s = 0.0 > s ? 0.0 : s;
                top = hi < c + s ? hi : c + s;
                bottom = lo > c - s ? lo : c - s;
                o = top - bottom;
                inter *= 0.0 > o ? 0.0 : o;
                size *= 2.0 * s;
            }
            u = size + area - inter;
            hits += (u > 0) & (inter >= threshold * u);
        }
        return hits;
    }
    #endif
    """
    long draw_hits "occtrack_draw_hits"(const f64* z, long n, const f64* centre,
                                         const f64* half, const f64* root,
                                         const f64* reported, double area,
                                         double threshold) noexcept nogil


cdef void _overlap_probability_c(const f64* centre, const f64* half, const f64* covariance,
                                 const f64* reported, Py_ssize_t n, double threshold,
                                 const f64* z, Py_ssize_t S, const f64* reach, Py_ssize_t B,
                                 const f64* need, f64* out) noexcept nogil:
    cdef Py_ssize_t block = S // B, i, a, b
    cdef f64 root[6]
    cdef double l00, l10, area
    cdef i64 hits
    cdef int decided
    for a in range(6):
        root[a] = 0.0
    for i in range(n):
        for a in range(2):  # a lower-triangular square root of the axis' 2 x 2 covariance
            l00 = sqrt(py_max(covariance[((i * 2 + a) * 2 + 0) * 2 + 0], 0.0))
            l10 = covariance[((i * 2 + a) * 2 + 0) * 2 + 1] / l00 if l00 > 0 else 0.0
            root[a * 3 + 0], root[a * 3 + 1] = l00, l10
            root[a * 3 + 2] = sqrt(py_max(covariance[((i * 2 + a) * 2 + 1) * 2 + 1] - l10 * l10,
                                        0.0))
        area = reported[i * 4 + 2] * reported[i * 4 + 3]
        hits = 0
        for b in range(B):
            if hits + (B - b) * block < need[i] * S:
                hits += (B - b) * block  # the bound: every draw left a hit
                break
            decided = _decided_c(centre + i * 2, half + i * 2, root, reported + i * 4, area,
                                 threshold, reach + b * 4)
            if decided == 1:
                hits += block
            if decided != 0:
                continue
            hits += draw_hits(z + b * block * 4, block, centre + i * 2, half + i * 2, root,
                              reported + i * 4, area, threshold)
        out[i] = <double>hits / <double>S


cdef int _decided_c(const f64* centre, const f64* half, const f64* root, const f64* reported,
                    double area, double threshold, const f64* reach) noexcept nogil:
    cdef double least = 1.0, most = 1.0, smallest = 1.0, largest = 1.0
    cdef double dc, ds, c_lo, c_hi, s_lo, s_hi, lo, hi, margin
    cdef Py_ssize_t a
    for a in range(2):
        dc = root[a * 3 + 0] * reach[a * 2 + 0]
        ds = fabs(root[a * 3 + 1]) * reach[a * 2 + 0] + root[a * 3 + 2] * reach[a * 2 + 1]
        c_lo, c_hi = centre[a] - dc, centre[a] + dc
        s_lo, s_hi = py_max(half[a] - ds, 0.0), py_max(half[a] + ds, 0.0)
        lo, hi = reported[a], reported[a] + reported[2 + a]
        least *= py_min(_overlap_c(c_lo, s_lo, lo, hi), _overlap_c(c_hi, s_lo, lo, hi))
        most *= _overlap_c(py_min(py_max((lo + hi) / 2.0, c_lo), c_hi), s_hi, lo, hi)
        smallest *= 2.0 * s_lo
        largest *= 2.0 * s_hi
    margin = 1e-9 * py_max(area, 1.0)  # (rounding: no draw may straddle the bound)
    if largest + area - least > 0 and least - margin >= threshold * (largest + area - least):
        return 1
    if most + margin < threshold * (smallest + area - most):
        return -1
    return 0


def _decided(object centre, object half, object root, object reported, double area,
             double threshold, object reach):
    """1 if every draw whose normals lie within `reach` (axis, 2) hits, -1 if every one
    misses, 0 if the bound cannot tell. Per axis the centre lies within c_lo..c_hi and the
    half-size within s_lo..s_hi; the overlap is least at a corner, most at the reported box's
    centre (clamped) with the largest half-size; IoU = I / (S + area - I) rises with the
    overlap I and falls with the size S, so the least I with the largest S bounds it below and
    the reverse above."""
    cdef const f64* ce = doubles(centre, 1, "centre")
    cdef const f64* ha = doubles(half, 1, "half")
    cdef const f64* ro = doubles(root, 2, "root")
    cdef const f64* rp = doubles(reported, 1, "reported")
    cdef const f64* re = doubles(reach, 2, "reach")
    if (dim(centre, 0) != 2 or dim(half, 0) != 2 or dim(root, 0) != 2 or dim(root, 1) != 3
            or dim(reported, 0) != 4 or dim(reach, 0) != 2 or dim(reach, 1) != 2):
        raise ValueError("centre, half (2,), root (2, 3), reported (4,), reach (2, 2) are "
                         "needed")
    return _decided_c(ce, ha, ro, rp, area, threshold, re)
