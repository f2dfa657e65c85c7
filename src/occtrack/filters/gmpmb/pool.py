"""The filter's component pool, compiled (`_gmpmb`, source `_pool.pxi`): its order by label,
the merging of one object's components that share a cell, and the births it takes in, with
their size prior learnt from the detections. Loops over a few hundred components, too small
for numpy's per-call overhead to pay off; `GaussianMixturePMB` calls them."""

from __future__ import annotations

from occtrack.filters.gmpmb._gmpmb import (  # noqa: F401 (the kernels, under their names)
    _append_births,
    _cell_keys,
    _count_sizes,
    _learnt_sizes,
    _merge_packed,
    _packed_order,
    _pool_cells,
    _prior_sizes,
    _rotate,
    _sort_pool,
)
