"""The filter's prediction, compiled (`_gmpmb`, source `_prediction.pxi`): each component's
motion, its Markov features d and o, its survival, and the camera's image motion. Loops over
a few hundred components, too small for numpy's per-call overhead to pay off;
`GaussianMixturePMB` calls them."""

from __future__ import annotations

from occtrack.filters.gmpmb._gmpmb import (  # noqa: F401 (the kernels, under their names)
    _move_in_place,
    _predict_in_place,
    _predict_pool,
    _relax_in_place,
    _survive_in_place,
)
