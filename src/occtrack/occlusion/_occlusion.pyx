# cython: language_level=3
"""Compiled kernels of occtrack.occlusion (issue 23): `_hidden_at` of scan.py (`_scan.pxi`);
the maths and the calls are in the .py modules."""

cimport numpy as cnp
from libc.math cimport asin, atan2, erfc, exp, hypot, log1p, sqrt, INFINITY

from occtrack._arrays cimport b8, f64, dim, doubles, new_doubles, zero_booleans, zero_doubles
from occtrack.models._scan_geometry cimport Window, beam_direction, beam_window_c, near_range_uv

cnp.import_array()

include "_scan.pxi"
