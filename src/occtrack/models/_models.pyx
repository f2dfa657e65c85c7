# cython: language_level=3
"""Compiled kernels of occtrack.models (issue 23): scan_geometry.py's `beam_window` and
`near_range` (`_scan_geometry.pxi`, their inline C forms in `_scan_geometry.pxd`),
scan_segments.py's `_linearise` and `_other_beams` (`_scan_segments.pxi`) and
scan_hand_made.py's `_other_beams_hand_made` (`_scan_hand_made.pxi`); the maths and the calls
are in the .py modules."""

cimport numpy as cnp
from libc.math cimport asin, atan2, erfc, fabs, hypot, log, sqrt

from occtrack._arrays cimport (b8, f64, i64, dim, doubles, integers, new_doubles, zero_booleans,
                               zero_doubles)
from occtrack.models._scan_geometry cimport (Window, beam_direction, beam_window_c, near_range_c,
                                             near_range_uv)

cnp.import_array()

include "_scan_geometry.pxi"
include "_scan_segments.pxi"
include "_scan_hand_made.pxi"
