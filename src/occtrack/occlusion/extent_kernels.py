"""Compiled loops of the highway's object-wise occlusion handlers
(`occtrack.occlusion.highway`): one pass over the particles each, no temporaries. Imported
only when a handler runs.

Particles arrive flat: angles a_l <= a_r (ends over lane distance), lane, owner track (-1:
the undetected intensity) and weight; the particles of one track are contiguous.

The loops are in `_occlusion.pyx` (its `_extent_kernels.pxi`): `track_extents` (each track's
lane and weight-averaged extent), `expval_visibility` (the expected-value handler's product
over the nearer tracks' extents) and `grid_visibility` (the visibility grid's handler).
"""

from __future__ import annotations

from occtrack.occlusion._occlusion import expval_visibility, grid_visibility, track_extents

__all__ = ["expval_visibility", "grid_visibility", "track_extents"]
