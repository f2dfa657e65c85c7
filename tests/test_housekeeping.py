"""The filter's housekeeping on small hand-made mixtures: capacity, trimming, merging, labels,
the existence guard, and the Bayes update of detectability and occludability.

The expected values are worked out here from the formulas in the `occtrack.filters.gmpmb`
docstring, without calling the filter, so that a fault in any of these steps changes a number
that these tests check. (These steps run rarely on the scenes the other tests use.)"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

# the tracker package first: importing gmpmb alone runs into the circular import
# gmpmb -> tracker.config -> tracker/__init__ -> tracker.tracker -> gmpmb
import occtrack.tracker  # noqa: F401
from occtrack.filters.gmpmb import N_BIRTH, GaussianMixturePMB
from occtrack.occlusion.base import NoOcclusion, OcclusionTerms
from occtrack.tracker import TrackerConfig

NO_MERGING = dict(merge_position=1e-6, merge_velocity=1e-6)  # every component its own cell
EMPTY = (np.zeros((0, 2, 2)), np.zeros((0, 2, 2), dtype=bool), np.zeros(0))


class FixedTerms:
    """An occlusion model that gives every component the same v and q, and every detection
    the same h, so that the miss and hit terms can be worked out by hand."""

    name = "fixed"

    def __init__(self, visible: float, hidden: float, seen_hidden: float | None = None):
        self.v, self.q, self.h = visible, hidden, seen_hidden

    def terms(self, ctx):
        k, m = len(ctx.means), len(ctx.measurements)
        h = None if self.h is None else np.full(m, self.h)
        return OcclusionTerms(np.full(k, self.v), np.full(k, self.q), h)


def make(occlusion=None, **settings) -> GaussianMixturePMB:
    config = TrackerConfig(**{"capacity": 16, "max_labels": 4, **NO_MERGING, **settings})
    return GaussianMixturePMB(config, occlusion or NoOcclusion())


def person(x=900.0, y=400.0, vx=0.0, vy=0.0, half=(20.0, 60.0)) -> np.ndarray:
    """State (2, 3): per axis centre, velocity, half-size."""
    return np.array([[x, vx, half[0]], [y, vy, half[1]]])


def edges(state: np.ndarray) -> np.ndarray:
    """The noise-free box edges of a state, as one measurement (1, 2, 2)."""
    c, s = state[:, 0], state[:, 2]
    return np.stack([c - s, c + s], axis=-1)[None]


def load(f, mass, label, means=None, det=0.9, occ=0.5, cov_diag=(25.0, 100.0, 4.0)):
    """Put components straight into the filter's arrays and mark their labels' slots used."""
    mass, label = np.asarray(mass, dtype=float), np.asarray(label, dtype=np.int64)
    n = len(mass)
    if means is None:
        means = np.stack([person(900.0 + 40.0 * k) for k in range(n)])
    f.n = n
    f.mass[:n], f.label[:n], f.mean[:n] = mass, label, means
    f.cov[:n] = np.diag(cov_diag)
    f.det[:n], f.occ[:n] = det, occ
    f.slot_used[:] = False
    used = np.unique(label[label >= 0])
    f.slot_used[used] = True
    f.slot_hits[used] = f.config.confirm_hits  # confirmed objects, to which occlusion applies
    f.slot_age[used] = f.config.confirm_window
    f.coast[:n] = 0.0


def clutter_rate(kappa: float) -> float:
    """The `clutter_rate` that gives a detection of `person()`'s 40 x 120 px box in the
    default 1920 x 1080 image the clutter density kappa (score 1): kappa W H w h."""
    return kappa * 1920.0 * 1080.0 * 40.0 * 120.0


def features_after(d, o, likelihood):
    """Bayes by enumeration of the four (D, O) states, independent a priori (the filter keeps
    the two marginals): P(D = 1 | y), P(O = 1 | y) and P(y), for y with P(y | D, O) given."""
    joint = {(D, O): (d if D else 1 - d) * (o if O else 1 - o) * likelihood(D, O)
             for D, O in itertools.product((0, 1), (0, 1))}
    total = sum(joint.values())
    return (joint[1, 0] + joint[1, 1]) / total, (joint[0, 1] + joint[1, 1]) / total, total


def miss_likelihood(v, q):
    """Undetectable: missed. Detectable, not occludable: always seen. Detectable and
    occludable: missed if not visible (1 - v), or visible and its measurement hidden (v q)."""
    return lambda D, O: 1.0 if D == 0 else (0.0 if O == 0 else 1 - v + v * q)


def hit_likelihood(v, h):
    """A detection seen where the others would hide an occludable one with probability h."""
    return lambda D, O: 0.0 if D == 0 else (1.0 if O == 0 else v * (1 - h))


def groups(f):
    """label -> indices of the filter's components with that label."""
    lab = f.label[:f.n]
    return {int(k): np.flatnonzero(lab == k) for k in np.unique(lab)}


# -- capacity ---------------------------------------------------------------------------------


def test_select_keeps_the_heaviest_children_when_over_capacity():
    """A hard capacity keeps the heaviest children and says so, once, with the count."""
    f = make()  # capacity 16: room for 11 children plus the next step's 5 births
    room = 16 - N_BIRTH
    rng = np.random.default_rng(0)
    flat = rng.permutation(np.concatenate([np.linspace(0.01, 0.3, 25), [1e-6, 5e-6, 0.0]]))
    with pytest.warns(RuntimeWarning, match="capacity = 16 .* 25 were above prune_mass, "
                                            "the 14 lightest"):
        keep = f._select(flat)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.array_equal(f._select(flat), keep)  # reported once
    heaviest = np.sort(np.argsort(-flat)[:room])
    assert np.array_equal(keep, heaviest)
    assert np.sort(flat[keep]) == pytest.approx(np.linspace(0.01, 0.3, 25)[-room:], abs=0)


def test_select_below_capacity_only_prunes():
    f = make()
    flat = np.array([0.2, 1e-6, 0.0, 0.3, 1e-5, 2e-5, 0.1])  # prune_mass 1e-5 is dropped too
    assert f._select(flat).tolist() == [0, 3, 5, 6]
    exactly = np.linspace(0.1, 0.2, 16 - N_BIRTH)
    assert f._select(exactly).tolist() == list(range(16 - N_BIRTH))


@pytest.mark.filterwarnings("ignore:max_labels = 4")
def test_an_update_over_capacity_keeps_the_heaviest_children_unscaled(monkeypatch):
    """Six components near three detections have 24 children, more than the 11 that fit: the
    pool fills to exactly 11 (16 after the next births) and holds the 11 heaviest, as they
    were (selection rescales nothing)."""
    f = make(max_components_per_object=0)
    means = np.stack([person(900.0 + 3.0 * k) for k in range(6)])
    load(f, [0.5, 0.3, 0.6, 0.2, 0.9, 2.0], [0, 0, 1, 1, 2, -1], means,
         cov_diag=(400.0, 100.0, 100.0))
    z = np.concatenate([edges(person(x)) for x in (898.0, 905.0, 912.0)])
    seen = {}
    select = f._select

    def spy(flat):
        seen["flat"] = flat.copy()
        return select(flat)

    monkeypatch.setattr(f, "_select", spy)
    with pytest.warns(RuntimeWarning, match="capacity = 16"):
        f._update(z, f.measurement.observed(z), np.ones(3))
    children = seen["flat"]
    assert (children > f.config.prune_mass).sum() > 16 - N_BIRTH
    assert f.n == 16 - N_BIRTH
    assert np.sort(f.mass[:f.n]) == pytest.approx(np.sort(children)[-f.n:], rel=1e-12)
    f._predict()
    f._add_births()
    assert f.n == 16  # full, and the next update still fits
    monkeypatch.undo()
    f._update(z, f.measurement.observed(z), np.ones(3))
    assert f.n == 16 - N_BIRTH and (f.existence() <= 1).all()


# -- trimming ---------------------------------------------------------------------------------


def test_trim_keeps_each_objects_heaviest_and_its_existence():
    """Bernoulli 0 has five children, 1 two, the one born from measurement 1 four; the Poisson
    part's miss children (label -1, no measurement) are the intensity and are not trimmed."""
    f = make(max_components_per_object=3)
    mass = np.array([0.1, 0.4, 0.05, 0.3, 0.15, 0.2, 0.1, 0.3, 0.2, 0.1, 0.05, 0.5, 0.4, 0.3,
                     0.2])
    label = np.array([0] * 5 + [1] * 2 + [-1] * 8)
    meas = np.array([-1, 0, -1, 2, 1, -1, 0, 1, 1, 1, 1, -1, -1, -1, -1])
    order = np.random.default_rng(1).permutation(len(mass))  # the order must not matter
    mass, label, meas = mass[order], label[order], meas[order]
    group = np.where(label >= 0, label, np.where(meas >= 0, 10, -1))
    before = mass.copy()
    keep = f._trim_objects(mass, label, meas)

    for g, kept_masses in ((0, [0.4, 0.3, 0.15]), (1, [0.2, 0.1]), (10, [0.3, 0.2, 0.1])):
        mine = group == g
        assert sorted(before[keep & mine]) == pytest.approx(sorted(kept_masses), abs=0)
        assert mass[keep & mine].sum() == pytest.approx(before[mine].sum(), abs=1e-12)
        ratio = mass[keep & mine] / before[keep & mine]  # one scale per object
        assert ratio == pytest.approx(np.full(len(kept_masses), before[mine].sum()
                                              / sum(kept_masses)), rel=1e-12)
    poisson = group == -1
    assert keep[poisson].all() and np.array_equal(mass[poisson], before[poisson])


def test_trim_with_room_to_spare_changes_nothing():
    f = make(max_components_per_object=4)
    mass = np.array([0.3, 0.2, 0.1, 0.4])
    label = np.array([0, 0, -1, 1])
    keep = f._trim_objects(mass, label, np.array([-1, 0, 0, 0]))
    assert keep.all() and mass.tolist() == [0.3, 0.2, 0.1, 0.4]


def test_a_bernoulli_born_this_step_keeps_at_most_its_share_of_components():
    """Six Poisson components near one detection: the new Bernoulli of that detection is the
    six hit children; it keeps its two heaviest, rescaled to its existence
    L_0 / (kappa p_F + L_0). (Trimming used to skip label -1, so a newborn kept all six.)"""
    f = make(max_components_per_object=2, clutter_rate=clutter_rate(1e-8), capacity=32)
    means = np.stack([person(900.0 + 2.0 * k) for k in range(6)])
    w = np.array([0.3, 0.5, 0.2, 0.6, 0.4, 0.1])
    occ = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])  # kept by a hit with v = 1: names the parent
    load(f, w, [-1] * 6, means, det=0.8, occ=occ)
    z = edges(person(905.0))
    lik = np.exp(f.measurement.loglik(f.mean[:6], f.cov[:6], z, f.measurement.observed(z)))[:, 0]
    hits = w * 0.8 * lik
    born = hits / (1e-8 + hits.sum())
    f._update(z, f.measurement.observed(z), np.ones(1))

    g = groups(f)
    assert sorted(g) == [-1, 0]
    assert len(g[0]) == 2
    assert f.mass[g[0]].sum() == pytest.approx(born.sum(), rel=1e-12)
    heaviest = occ[np.argsort(-born)[:2]]
    assert sorted(f.occ[g[0]]) == pytest.approx(sorted(heaviest), rel=1e-12)
    # the Poisson part's miss children stay, each w (1 - d)
    assert sorted(f.mass[g[-1]]) == pytest.approx(sorted(w * 0.2), rel=1e-12)


# -- merging ----------------------------------------------------------------------------------


def test_merge_is_moment_matching():
    # cells are in box heights, the height rounded to a power of two: 128 px for these boxes
    """a and b (object 0) share a 10 px / 10 px/s cell, c (object 0) does not, d (object 1)
    sits on a but belongs to another object, e1 and e2 are Poisson components in one cell."""
    f = make(merge_position=10.0 / 128, merge_velocity=10.0 / 128)
    rng = np.random.default_rng(2)
    means = np.array([
        [[101.0, 1.0, 31.0], [402.0, -3.0, 62.0]],  # a
        [[108.0, 8.0, 38.0], [407.0, -9.0, 68.0]],  # b
        [[150.0, 0.0, 30.0], [400.0, 0.0, 60.0]],  # c
        [[101.0, 1.0, 31.0], [402.0, -3.0, 62.0]],  # d
        [[501.0, 2.0, 21.0], [301.0, 2.0, 51.0]],  # e1
        [[509.0, 7.0, 29.0], [308.0, 9.0, 59.0]],  # e2
    ])
    root = rng.normal(size=(6, 2, 3, 3))
    covs = root @ np.swapaxes(root, -1, -2) + np.eye(3)
    mass = np.array([0.3, 0.15, 0.2, 0.35, 0.05, 0.02])
    det = np.array([0.9, 0.5, 0.7, 0.6, 0.2, 0.8])
    occ = np.array([0.2, 0.7, 0.4, 0.5, 0.9, 0.1])
    label = np.array([0, 0, 0, 1, -1, -1])
    coast = np.array([0.0, 0.1, 0.0, 0.2, 0.0, 0.0])
    out = f._merge(mass, means, covs, det, occ, coast, label)
    assert len(out[0]) == 4

    def pooled(idx):
        w = mass[idx]
        share = w / w.sum()
        mu = np.einsum("k,kab->ab", share, means[idx])
        sigma = np.zeros((2, 3, 3))
        for k, s in zip(idx, share, strict=True):
            for axis in range(2):
                dev = means[k, axis] - mu[axis]
                sigma[axis] += s * (covs[k, axis] + np.outer(dev, dev))
        return (w.sum(), mu, sigma, share @ det[idx], share @ occ[idx], share @ coast[idx],
                label[idx[0]])

    expected = [pooled([0, 1]), pooled([2]), pooled([3]), pooled([4, 5])]
    for w, mu, sigma, d, o, t, lab in expected:
        (k,) = np.flatnonzero(np.isclose(out[0], w, rtol=1e-12, atol=0))
        assert out[1][k] == pytest.approx(mu, rel=1e-12)
        assert out[2][k] == pytest.approx(sigma, rel=1e-12)
        assert (out[3][k], out[4][k], out[5][k], out[6][k]) == (
            pytest.approx(d, rel=1e-12), pytest.approx(o, rel=1e-12),
            pytest.approx(t, rel=1e-12), lab)
    # the spread of the means is a large part of the merged covariance: dropping it shows
    ab = expected[0][2]
    without_spread = (mass[0] * covs[0] + mass[1] * covs[1]) / (mass[0] + mass[1])
    assert np.abs(ab - without_spread).max() > 5.0


def test_merge_leaves_distinct_cells_alone():
    f = make(merge_position=10.0 / 128, merge_velocity=10.0 / 128)
    means = np.stack([person(100.0), person(115.0), person(100.0, vx=15.0)])
    covs = np.broadcast_to(np.eye(3), (3, 2, 3, 3)).copy()
    out = f._merge(np.array([0.1, 0.2, 0.3]), means, covs, np.full(3, 0.5), np.full(3, 0.5),
                   np.zeros(3), np.zeros(3, dtype=np.int64))
    assert sorted(out[0]) == [0.1, 0.2, 0.3]


# -- existence and labels ---------------------------------------------------------------------


def test_existence_is_capped_at_one_and_only_there():
    """Object 0 reached r = 1.2 (by rounding, say): scaled to 1, its density unchanged. Object
    1 and the Poisson part (an intensity, which may exceed 1) are left as they are."""
    f = make()
    load(f, [0.7, 0.5, 0.3, 0.2, 3.0, 0.6, 0.4], [0, 0, 1, 1, -1, 2, 2])
    f._cap_existence()
    r = f.existence()
    assert r[0] == pytest.approx(1.0, abs=1e-15) and (r <= 1.0).all()
    assert f.mass[:2] == pytest.approx([0.7 / 1.2, 0.5 / 1.2], rel=1e-15)
    assert f.mass[2:7].tolist() == [0.3, 0.2, 3.0, 0.6, 0.4]  # r = 1 exactly is not over


def test_labels_go_to_the_strongest_above_label_min_existence():
    """Slots 0 (r 0.9) and 1 (r 5e-4) are in use; measurements 0, 1, 2 give new Bernoullis of
    r 0.4, 2e-4, 0.6. Four slots would hold all five, but 5e-4 and 2e-4 are below
    label_min_existence (1e-3): their components go to the Poisson part, label -1."""
    f = make(max_labels=4)
    f.slot_used[:] = [True, True, False, False]
    mass = np.array([0.5, 0.4, 5e-4, 0.3, 0.1, 2e-4, 0.6, 0.05])
    label = np.array([0, 0, 1, -1, -1, -1, -1, -1])
    newborn = np.array([-1, -1, -1, 0, 0, 1, 2, -1])  # the last: a Poisson miss child
    out = f._assign_labels(mass, label, newborn, 3)
    assert out[:2].tolist() == [0, 0]  # an existing Bernoulli keeps its slot
    assert out[2] == -1 and out[5] == -1 and out[7] == -1
    assert out[3] == out[4] and len({0, int(out[3]), int(out[6])}) == 3 and min(out[[3, 6]]) > 0
    assert np.flatnonzero(f.slot_used).tolist() == sorted({0, int(out[3]), int(out[6])})
    assert mass.tolist() == [0.5, 0.4, 5e-4, 0.3, 0.1, 2e-4, 0.6, 0.05]  # nothing scaled


def test_the_weakest_labels_are_recycled_when_slots_run_out():
    """Under a hard max_labels the strongest keep their labels, and the cut is reported."""
    f = make(max_labels=2)
    f.slot_used[:] = True
    mass = np.array([0.9, 0.2, 0.6, 0.1])
    label = np.array([0, 1, -1, -1])
    newborn = np.array([-1, -1, 0, 1])
    with pytest.warns(RuntimeWarning, match="max_labels = 2 .* 4 Bernoullis .* the 2 weakest"):
        out = f._assign_labels(mass, label, newborn, 2)
    assert out.tolist() == [0, -1, 1, -1]  # r 0.9 and 0.6 keep slots, 0.2 and 0.1 go
    assert f.slot_used.tolist() == [True, True]


def test_a_weak_bernoulli_is_recycled_into_the_poisson_part_with_its_mass():
    """No detections. Object 0 (r 0.8) stays; object 1 (r 5e-4, two components) drops below
    label_min_existence and its components join the Poisson part with their masses, so the
    Poisson mass is sum w (1 - d) over the old Poisson part plus object 1's miss children
    w (1 - d) / (1 - r + r (1 - d))."""
    f = make()
    load(f, [0.8, 3e-4, 2e-4, 0.5, 0.25], [0, 1, 1, -1, -1], det=0.5)
    f._update(*EMPTY)
    r1 = 5e-4
    poisson = 0.75 * 0.5 + r1 * 0.5 / (1 - r1 + r1 * 0.5)
    g = groups(f)
    assert f.slot_used.tolist() == [True, False, False, False]
    assert sorted(g) == [-1, 0] and len(g[-1]) == 4
    assert f.mass[g[-1]].sum() == pytest.approx(poisson, rel=1e-12)
    assert f.existence()[0] == pytest.approx(0.4 / 0.6, rel=1e-12)


# -- detectability and occludability ----------------------------------------------------------


@pytest.mark.parametrize("misses", [1, 4])
def test_features_after_misses_equal_bayes(misses):
    """An object missed `misses` times in a row where it is partly hidden (v = 0.6) and where
    a visible measurement would be hidden with q = 0.3. Each step: the Markov prediction
    p <- s + (1 - h)^(dt / 0.5) (p - s) of both features and survival, then Bayes with the
    miss likelihood by enumeration, and r <- r miss / (1 - r + r miss)."""
    v, q = 0.6, 0.3
    f = make(FixedTerms(v, q))
    c = f.config
    load(f, [0.9], [0], det=0.7, occ=0.6)
    d, o, r = 0.7, 0.6, 0.9
    keep_d = (1 - c.detectability_ratio) ** (c.dt / 0.5)
    keep_o = (1 - c.occludability_ratio) ** (c.dt / 0.5)
    for _ in range(misses):
        f._predict()
        f._update(*EMPTY)
        d = c.stationary_detectability + keep_d * (d - c.stationary_detectability)
        o = c.occludability + keep_o * (o - c.occludability)
        r *= np.exp(-c.death_rate * c.dt)
        d, o, miss = features_after(d, o, miss_likelihood(v, q))
        r = r * miss / (1 - r + r * miss)
    assert f.n == 1
    assert (f.det[0], f.occ[0]) == (pytest.approx(d, rel=1e-12), pytest.approx(o, rel=1e-12))
    assert f.existence()[0] == pytest.approx(r, rel=1e-12)
    assert o > 0.8  # missed where it could hide: more occludable than the stationary 0.8


def test_features_after_a_hit_equal_bayes():
    """One object (r 0.8, d 0.7, o 0.6), one detection near it, v = 0.6, q = 0.3, h = 0.25.
    The association is exact for one object and one detection:
    p_hit = L / (L + miss_obj kappa'), L = r P(seen | D, O averaged) p(z | x),
    kappa' = kappa (1 - o_stationary h). The hit child has D = 1 and O by Bayes with the
    hit likelihood; the miss child has both by Bayes with the miss likelihood."""
    v, q, h = 0.6, 0.3, 0.25
    kappa = 1e-7
    f = make(FixedTerms(v, q, h), clutter_rate=clutter_rate(kappa))
    load(f, [0.8], [0], det=0.7, occ=0.6)
    z = edges(person(905.0, 396.0))
    lik = np.exp(f.measurement.loglik(f.mean[:1], f.cov[:1], z,
                                      f.measurement.observed(z)))[0, 0]
    d_miss, o_miss, miss = features_after(0.7, 0.6, miss_likelihood(v, q))
    d_hit, o_hit, seen = features_after(0.7, 0.6, hit_likelihood(v, h))
    big_l = 0.8 * seen * lik
    miss_obj = 1 - 0.8 + 0.8 * miss
    clutter = kappa * (1 - f.config.occludability * h)
    p_hit = big_l / (big_l + miss_obj * clutter)
    assert 0.2 < p_hit < 0.98  # both children matter
    f._update(z, f.measurement.observed(z), np.ones(1))

    assert f.n == 2 and (f.label[:2] == 0).all()
    hit, missed = (0, 1) if f.det[0] == 1.0 else (1, 0)
    assert f.det[hit] == 1.0 and d_hit == 1.0
    assert f.occ[hit] == pytest.approx(o_hit, rel=1e-12)
    assert f.mass[hit] == pytest.approx(p_hit, rel=1e-9)
    assert (f.det[missed], f.occ[missed]) == (pytest.approx(d_miss, rel=1e-12),
                                              pytest.approx(o_miss, rel=1e-12))
    assert f.mass[missed] == pytest.approx(0.8 * miss * (1 - p_hit) / miss_obj, rel=1e-9)
    assert o_hit < 0.6 < o_miss
