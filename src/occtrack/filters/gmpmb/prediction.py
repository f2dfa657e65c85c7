"""The filter's prediction, compiled (`occtrack.jit`): each component's motion, its Markov
features d and o, its survival, and the camera's image motion. Loops over a few hundred
components, too small for numpy's per-call overhead to pay off; `GaussianMixturePMB`
calls them."""

from __future__ import annotations

import numpy as np

from occtrack.jit import njit
from occtrack.models.box import MIN_HEIGHT


@njit
def _predict_pool(mass, mean, cov, det, occ, coast, coasting_after, F, Q, F_coast, Q_coast,
                  det_stationary, det_memory, occ_stationary, occ_memory, image_size,
                  survival_inside, exit_survival):
    """The prediction of every component, in place: motion (the coasting model for one
    unseen longer than `coasting_after` s), the Markov features d and o, survival."""
    _predict_in_place(mean, cov, coast > coasting_after, F, Q, F_coast, Q_coast)
    _relax_in_place(det, det_stationary, det_memory)
    _relax_in_place(occ, occ_stationary, occ_memory)
    _survive_in_place(mass, mean, image_size, survival_inside, exit_survival)


@njit
def _predict_in_place(mean, cov, coasting, F, Q, F_coast, Q_coast):
    """m <- F m, P <- F P F' + h^2 Q per component and axis, with h its box height (the
    unit of the motion noises, `ConstantVelocity.predict`) and (F, Q) the coasting model's
    for a component whose object was missed."""
    d = mean.shape[2]
    m, FP = np.empty(d), np.empty((d, d))
    for k in range(len(mean)):
        A, Qk = (F_coast, Q_coast) if coasting[k] else (F, Q)
        unit2 = max(2.0 * mean[k, 1, 2], MIN_HEIGHT) ** 2
        for b in range(mean.shape[1]):
            for r in range(d):
                m[r] = 0.0
                for c in range(d):
                    m[r] += A[r, c] * mean[k, b, c]
                    FP[r, c] = 0.0
                    for i in range(d):
                        FP[r, c] += A[r, i] * cov[k, b, i, c]
            for r in range(d):
                mean[k, b, r] = m[r]
                for c in range(d):
                    total = 0.0
                    for i in range(d):
                        total += FP[r, i] * A[c, i]
                    cov[k, b, r, c] = total + unit2 * Qk[r, c]


@njit
def _relax_in_place(p, stationary, memory):
    """`TwoStateMarkov.predict`: p <- stationary + memory (p - stationary)."""
    for k in range(len(p)):
        p[k] = stationary + memory * (p[k] - stationary)


@njit
def _survive_in_place(mass, mean, image_size, survival_inside, exit_survival):
    """Masses times the survival of a component whose centre is in the image (and whose box
    is at least 2 px wide and tall), else times `exit_survival`."""
    for k in range(len(mass)):
        inside = True
        for axis in range(2):
            centre = mean[k, axis, 0]
            if not (centre >= 0 and centre <= image_size[axis] and mean[k, axis, 2] >= 1.0):
                inside = False
        mass[k] *= survival_inside if inside else exit_survival


@njit
def _move_in_place(mean, cov, scale, shift, shift_variance):
    """x -> scale x + shift per axis: centres move, velocities and half-sizes scale,
    covariances scale by scale^2; the shift's own variance adds to every centre's."""
    for k in range(len(mean)):
        for axis in range(2):
            for r in range(mean.shape[2]):
                mean[k, axis, r] *= scale[axis]
                for c in range(mean.shape[2]):
                    cov[k, axis, r, c] *= scale[axis] ** 2
            mean[k, axis, 0] += shift[axis]
            cov[k, axis, 0, 0] += shift_variance[axis]
