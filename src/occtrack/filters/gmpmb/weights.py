"""The update's weights, compiled (`_gmpmb`, source `_weights.pxi`): each component's miss
term under occlusion, the (component, detection) pairs and their hit weights l_kj, and the
association's weights miss_i, L_ij and L_0j that loopy BP takes (the formulas are
`occtrack.filters.gmpmb`'s docstring). Loops over components and pairs, too small for
numpy's per-call overhead to pay off; `GaussianMixturePMB._update` calls them. A pair whose
hit weight is at most e^LOG_FLOOR is impossible."""

from __future__ import annotations

from occtrack.filters.gmpmb._gmpmb import (  # noqa: F401 (the kernels, under their names)
    LOG_FLOOR,
    _all_pairs,
    _association_weights,
    _clipped,
    _hidden_evidence,
    _hit_edges,
    _miss_terms,
    _new_weights,
    _object_misses,
    _object_rows,
    _occludable,
    _strong_edges,
)
