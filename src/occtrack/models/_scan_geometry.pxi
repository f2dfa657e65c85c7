# The Python-callable forms of the beam-and-disc helpers of scan_geometry.py (the inline C
# forms, which the compiled scan kernels call, are in _scan_geometry.pxd).


def beam_window(object angle, double low, double high):
    """The beams whose angles lie in [low, high] modulo a turn, `angle` (B,) sorted over one
    turn: two index ranges (lo0, hi0, lo1, hi1) found by bisection, the window taken at the
    turn of angle[0] and at the next (a window across the wrap falls in both). The compiled
    scan kernels' one way of finding a disc's beams."""
    cdef const f64* a = doubles(angle, 1, "angle")
    cdef Window w = beam_window_c(a, dim(angle, 0), low, high)
    return w.lo0, w.hi0, w.lo1, w.hi1


def near_range(double beam_angle, double px, double py, double radius):
    """The range along the beam at `beam_angle` to the near surface of the disc of `radius`
    centred at (px, py) from the sensor: t_c - sqrt(a^2 - d^2) (`disc_interval`), or -1 where
    the beam misses the disc or the surface is not ahead of the sensor."""
    return near_range_c(beam_angle, px, py, radius)
