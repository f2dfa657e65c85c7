"""The update's children, compiled (`_gmpmb`, source `_children.pxi`): their masses from
loopy BP's marginals, which are kept (pruning, at most `max_components_per_object` per
object), and what each inherits from its parent (state, label, d, o, coasting time). Loops
over components and pairs, too small for numpy's per-call overhead to pay off;
`GaussianMixturePMB._update` calls them. `_miss_branch_moments` is numpy."""

from __future__ import annotations

import numpy as np

from occtrack.filters.gmpmb._gmpmb import (  # noqa: F401 (the kernels, under their names)
    _child_features,
    _child_parents,
    _children,
    _inherit,
    _kept_children,
    _trim,
)


def _miss_branch_moments(mean, cov, parent, j, det, occ, v, q, miss, centre, variance):
    """In place, the miss children (j < 0) of component parent[c]: their density
    p(x) (1 - d + d o v q(x)) / miss moment-matched, given the moments (`centre`, per-axis
    `variance`) of p(x) q(x) / q of each parent. The hidden share s = d o v q / miss moves the
    centre there and the rest of the state with it (its regression on the centre, per axis,
    gain g = P[:, 0] / P[0, 0]): m' = m + s g (c_h - m_0), P' = P + s (v_h - P_00 +
    (1 - s) (c_h - m_0)^2) g g'. Numpy: only the lidar scan tracker's occlusion gives
    these moments."""
    rows = np.flatnonzero(j < 0)
    if len(rows) == 0:
        return
    p = parent[rows]
    share = np.clip(det[p] * occ[p] * v[p] * q[p] / np.maximum(miss[p], 1e-300), 0.0, 1.0)
    for axis in range(mean.shape[1]):
        P = cov[rows, axis]
        P00 = P[:, 0, 0]
        gain = P[:, :, 0] / np.maximum(P00, 1e-300)[:, None]
        dm = centre[p, axis] - mean[rows, axis, 0]
        dv = variance[p, axis] - P00
        mean[rows, axis] += (share * dm)[:, None] * gain
        cov[rows, axis] += (share * (dv + (1.0 - share) * dm * dm))[:, None, None] * (
            gain[:, :, None] * gain[:, None, :])
