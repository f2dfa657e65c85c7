# The kernel of occtrack.models.birth (included by _models.pyx): the maths is in birth.py.


def _components(object extent, double inward_speed, double speed_std, double edge_mass,
                double spread_mass, object size_mean, object size_std, double speed_unit):
    """`EdgeBirths.components`: every birth is centred in the image, still, of the prior's
    size, with a standard deviation of half the image, `speed_std` and the prior's spread;
    the edge ones then sit on their edge (spread by one half-size across it) and move inward."""
    cdef const f64* ext = doubles(extent, 1, "extent")
    cdef const f64* size = doubles(size_mean, 1, "size_mean")
    cdef const f64* spread = doubles(size_std, 1, "size_std")
    if dim(extent, 0) < 2 or dim(size_mean, 0) < 2 or dim(size_std, 0) < 2:
        raise ValueError("_components: extent, size_mean and size_std of 2 values are needed")
    cdef cnp.ndarray mass_ = new_doubles(1, 5)
    cdef cnp.ndarray means_ = zero_doubles(3, 5, 2, 3)
    cdef cnp.ndarray covs_ = zero_doubles(4, 5, 2, 3, 3)
    cdef cnp.ndarray sds_ = zero_doubles(3, 5, 2, 3)
    cdef f64* mass = <f64*>cnp.PyArray_DATA(mass_)
    cdef f64* means = <f64*>cnp.PyArray_DATA(means_)
    cdef f64* sds = <f64*>cnp.PyArray_DATA(sds_)
    cdef f64* covs = <f64*>cnp.PyArray_DATA(covs_)
    cdef Py_ssize_t b, axis, edge, side, r
    cdef double s
    for b in range(5):
        mass[b] = edge_mass
    mass[4] = spread_mass
    for b in range(5):
        for axis in range(2):
            means[(b * 2 + axis) * 3] = ext[axis] / 2.0
            sds[(b * 2 + axis) * 3] = ext[axis] / 2.0
            sds[(b * 2 + axis) * 3 + 1] = speed_std * speed_unit
            means[(b * 2 + axis) * 3 + 2] = size[axis]
            sds[(b * 2 + axis) * 3 + 2] = spread[axis]
    for edge in range(4):
        axis, side = edge // 2, edge % 2
        means[(edge * 2 + axis) * 3] = <double>side * ext[axis]
        sds[(edge * 2 + axis) * 3] = size[axis]
        means[(edge * 2 + axis) * 3 + 1] = inward_speed * speed_unit * <double>(1 - 2 * side)
    for b in range(5):
        for axis in range(2):
            for r in range(3):
                s = sds[(b * 2 + axis) * 3 + r]
                covs[((b * 2 + axis) * 3 + r) * 3 + r] = s * s
    return mass_, means_, covs_
