# cython: language_level=3
"""Compiled kernels of occtrack.models (issue 23), one `.pxi` per module they serve:
`_box.pxi` (box.py: the box measurement's innovation, likelihood and updates), `_aspect.pxi`
(aspect.py: the aspect ratio's count and update), `_birth.pxi` (birth.py: the birth
components) and `_highway_sensor.pxi` (highway_sensor.py: the highway sensor's per-particle
loops; its end terms are inline in `_highway_sensor.pxd`, for other extensions too).

The maths and the calls are in those Python modules, which import the kernels from here under
the names they had. Each kernel is written as its numba loop read: the arrays are C pointers
(checked once at the `def` entry: dtype, dimensions, C order), indexed by hand, and each sum is
taken in the same order (no fused multiply-add, no reassociation), so the numbers are the same
to the last bit. Kernels that call kernels call the `cdef` (`_c`) versions.
"""

cimport numpy as cnp
from libc.math cimport M_PI, erfc, exp, log, sqrt

from occtrack._arrays cimport (argsort_stable, b8, booleans, dim, doubles, f64, i64, integers,
                               new_booleans, new_doubles, new_integers, zero_doubles,
                               zero_integers)
from occtrack.models._highway_sensor cimport _both_orders_c, _end_term_c, _ndtr_c, _near_c

cnp.import_array()

include "_box.pxi"
include "_aspect.pxi"
include "_birth.pxi"
include "_highway_sensor.pxi"
