# cython: language_level=3
"""Compiled kernels of occtrack.tracker (issue 23), one source per module they serve:

* `_boxes.pxi`: boxes.py's fast check of a detector's frame (`_checked_ltwh`);
* `_camera.pxi`: camera.py's camera shift and expansion from the detections (`_camera_dense`,
  `_estimate_dense`, `_candidates`, `_mutual_shifts`, `_mode_shift`, `_votes`, ...);
* `_confidence.pxi`: confidence.py's confidence of a reported box (`box_covariances`,
  `_report_confidence`, `_overlap_probability`, ...);
* `_sizes.pxi`: sizes.py's bookkeeping of the sizes the tracks take (`_record_sizes`);
* `_tracker_rows.pxi`: tracker.py's reporting rule and rows (`_reported`, `_report_rows`).

The maths and the calls are in those modules, which import the kernels from here under the
same names. Each kernel is written as its numba loop read: arrays are C pointers, 2-d and 3-d
indexed by hand, each sum taken in the same order (no fused multiply-add, no reassociation),
so the numbers are the same to the last bit. A `def` entry checks each array once (dtype,
dimensions, C order: `occtrack._arrays`) and hands pointers to `cdef` code; kernels that call
kernels call the `cdef` versions.

Two pieces are C written here, for speed, exact by construction: Python's max and min of two
numbers as SSE2's maxsd / minsd (gcc branches on max(x, 0.0) otherwise), and the draw loop of
`_overlap_probability` with the two image axes as the two lanes of one SSE2 register (numba's
AVX code packed them so); each has the plain C form beside it for a machine without SSE2, and
both give numba's numbers to the bit.
"""

cimport numpy as cnp
from libc.math cimport fabs, floor, isfinite, sqrt

from occtrack._arrays cimport bdata, fdata, idata, length
from occtrack._arrays cimport py_imax, py_imin, py_max, py_min
from occtrack._arrays cimport (
    argsort_stable,
    b8,
    booleans,
    dim,
    doubles,
    f64,
    i64,
    integers,
    new_booleans,
    new_doubles,
    new_integers,
    zero_booleans,
    zero_doubles,
    zero_integers,
)

import numpy as np

cnp.import_array()


include "_boxes.pxi"
include "_camera.pxi"
include "_confidence.pxi"
include "_sizes.pxi"
include "_tracker_rows.pxi"
