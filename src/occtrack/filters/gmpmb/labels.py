"""The filter's label slots and their Bernoullis, compiled (`_gmpmb`, source `_labels.pxi`):
existence per label, which Bernoullis keep a label and which get a new slot, n-of-m
confirmation, the existence guard, the moments of each object and the recycling of undetected
objects whose place is lost. Loops over a few dozen slots, too small for numpy's per-call
overhead to pay off; `GaussianMixturePMB` calls them."""

from __future__ import annotations

from occtrack.filters.gmpmb._gmpmb import (  # noqa: F401 (the kernels, under their names)
    _cap_in_place,
    _confirm_in_place,
    _count_in_place,
    _keep_labels,
    _label_sums,
    _object_moments,
    _open_slots,
    _rank_bernoullis,
    _recycle_unplaced,
    _split_ranked,
)
