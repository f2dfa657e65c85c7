# cython: language_level=3
"""Compiled kernels of occtrack.models (issue 23), one `.pxi` per module they serve:
`_box.pxi` (box.py: the box measurement's innovation, likelihood and updates), `_aspect.pxi`
(aspect.py: the aspect ratio's count and update), `_birth.pxi` (birth.py: the birth
components), `_highway_sensor.pxi` (highway_sensor.py: the highway sensor's per-particle
loops; its end terms are inline in `_highway_sensor.pxd`, for other extensions too),
`_scan_geometry.pxi` (scan_geometry.py's `beam_window` and `near_range`, their inline C forms in
`_scan_geometry.pxd`), `_scan_segments.pxi` (scan_segments.py's `_linearise`,
`_other_beams` and `_gaussian_hits`), `_scan_hand_made.pxi` (scan_hand_made.py's
`_other_beams_hand_made`), `_score_model.pxi` (score_model.py's per-frame sums) and
`_motion.pxi` (motion.py's median of squares).

The maths and the calls are in those Python modules, which import the kernels from here under
the names they had. Each kernel is written as its numba loop read: the arrays are C pointers
(checked once at the `def` entry: dtype, dimensions, C order), indexed by hand, and each sum is
taken in the same order (no fused multiply-add, no reassociation), so the numbers are the same
to the last bit (`_gaussian_hits`, written from numpy's 2 x 2 algebra rather than a numba
loop, agrees with it to about 1e-11 relative). Kernels that call kernels call the `cdef`
(`_c`) versions.
"""

cimport numpy as cnp
from libc.math cimport M_PI, asin, atan2, erfc, exp, fabs, hypot, log, log1p, sqrt

from occtrack._arrays cimport (argsort_stable, b8, booleans, dim, doubles, f64, fdata, i64,
                               integers, length, new_booleans, new_doubles, new_integers,
                               zero_booleans, zero_doubles, zero_integers)
from occtrack.models._highway_sensor cimport _both_orders_c, _end_term_c, _ndtr_c, _near_c
from occtrack.models._scan_geometry cimport (Window, beam_direction, beam_window_c, near_range_c,
                                             near_range_uv)

cnp.import_array()

include "_box.pxi"
include "_aspect.pxi"
include "_birth.pxi"
include "_highway_sensor.pxi"
include "_scan_geometry.pxi"
include "_scan_segments.pxi"
include "_scan_hand_made.pxi"
include "_score_model.pxi"
include "_motion.pxi"
