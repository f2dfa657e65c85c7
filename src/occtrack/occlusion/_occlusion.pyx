# cython: language_level=3
"""Compiled kernels of occtrack.occlusion (issue 23), one extension for the package.

The maths and the calls are in the Python modules the kernels serve; each source file here is
named after its module:

* `_box_geometry.pxi`: box_geometry.py, when one image box hides another (`_hides`, `_table`,
  `_visible_dense`, `_visible_pairs`, `_hidden_dense`);
* `_box_objectwise.pxi`: box_objectwise.py, the occluders' mean boxes (`_occluder_boxes`,
  `_visible_behind_means`);
* `_extent_kernels.pxi`: extent_kernels.py, the highway's 1-D extents (`track_extents`,
  `expval_visibility`, `grid_visibility`);
* `_scan.pxi`: scan.py, the chance that a disc is hidden behind a scan's returns
  (`_hidden_at`; the beam geometry is models/_scan_geometry.pxd's).

Each kernel is written as the numba loop it replaces read: the same operations in the same
order (no fused multiply-add, no reassociation), libm's exp/log1p/expm1, and max/min as
Python's (the first argument unless the second is strictly larger/smaller), so the numbers
are the same to the last bit. A `def` entry checks each array once (dtype, dimensions, C
order: `occtrack._arrays`) and runs the loops on pointers; kernels that call kernels call the
`cdef` form.
"""

cimport numpy as cnp
from libc.float cimport DBL_MIN
from libc.math cimport (INFINITY, asin, atan2, ceil, erfc, exp, expm1, floor, hypot, log,
                        log1p, sqrt)

from occtrack._arrays cimport bdata, fdata, idata, length
from occtrack._arrays cimport py_imax, py_imin, py_max, py_min
from occtrack._arrays cimport (b8, dim, doubles, f64, i64, integers, new_doubles,
                               new_integers, zero_booleans, zero_doubles, zero_integers)
from occtrack.models._scan_geometry cimport Window, beam_direction, beam_window_c, near_range_uv

cnp.import_array()


cdef inline f64* _boxes(object a, str name) except NULL:
    """a's data, if a is a C-contiguous float64 array of edge boxes (n, 2, 2)."""
    cdef f64* x = doubles(a, 3, name)
    if dim(a, 1) != 2 or dim(a, 2) != 2:
        raise ValueError(f"{name}: boxes (n, 2, 2) are needed, not {a.shape}")
    return x


include "_box_geometry.pxi"
include "_box_objectwise.pxi"
include "_extent_kernels.pxi"
include "_scan.pxi"
