"""numba's `njit` with the project's settings, for the loops that cannot be vectorised.

A tracker step on a frame of a few dozen detections is a few thousand floating-point
operations; written as numpy array expressions it costs a few hundred array calls of a
microsecond or more each, so the call overhead, not the arithmetic, sets the frame rate. The
per-pair and per-component kernels (Kalman update, likelihoods, merging, prediction) are
therefore compiled. `cache=True` keeps the machine code on disk (beside the module, or in the
user's cache folder when that is read-only), so only the first run on a machine compiles;
`error_model="numpy"` makes a division by zero give inf or nan as the array code it replaces
did, instead of raising.
"""

from __future__ import annotations

from collections.abc import Callable

import numba


def njit(function: Callable) -> Callable:
    """Compile `function` in nopython mode, cached on disk."""
    return numba.njit(cache=True, nogil=True, error_model="numpy")(function)
