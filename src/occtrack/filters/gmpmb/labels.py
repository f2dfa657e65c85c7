"""The filter's label slots and their Bernoullis, compiled (`occtrack.jit`): existence per
label, which Bernoullis keep a label and which get a new slot, n-of-m confirmation, the
existence guard and the moments of each object. Loops over a few dozen slots, too small for
numpy's per-call overhead to pay off; `GaussianMixturePMB` calls them."""

from __future__ import annotations

import numpy as np

from occtrack.jit import njit


@njit
def _label_sums(label, mass, L):
    """r_i = sum of w_k over the components with label i, for i < L (label -1: none)."""
    r = np.zeros(L)
    for k in range(len(label)):
        if label[k] >= 0:
            r[label[k]] += mass[k]
    return r


@njit
def _rank_bernoullis(label, mass, newborn, used, M, min_existence):
    """(used slots, measurements with a newborn Bernoulli, the existence of each of those
    in that order, their indices strongest first among those at min_existence or above)."""
    r_old = _label_sums(label, mass, len(used))
    r_new = _label_sums(newborn, mass, M)
    old = np.flatnonzero(used)
    new = np.flatnonzero(r_new > 0)
    r_all = np.concatenate((r_old[old], r_new[new]))
    ranked = np.argsort(-r_all, kind="mergesort")
    return old, new, r_all, ranked[r_all[ranked] >= min_existence]


@njit
def _keep_labels(label, mass, newborn, used, M, min_existence, limit):
    """`GaussianMixturePMB._assign_labels` up to the opening of new slots: the strongest
    Bernoullis at min_existence or above keep (or will get) a label, at most `limit` of them
    when limit > 0; the other used slots are freed in place and their components' labels set
    to -1. Returns (labels, the measurements whose newborn gets a slot (ascending), the
    existences cut by the limit, how many Bernoullis were at min_existence or above)."""
    old, new, r_all, ranked = _rank_bernoullis(label, mass, newborn, used, M, min_existence)
    held = len(ranked)
    lost = np.empty(0)
    if limit and held > limit:
        lost = r_all[ranked[limit:]]
        ranked = ranked[:limit]
    keep_old, keep_new = _split_ranked(ranked, len(old))
    gone = np.zeros(len(used), dtype=np.bool_)
    for i in range(len(old)):
        if not keep_old[i]:
            used[old[i]] = False
            gone[old[i]] = True
    out = label.copy()
    for k in range(len(label)):
        if label[k] >= 0 and gone[label[k]]:
            out[k] = -1
    return out, new[keep_new], lost, held


@njit
def _split_ranked(ranked, n_old):
    """Which of the n_old existing Bernoullis keep their label, and the new ones that get
    one (indices among the new, ascending)."""
    keep_old = np.zeros(n_old, dtype=np.bool_)
    count = 0
    for i in ranked:
        if i < n_old:
            keep_old[i] = True
        else:
            count += 1
    keep_new = np.empty(count, np.int64)
    count = 0
    for i in ranked:
        if i >= n_old:
            keep_new[count] = i - n_old
            count += 1
    keep_new.sort()
    return keep_old, keep_new


@njit
def _open_slots(label, newborn, meas, M, serial0, used, serial, age, hits, coast, detection,
                cls, classes):
    """Give the newborn Bernoullis of measurements `meas` the first free slots (in place on
    the slot arrays): serials from serial0, one hit at age 1, their measurement's class
    (`classes`, empty: one class). Returns the components' labels."""
    slot_of_meas = np.full(M, -1, dtype=np.int64)
    i = 0
    for s in range(len(used)):
        if i == len(meas):
            break
        if not used[s]:
            used[s] = True
            slot_of_meas[meas[i]] = s
            serial[s] = serial0 + i
            age[s] = 1
            hits[s] = 1
            coast[s] = 0.0
            detection[s] = meas[i]
            cls[s] = classes[meas[i]] if len(classes) else 0
            i += 1
    out = label.copy()
    for k in range(len(label)):
        if newborn[k] >= 0:
            out[k] = slot_of_meas[newborn[k]]
    return out


@njit
def _count_in_place(detection, age, hits, coast, used, slots, row, col, p_hit, dt):
    """`GaussianMixturePMB._count_detections` on the slot arrays, in place."""
    detection[:] = -1
    for e in range(len(p_hit)):
        if p_hit[e] > 0.5:
            detection[slots[row[e]]] = col[e]
    for i in range(len(used)):
        hit = detection[i] >= 0
        if used[i]:
            age[i] += 1
            if not hit:
                coast[i] += dt
        if hit:
            hits[i] += 1
            coast[i] = 0.0


@njit
def _confirm_in_place(used, age, hits, label, window, needed):
    """`GaussianMixturePMB._confirm_or_delete`: frees the doomed slots in place and returns
    which components are kept."""
    doomed = np.zeros(len(used), dtype=np.bool_)
    any_doomed = False
    for i in range(len(used)):
        if used[i] and hits[i] + max(window - age[i], 0) < needed:
            doomed[i] = True
            used[i] = False
            any_doomed = True
    keep = np.ones(len(label), dtype=np.bool_)
    if any_doomed:
        for k in range(len(label)):
            if label[k] >= 0 and doomed[label[k]]:
                keep[k] = False
    return keep


@njit
def _cap_in_place(mass, label, L):
    """`GaussianMixturePMB._cap_existence` in place: an object whose masses sum above 1
    (rounding) has them scaled by 1 / r."""
    r = _label_sums(label, mass, L)
    for k in range(len(label)):
        i = label[k]
        if i >= 0 and r[i] > 1.0:
            mass[k] *= 1.0 / max(r[i], 1e-300)


@njit
def _object_moments(label, mass, mean, cov, L):
    """`GaussianMixturePMB.object_moments` of components with these labels: per slot the
    existence, the mass-weighted mean state and the centre's standard deviation."""
    r = _label_sums(label, mass, L)
    means = np.zeros((L,) + mean.shape[1:])
    var = np.zeros((L, 2))
    for k in range(len(label)):
        i = label[k]
        if i >= 0:
            share = mass[k] / max(r[i], 1e-300)
            for b in range(mean.shape[1]):
                for c in range(mean.shape[2]):
                    means[i, b, c] += share * mean[k, b, c]
    for k in range(len(label)):
        i = label[k]
        if i >= 0:
            share = mass[k] / max(r[i], 1e-300)
            for a in range(2):
                var[i, a] += share * (cov[k, a, 0, 0] + (mean[k, a, 0] - means[i, a, 0]) ** 2)
    return r, means, np.sqrt(var)
