# cython: language_level=3
"""Compiled kernels of occtrack.filters (issue 23).

_particle_tomb.pxi: the highway's particle multi-Bernoulli tracker, one kernel per stage of a
step (predict, associate, update, resample, recycle); the maths and the call are in
particle_tomb.py. Each kernel reads as the numba loop it replaced: arrays are C pointers
(2-d and 3-d indexed by hand), sums taken in the same order, so the numbers are the same to
the last bit. A `def` entry checks each array once (dtype, dimensions, C order) and hands
pointers to a `cdef` kernel. (The gmpmb subpackage has its own extension.)
"""

cimport numpy as cnp

cnp.import_array()

include "_particle_tomb.pxi"
