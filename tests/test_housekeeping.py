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

from occtrack.filters.gmpmb import INITIAL_POOL, INITIAL_SLOTS, N_BIRTH, GaussianMixturePMB
from occtrack.filters.gmpmb.children import _trim
from occtrack.filters.gmpmb.pool import _cell_keys, _packed_order
from occtrack.models.box import edges_from_ltwh
from occtrack.models.motion import ConstantVelocity
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
    """A filter on the Gaussian edge likelihood (no tail, tests/test_edge_tail.py has it), so
    that the expected numbers below are the Gaussian's."""
    config = TrackerConfig(**{"capacity": 16, "max_labels": 4, "tail_weight": 0.0,
                              **NO_MERGING, **settings})
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


@pytest.mark.parametrize("seed", range(4))
def test_select_keeps_exactly_the_heaviest_of_many(seed):
    f = make(capacity=64)
    flat = np.random.default_rng(seed).random(2000)
    with pytest.warns(RuntimeWarning, match="capacity = 64 .* the 1941 lightest"):
        keep = f._select(flat)
    assert np.array_equal(keep, np.sort(np.argsort(-flat)[:64 - N_BIRTH]))


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


def test_a_growing_pool_doubles_and_keeps_every_component():
    """capacity = 0: the pool's arrays at least double when they grow, keep the components
    they hold (values and dtypes), and a new entry is empty (label -1: no Bernoulli)."""
    f = make(capacity=0)
    assert len(f.mass) == INITIAL_POOL
    load(f, [0.5, 0.3, 0.2], [0, -1, 1], det=0.7, occ=0.4)
    f.coast[:3] = [0.0, 0.5, 1.0]
    before = {name: getattr(f, name).copy() for name in f._POOL}
    same = {name: getattr(f, name) for name in f._POOL}
    f._reserve(INITIAL_POOL)  # fits: the very same arrays
    assert all(getattr(f, name) is same[name] for name in f._POOL)
    f._reserve(INITIAL_POOL + 1)
    for name in f._POOL:
        arr = getattr(f, name)
        assert len(arr) == 2 * INITIAL_POOL and arr.dtype == before[name].dtype
        assert arr.shape[1:] == before[name].shape[1:]
        assert np.array_equal(arr[:3], before[name][:3])
        assert (arr[3:] == (-1 if name == "label" else 0)).all()
    f._reserve(5 * len(f.mass))  # more than double: exactly what is asked
    assert len(f.mass) == len(f.label) == 10 * INITIAL_POOL
    assert np.array_equal(f.cov[:3], before["cov"][:3]) and (f.label[3:] == -1).all()


def test_label_slots_grow_and_keep_every_slot():
    """max_labels = 0: the slot arrays at least double, every old slot (used or not) is kept,
    and a new slot is unused with no detection and no serial (-1)."""
    f = make(max_labels=0)
    assert len(f.slot_used) == INITIAL_SLOTS
    f.slot_used[[0, 2]] = True
    f.slot_age[:3], f.slot_hits[:3], f.slot_coast[:3] = [4, 9, 2], [3, 7, 1], [0.0, 0.2, 0.4]
    f.slot_detection[:3], f.slot_serial[:3], f.slot_class[:3] = [1, -1, 0], [0, 1, 2], [2, 0, 5]
    f.slot_hidden[:3] = [0.0, 0.3, 0.9]
    before = {name: getattr(f, name).copy() for name in f._SLOTS}
    f._reserve_slots(INITIAL_SLOTS)
    assert all(np.array_equal(getattr(f, name), before[name]) for name in f._SLOTS)
    assert len(f.slot_used) == INITIAL_SLOTS
    f._reserve_slots(INITIAL_SLOTS + 1)
    empty = {"slot_detection": -1, "slot_serial": -1}
    for name in f._SLOTS:
        arr = getattr(f, name)
        assert len(arr) == 2 * INITIAL_SLOTS and arr.dtype == before[name].dtype
        assert np.array_equal(arr[:INITIAL_SLOTS], before[name])
        assert (arr[INITIAL_SLOTS:] == empty.get(name, 0)).all()
    f._reserve_slots(1000)
    assert len(f.slot_used) == len(f.slot_hidden) == 1000
    assert np.array_equal(f.slot_serial[:3], [0, 1, 2]) and (f.slot_serial[3:] == -1).all()


def test_more_new_bernoullis_than_slots_get_a_label_each_when_labels_grow():
    """40 new Bernoullis and 32 slots, no hard limit: every one gets its own slot and a new
    serial, and nothing is reported."""
    f = make(max_labels=0)
    f.slot_used[0] = True
    f.slot_serial[0], f._next_serial = 0, 1
    mass = np.append(np.linspace(0.2, 0.6, 40), 0.9)
    label = np.append(np.full(40, -1), 0)
    newborn = np.append(np.arange(40), -1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = f._assign_labels(mass, label, newborn, 40)
    assert out[-1] == 0 and len(set(out[:40].tolist())) == 40 and (out[:40] > 0).all()
    assert len(f.slot_used) == 2 * INITIAL_SLOTS and f.slot_used.sum() == 41
    assert sorted(f.slot_serial[out[:40]].tolist()) == list(range(1, 41))
    assert (f.slot_age[out[:40]] == 1).all() and (f.slot_hits[out[:40]] == 1).all()
    assert f.slot_detection[out[:40]].tolist() == list(range(40))


def test_a_growing_pool_tracks_exactly_as_a_large_fixed_one():
    """Growth must change nothing but memory: 254 components, the births that overflow the
    initial 256 and an update with three detections give the same pool, bit for bit, as a
    capacity far from its limit, and no warning."""
    rng = np.random.default_rng(5)
    n = INITIAL_POOL - 2
    means = np.stack([person(x, y) for x, y in zip(rng.uniform(100, 1800, n),
                                                   rng.uniform(200, 900, n), strict=True)])
    mass = rng.uniform(0.001, 0.02, n)
    label = np.where(np.arange(n) < 6, np.arange(n) % 3, -1)
    z = np.concatenate([edges(means[k]) for k in (0, 1, 2)])
    pools = []
    for f in (make(capacity=0, max_labels=0), make(capacity=4096, max_labels=4096)):
        load(f, mass, label, means)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            f._add_births()
            grown = f.n
            f._update(z, f.measurement.observed(z), np.ones(3))
        pools.append((grown, f.n, [getattr(f, a)[:f.n].copy() for a in f._POOL],
                      f.existence()[:INITIAL_SLOTS]))
    (grown, n_grow, pool_grow, r_grow), (fixed, n_fixed, pool_fixed, r_fixed) = pools
    assert grown == fixed > INITIAL_POOL and n_grow == n_fixed > INITIAL_POOL
    assert all(np.array_equal(a, b) for a, b in zip(pool_grow, pool_fixed, strict=True))
    assert np.array_equal(r_grow, r_fixed)


# -- trimming ---------------------------------------------------------------------------------


def test_trim_keeps_each_objects_heaviest_and_its_existence():
    """Bernoulli 0 has five children, 3 two, the one born from measurement 1 four; the Poisson
    part's miss children (label -1, no measurement) are the intensity and are not trimmed."""
    f = make(max_components_per_object=3)
    mass = np.array([0.1, 0.4, 0.05, 0.3, 0.15, 0.2, 0.1, 0.3, 0.2, 0.1, 0.05, 0.5, 0.4, 0.3,
                     0.2])
    label = np.array([0] * 5 + [3] * 2 + [-1] * 8)
    meas = np.array([-1, 0, -1, 2, 1, -1, 0, 1, 1, 1, 1, -1, -1, -1, -1])
    order = np.random.default_rng(1).permutation(len(mass))  # the order must not matter
    mass, label, meas = mass[order], label[order], meas[order]
    group = np.where(label >= 0, label, np.where(meas >= 0, 10, -1))
    before = mass.copy()
    keep = _trim(mass, label, meas, 3, len(f.slot_used))

    for g, kept_masses in ((0, [0.4, 0.3, 0.15]), (3, [0.2, 0.1]), (10, [0.3, 0.2, 0.1])):
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
    keep = _trim(mass, label, np.array([-1, 0, 0, 0]), 4, len(f.slot_used))
    assert keep.all() and mass.tolist() == [0.3, 0.2, 0.1, 0.4]


def test_a_bernoulli_born_this_step_keeps_at_most_its_share_of_components():
    """Six Poisson components near one detection, and one object (slot 0) far from it: the new
    Bernoulli of that detection is the six hit children; it keeps its two heaviest, rescaled
    to its existence L_0 / (kappa p_F + L_0). (Trimming used to skip label -1, so a newborn
    kept all six.) The far object is only missed: r <- r miss / (1 - r + r miss)."""
    f = make(max_components_per_object=2, clutter_rate=clutter_rate(1e-8), capacity=32)
    means = np.stack([person(900.0 + 2.0 * k) for k in range(6)] + [person(100.0)])
    w = np.array([0.3, 0.5, 0.2, 0.6, 0.4, 0.1])
    occ = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])  # kept by a hit with v = 1: names the parent
    load(f, [*w, 0.5], [-1] * 6 + [0], means, det=0.8, occ=[*occ, 0.5])
    z = edges(person(905.0))
    lik = np.exp(f.measurement.loglik(f.mean[:7], f.cov[:7], z, f.measurement.observed(z)))[:, 0]
    assert lik[6] == 0.0  # out of reach of the detection
    hits = w * 0.8 * lik[:6]
    born = hits / (1e-8 + hits.sum())
    f._update(z, f.measurement.observed(z), np.ones(1))

    g = groups(f)
    assert sorted(g) == [-1, 0, 1]
    assert f.existence()[0] == pytest.approx(0.5 * 0.2 / (1 - 0.5 + 0.5 * 0.2), rel=1e-12)
    assert len(g[1]) == 2
    assert f.mass[g[1]].sum() == pytest.approx(born.sum(), rel=1e-12)
    heaviest = occ[np.argsort(-born)[:2]]
    assert sorted(f.occ[g[1]]) == pytest.approx(sorted(heaviest), rel=1e-12)
    # the Poisson part's miss children stay, each w (1 - d)
    assert sorted(f.mass[g[-1]]) == pytest.approx(sorted(w * 0.2), rel=1e-12)


# -- merging ----------------------------------------------------------------------------------


def test_merge_is_moment_matching():
    """a and b (object 0) share a 10 px / 10 px/s cell; c (object 0) lies between them in the
    input and differs from a only in its horizontal centre cell; d sits on a but belongs to
    object 1; e1 and e2 are Poisson components in one cell with e3, in another, between them."""
    f = make(merge_position=10.0 / 128, merge_velocity=10.0 / 128)
    rng = np.random.default_rng(2)
    means = np.array([
        [[101.0, 1.0, 31.0], [402.0, -3.0, 62.0]],  # a
        [[150.0, 1.0, 31.0], [402.0, -3.0, 62.0]],  # c
        [[108.0, 8.0, 38.0], [407.0, -9.0, 68.0]],  # b
        [[101.0, 1.0, 31.0], [402.0, -3.0, 62.0]],  # d
        [[501.0, 2.0, 21.0], [301.0, 2.0, 51.0]],  # e1
        [[700.0, 2.0, 21.0], [301.0, 2.0, 51.0]],  # e3
        [[509.0, 7.0, 29.0], [308.0, 9.0, 59.0]],  # e2
    ])
    root = rng.normal(size=(7, 2, 3, 3))
    covs = root @ np.swapaxes(root, -1, -2) + np.eye(3)
    mass = np.array([0.3, 0.2, 0.15, 0.35, 0.05, 0.03, 0.02])
    det = np.array([0.9, 0.7, 0.5, 0.6, 0.2, 0.4, 0.8])
    occ = np.array([0.2, 0.4, 0.7, 0.5, 0.9, 0.3, 0.1])
    label = np.array([0, 0, 0, 1, -1, -1, -1])
    coast = np.array([0.0, 0.1, 0.0, 0.2, 0.0, 0.05, 0.0])
    out = f._merge(mass, means, covs, det, occ, coast, label)
    assert len(out[0]) == 5

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

    expected = [pooled([0, 2]), pooled([1]), pooled([3]), pooled([4, 6]), pooled([5])]
    for w, mu, sigma, d, o, t, lab in expected:
        (k,) = np.flatnonzero(np.isclose(out[0], w, rtol=1e-12, atol=0))
        assert out[1][k] == pytest.approx(mu, rel=1e-12)
        assert out[2][k] == pytest.approx(sigma, rel=1e-12)
        assert (out[3][k], out[4][k], out[5][k], out[6][k]) == (
            pytest.approx(d, rel=1e-12), pytest.approx(o, rel=1e-12),
            pytest.approx(t, rel=1e-12), lab)
    # the spread of the means is a large part of the merged covariance: dropping it shows
    ab = expected[0][2]
    without_spread = (mass[0] * covs[0] + mass[2] * covs[2]) / (mass[0] + mass[2])
    assert np.abs(ab - without_spread).max() > 5.0


def test_two_components_in_one_cell_merge():
    f = make(merge_position=10.0 / 128, merge_velocity=10.0 / 128)
    means = np.stack([person(101.0), person(104.0)])
    covs = np.broadcast_to(np.eye(3), (2, 2, 3, 3)).copy()
    out = f._merge(np.array([0.1, 0.3]), means, covs, np.array([0.2, 0.6]),
                   np.array([0.5, 0.1]), np.zeros(2), np.zeros(2, dtype=np.int64))
    assert out[0].tolist() == [pytest.approx(0.4)] and out[1][0, 0, 0] == pytest.approx(103.25)
    assert out[2][0, 0, 0, 0] == pytest.approx(1 + 0.25 * 2.25**2 + 0.75 * 0.75**2)
    assert (out[3][0], out[4][0]) == (pytest.approx(0.5), pytest.approx(0.2))


def test_merge_leaves_distinct_cells_alone():
    f = make(merge_position=10.0 / 128, merge_velocity=10.0 / 128)
    means = np.stack([person(100.0), person(115.0), person(100.0, vx=15.0)])
    covs = np.broadcast_to(np.eye(3), (3, 2, 3, 3)).copy()
    out = f._merge(np.array([0.1, 0.2, 0.3]), means, covs, np.full(3, 0.5), np.full(3, 0.5),
                   np.zeros(3), np.zeros(3, dtype=np.int64))
    assert sorted(out[0]) == [0.1, 0.2, 0.3]


# -- existence and labels ---------------------------------------------------------------------


def test_existence_is_capped_at_one_and_only_there():
    """Objects 0 and 3 (the first and last slot) reached r = 1.5 and 1.2 (by rounding, say):
    scaled to 1, their densities unchanged. Objects 1 and 2 and the Poisson part (an
    intensity, which may exceed 1) are left as they are."""
    f = make()
    load(f, [0.7, 0.5, 0.3, 0.2, 3.0, 0.6, 0.4, 1.5], [3, 3, 1, 1, -1, 2, 2, 0])
    f._cap_existence()
    r = f.existence()
    assert r[[0, 3]] == pytest.approx([1.0, 1.0], abs=1e-15) and (r <= 1.0).all()
    assert f.mass[[0, 1, 7]] == pytest.approx([0.7 / 1.2, 0.5 / 1.2, 1.0], rel=1e-15)
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


def test_a_recycled_slot_zero_frees_its_components_before_a_newborn_takes_it():
    """Slot 0's Bernoulli (r 0.2) is the weakest under max_labels = 2: its component goes to
    the Poisson part (label -1), and the newborn of measurement 0 (r 0.6) opens slot 0."""
    f = make(max_labels=2)
    f.slot_used[:] = True
    mass = np.array([0.2, 0.9, 0.6, 0.1])
    with pytest.warns(RuntimeWarning, match="max_labels = 2"):
        out = f._assign_labels(mass, np.array([0, 1, -1, -1]), np.array([-1, -1, 0, 1]), 2)
    assert out.tolist() == [-1, 1, 0, -1]
    assert f.slot_used.tolist() == [True, True] and f.slot_detection[0] == 0


def test_label_min_existence_is_inclusive_and_empty_objects_are_recycled():
    """r exactly at label_min_existence keeps (or gets) a label; a slot left with no component
    (all its children pruned) is freed."""
    f = make(max_labels=4, label_min_existence=0.25)
    f.slot_used[:] = [True, False, False, True]  # slot 3: no component left
    out = f._assign_labels(np.full(4, 0.125), np.array([0, 0, -1, -1]), np.array([-1, -1, 0, 0]),
                           1)
    assert out[:2].tolist() == [0, 0] and out[2] == out[3] > 0
    assert f.slot_used.sum() == 2 and f.slot_used[0] and f.slot_used[out[2]]


def _unplaced_by_hand(f, spread):
    """The slots `_recycle_unplaced` must free, from its definition: used, undetected at the
    last update, and a centre variance of the mixture, sum_k w_k (P_k[centre] + (mu_k -
    mean)^2) / r, above (spread sum_k w_k half_k / r)^2 on an axis."""
    n, L = f.n, len(f.slot_used)
    lost = []
    for i in range(L):
        mine = np.flatnonzero(f.label[:n] == i)
        if not f.slot_used[i] or not f.slot_coast[i] > 0 or len(mine) == 0:
            continue
        w = f.mass[mine] / f.mass[mine].sum()
        for a in range(2):
            centre = f.mean[mine, a, 0]
            var = (w * (f.cov[mine, a, 0, 0] + (centre - (w * centre).sum()) ** 2)).sum()
            if var > (spread * (w * f.mean[mine, a, 2]).sum()) ** 2 * (1 + 1e-12):
                lost.append(i)
                break
    return lost


@pytest.mark.parametrize("spread", [0.5, 1.0, 2.0])
def test_undetected_objects_that_lost_their_place_are_recycled(spread):
    """Four objects of half-size (20, 60): slot 0 detected at its last update, slots 1-3
    undetected, with centre standard deviations (30, 10) and (12, 10), and slot 3 two
    hypotheses 30 px apart, each (5, 5): its mixture's spread (15.8 px) is mostly the distance
    between them. The ones whose spread exceeds spread x half-size on an axis go to the Poisson
    part: label -1, slot free, mass unchanged; the others keep everything."""
    f = make(max_labels=4)
    means = np.stack([person(900.0), person(1000.0), person(1100.0), person(1185.0),
                      person(1215.0)])
    load(f, [0.9, 0.8, 0.7, 0.3, 0.3], [0, 1, 2, 3, 3], means=means)
    sd = np.array([[30.0, 10.0], [30.0, 10.0], [12.0, 10.0], [5.0, 5.0], [5.0, 5.0]])
    f.cov[:5, :, 0, 0] = sd ** 2
    f.slot_coast[:4] = [0.0, 0.5, 0.5, 2.0]
    expected = _unplaced_by_hand(f, spread)
    assert expected == {0.5: [1, 2, 3], 1.0: [1], 2.0: []}[spread]
    mass, label = f.mass[:5].copy(), f.label[:5].copy()
    f.config = f.config.replace(identity_spread=spread)
    f._recycle_unplaced()
    assert f.mass[:5].tolist() == mass.tolist()
    assert np.flatnonzero(~f.slot_used).tolist() == expected
    gone = np.isin(label, expected)
    assert (f.label[:5][gone] == -1).all() and (f.label[:5][~gone] == label[~gone]).all()


def test_identity_spread_inf_keeps_every_label_and_a_bad_value_is_refused():
    f = make(max_labels=4, identity_spread=float("inf"))
    load(f, [0.9], [0])
    f.cov[0, :, 0, 0] = 1e8
    f.slot_coast[0] = 10.0
    f._recycle_unplaced()
    assert f.slot_used[0] and f.label[0] == 0
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="identity_spread must be a positive number"):
            TrackerConfig(identity_spread=bad)


def test_a_measurement_without_a_new_bernoulli_gets_no_slot():
    f = make(max_labels=4, label_min_existence=0.0)
    out = f._assign_labels(np.array([0.2]), np.array([-1]), np.array([1]), 3)
    assert f.slot_used.sum() == 1 and f.slot_used[out[0]]  # measurements 0 and 2: nothing born


def test_every_new_bernoulli_gets_a_serial_never_used_before():
    """A slot freed and taken again holds a new object: the tracker tells them apart by the
    serial, so serials are never reused."""
    f = make(max_labels=4)
    serials = []
    for _ in range(3):
        # the last round's objects have no component left: two new ones take their slots
        out = f._assign_labels(np.array([0.5, 0.4]), np.array([-1, -1]), np.array([0, 1]), 2)
        slots = sorted(set(out.tolist()))
        assert len(slots) == 2 and f.slot_used.sum() == 2
        serials += f.slot_serial[slots].tolist()
    assert len(set(serials)) == 6 and min(serials) >= 0


def test_sort_by_label_puts_the_poisson_part_first_and_keeps_order_within_a_label():
    f = make(capacity=64)
    label = np.random.default_rng(3).integers(-1, 3, size=40)
    load(f, np.arange(1.0, 41.0), label)
    f._sort_by_label()
    assert np.array_equal(f.label[:40], np.sort(label))
    for k in (-1, 0, 1, 2):  # stable: within a label, the original order
        assert np.array_equal(f.mass[:40][f.label[:40] == k], np.flatnonzero(label == k) + 1.0)
    load(f, [1.0, 2.0, 3.0], [1, 2, -1])  # every component out of place
    f._sort_by_label()
    assert f.label[:3].tolist() == [-1, 1, 2] and f.mass[:3].tolist() == [3.0, 1.0, 2.0]
    assert f.mean[:3, 0, 0].tolist() == [980.0, 900.0, 940.0]


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


def test_n_of_m_confirmation_deletes_exactly_the_bernoullis_that_cannot_make_it():
    """confirm_hits 3 of confirm_window 5: a Bernoulli is deleted once its hits plus the
    frames left in its window fall below 3; its components go (no recycling), the Poisson
    part and the other objects stay, and slots not in use are not touched."""
    f = make(max_labels=8)
    f.slot_used[:] = [True, True, True, True, True, False, True, True]
    # slot:               0  1  2  3  4  5  6   7
    f.slot_age[:] = [2, 4, 5, 5, 4, 9, 30, 1]
    f.slot_hits[:] = [1, 1, 2, 3, 2, 0, 3, 0]
    # hits + frames left: 4, 2, 2, 3, 3, -, 3, 4: slots 1 and 2 are doomed (3 is enough)
    label = np.array([-1, 0, 1, 1, 2, 3, 4, 6, 7, -1])
    keep = f._confirm_or_delete(label)
    assert keep.tolist() == [True, True, False, False, False, True, True, True, True, True]
    assert f.slot_used.tolist() == [True, False, False, True, True, False, True, True]
    f.slot_age[:] = 5  # nothing left to delete: every component kept, no slot changed
    f.slot_hits[:] = 3
    assert f._confirm_or_delete(label).tolist() == [True] * 10
    assert f.slot_used.tolist() == [True, False, False, True, True, False, True, True]


def test_an_unconfirmed_bernoulli_missed_out_of_its_window_is_deleted_with_its_mass():
    """No detections. Object 1 was detected twice in its first four frames: missed in the
    fifth, it can no longer reach 3 hits of 5 and goes, mass and all (the Poisson part does
    not receive it); object 0 is confirmed and stays."""
    f = make()
    load(f, [0.8, 0.6, 0.5], [0, 1, -1], det=0.5)
    f.slot_age[1], f.slot_hits[1] = 4, 2
    f._update(*EMPTY)
    g = groups(f)
    assert f.slot_used.tolist() == [True, False, False, False] and sorted(g) == [-1, 0]
    assert f.mass[g[-1]].sum() == pytest.approx(0.5 * 0.5, rel=1e-12)
    assert f.existence()[0] == pytest.approx(0.4 / 0.6, rel=1e-12)
    assert f.slot_age[0] == f.config.confirm_window + 1 and f.slot_hits[0] == 3


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


def one_hit(f, v, q, h, kappa, score=1.0):
    """Expected children of one object (r 0.8, d 0.7, o 0.6, the only component) hit by one
    detection near it. The association is exact for one object and one detection:
    p_hit = L / (L + miss_obj kappa'), L = r P(seen) p(z | x), kappa' the clutter density of
    the detection's score, times (1 - o_stationary h). Returns the detection and, for the hit
    and the miss child, (mass, d, o)."""
    z = edges(person(905.0, 396.0))
    lik = np.exp(f.measurement.loglik(f.mean[:1], f.cov[:1], z,
                                      f.measurement.observed(z)))[0, 0]
    d_miss, o_miss, miss = features_after(0.7, 0.6, miss_likelihood(v, q))
    d_hit, o_hit, seen = features_after(0.7, 0.6, hit_likelihood(v, h))
    big_l = 0.8 * seen * lik
    miss_obj = 1 - 0.8 + 0.8 * miss
    clutter = kappa * min(max(score, 0.05), 1.0) ** -2 * (1 - f.config.occludability * h)
    p_hit = big_l / (big_l + miss_obj * clutter)
    assert 0.2 < p_hit < 0.98  # both children matter
    return z, (p_hit, d_hit, o_hit), (0.8 * miss * (1 - p_hit) / miss_obj, d_miss, o_miss)


@pytest.mark.parametrize("score", [1.0, 0.5, 0.01, 1.5])
def test_features_after_a_hit_equal_bayes(score):
    """v = 0.6, q = 0.3, h = 0.25. The hit child has D = 1 and O by Bayes with the hit
    likelihood; the miss child has both by Bayes with the miss likelihood. The clutter density
    of a detection is kappa / clip(score, 0.05, 1)^2 (kappa chosen so that it is the same)."""
    v, q, h = 0.6, 0.3, 0.25
    kappa = 1e-7 * min(max(score, 0.05), 1.0) ** 2
    f = make(FixedTerms(v, q, h), clutter_rate=clutter_rate(kappa))
    load(f, [0.8], [0], det=0.7, occ=0.6)
    z, hit_child, miss_child = one_hit(f, v, q, h, kappa, score)
    f._update(z, f.measurement.observed(z), np.array([score]))

    assert f.n == 2 and (f.label[:2] == 0).all()
    hit, missed = (0, 1) if f.det[0] == 1.0 else (1, 0)
    assert f.det[hit] == 1.0 and hit_child[1] == 1.0
    assert f.occ[hit] == pytest.approx(hit_child[2], rel=1e-12)
    assert f.mass[hit] == pytest.approx(hit_child[0], rel=1e-9)
    assert (f.det[missed], f.occ[missed]) == (pytest.approx(miss_child[1], rel=1e-12),
                                              pytest.approx(miss_child[2], rel=1e-12))
    assert f.mass[missed] == pytest.approx(miss_child[0], rel=1e-9)
    assert hit_child[2] < 0.6 < miss_child[2]
    assert f.iterations >= 1


def test_hit_and_miss_children_in_one_cell_merge_with_averaged_features():
    """The same step with cells 1000 px (px/s) wide: the two children become one component
    with their total mass and their mass-weighted d and o."""
    v, q, h = 0.6, 0.3, 0.25
    f = make(FixedTerms(v, q, h), clutter_rate=clutter_rate(1e-7), merge_position=1000.0 / 128,
             merge_velocity=1000.0 / 128)
    load(f, [0.8], [0], np.stack([person(900.0, 400.0, vx=500.0, vy=500.0)]), det=0.7, occ=0.6)
    z, hit_child, miss_child = one_hit(f, v, q, h, 1e-7)
    f._update(z, f.measurement.observed(z), np.ones(1))
    (w1, d1, o1), (w2, d2, o2) = hit_child, miss_child
    assert f.n == 1 and f.mass[0] == pytest.approx(w1 + w2, rel=1e-9)
    assert f.det[0] == pytest.approx((w1 * d1 + w2 * d2) / (w1 + w2), rel=1e-9)
    assert f.occ[0] == pytest.approx((w1 * o1 + w2 * o2) / (w1 + w2), rel=1e-9)


@pytest.mark.parametrize("raw,clipped", [((-0.3, 0.2, 0.1), (0.0, 0.2, 0.1)),
                                         ((0.5, -0.4, -0.2), (0.5, 0.0, 0.0)),
                                         ((1.7, 1.6, 1.3), (1.0, 1.0, 1.0))])
def test_occlusion_terms_outside_zero_one_are_clipped(raw, clipped):
    """A model's v, q and h are probabilities: values outside [0, 1] act as the nearest end."""
    results = []
    for terms in (raw, clipped):
        f = make(FixedTerms(*terms), clutter_rate=clutter_rate(1e-7))
        load(f, [0.8, 0.3], [0, -1], np.stack([person(), person(930.0)]), det=0.7, occ=0.6)
        z = edges(person(905.0, 396.0))
        f._update(z, f.measurement.observed(z), np.ones(1))
        n = f.n
        results.append([f.mass[:n].copy(), f.det[:n].copy(), f.occ[:n].copy(), f.label[:n]])
    for a, b in zip(*results, strict=True):
        assert np.array_equal(a, b)


class Recorder(FixedTerms):
    """Keeps a copy of what the filter shows the occlusion model."""

    def terms(self, ctx):
        self.weights, self.owner = np.array(ctx.weights), np.array(ctx.owner)
        self.existence, self.covs = np.array(ctx.existence), ctx.covs
        self.means, self.n_measurements = np.array(ctx.means), len(ctx.measurements)
        return super().terms(ctx)


def test_the_occlusion_model_sees_each_components_weight_within_its_object():
    """OcclusionContext: weight w_k / r_i for a component of object i and w_k for the Poisson
    part, existence r of every slot, owner the labels, and the components' states."""
    model = Recorder(1.0, 0.0)
    f = make(model)
    load(f, [0.3, 0.7, 0.1, 0.5, 0.2], [0, -1, 0, 2, -1])
    states = f.mean[:5].copy()
    f._update(*EMPTY)
    for k, weights in {0: [0.75, 0.25], 2: [1.0], -1: [0.7, 0.2]}.items():
        mine = model.owner == k
        assert sorted(model.weights[mine]) == pytest.approx(sorted(weights), rel=1e-12)
    assert model.existence == pytest.approx([0.4, 0.0, 0.5, 0.0], rel=1e-12)
    assert sorted(model.means[:, 0, 0]) == sorted(states[:, 0, 0])
    assert model.covs is not None and model.covs.shape == (5, 2, 3, 3)
    assert model.n_measurements == 0


# -- prediction, births, the size prior -------------------------------------------------------


def test_survival_depends_on_the_centre_being_in_the_image():
    """P_S = exp(-death_rate dt) while the box centre is in the image (its edges included) and
    both half-sizes are at least 1 px, else exit_survival."""
    f = make()
    W, H = f.config.image_size
    states = [person(900.0), person(0.0), person(W), person(900.0, 0.0), person(900.0, H),
              person(900.0, half=(1.0, 1.0)),
              person(-0.5), person(W + 0.5), person(900.0, -0.5), person(900.0, H + 0.5),
              person(900.0, half=(0.99, 60.0)), person(900.0, half=(20.0, 0.99))]
    inside = np.arange(len(states)) < 6
    load(f, np.full(len(states), 0.5), np.full(len(states), -1), np.stack(states))
    f._predict()
    survival = np.exp(-f.config.death_rate * f.config.dt)
    expected = 0.5 * np.where(inside, survival, f.config.exit_survival)
    assert f.mass[:f.n] == pytest.approx(expected, rel=1e-15)


def test_births_join_the_poisson_part_at_the_edges_and_everywhere():
    """Four edge components (mass edge rate x dt, centred on the edge, moving inward) and one
    spread over the image (spread rate x dt, plus the initial objects at the first step).
    Speeds are in box heights of the size prior (120 px here): 0.375 h/s is 45 px/s."""
    f = make(edge_birth_rate=6.0, spread_birth_rate=3.0, initial_objects=50.0,
             inward_speed=0.375, birth_speed_std=0.75, birth_half_size=(20.0, 60.0),
             birth_half_size_std=(4.0, 9.0), birth_detectability=0.85, birth_occludability=0.4)
    dt = f.config.dt
    W, H = f.config.image_size
    f._add_births()
    assert f.n == 5 and (f.label[:5] == -1).all()
    assert f.mass[:5] == pytest.approx([6 * dt] * 4 + [3 * dt + 50.0], rel=1e-15)
    assert (f.det[:5] == 0.85).all() and (f.occ[:5] == 0.4).all()
    assert (f.coast[:5] == 0.0).all()  # not coasting: predicted with the configured motion
    half = [20.0, 60.0]
    expected = np.array([[[0, 45, 20], [H / 2, 0, 60]], [[W, -45, 20], [H / 2, 0, 60]],
                         [[W / 2, 0, 20], [0, 45, 60]], [[W / 2, 0, 20], [H, -45, 60]],
                         [[W / 2, 0, 20], [H / 2, 0, 60]]])
    assert np.array_equal(f.mean[:5], expected)
    sd = np.array([[[half[0], 90, 4], [H / 2, 90, 9]], [[half[0], 90, 4], [H / 2, 90, 9]],
                   [[W / 2, 90, 4], [half[1], 90, 9]], [[W / 2, 90, 4], [half[1], 90, 9]],
                   [[W / 2, 90, 4], [H / 2, 90, 9]]])
    assert np.array_equal(f.cov[:5], sd[..., None] ** 2 * np.eye(3))

    f.steps, f.n = 1, 0  # later steps: no initial objects
    f._add_births()
    assert f.mass[4] == pytest.approx(3 * dt, rel=1e-15)
    g = make(spread_birth_rate=0.0)
    g.steps = 1
    g._add_births()
    assert g.n == 4  # a component of mass 0 is not added
    masses = g.births.components(1, 2, np.array([20.0, 60.0]), np.array([4.0, 9.0]))[0]
    assert masses.dtype == float


def test_births_into_a_full_growing_pool_make_it_grow():
    """capacity = 0 and every entry of the pool in use: the five births are appended after
    the components held, which stay as they were."""
    f = make(capacity=0)
    n = len(f.mass)
    load(f, np.full(n, 0.01), np.full(n, -1))
    before = f.mean[:n].copy()
    f._add_births()
    assert f.n == n + 5 and len(f.mass) == len(f.label) == 2 * n
    assert np.array_equal(f.mean[:n], before) and (f.mass[:n] == 0.01).all()
    assert (f.label[:n + 5] == -1).all() and (f.mass[n:n + 5] > 0).all()


def test_birth_size_prior_from_settings_defaults_and_detections():
    mean, std = make()._size_prior()  # nothing seen: 30 x 90 px half-sizes, std a third
    assert mean.tolist() == [30.0, 90.0] and std.tolist() == [10.0, 30.0]
    mean, std = make(birth_half_size=(12.0, 34.0), birth_half_size_std=(1.5, 0.5))._size_prior()
    assert mean.tolist() == [12.0, 34.0] and std.tolist() == [1.5, 1.0]  # at least 1 px
    mean, std = make(birth_half_size=(12, 34), birth_half_size_std=(2, 1))._size_prior()
    assert mean.dtype == std.dtype == float and mean.tolist() == [12.0, 34.0]  # whole numbers

    f = make()
    first = edges_from_ltwh([[100.0, 100.0, 20.0, 60.0]])  # half-sizes 10 x 30
    # 14 x 40, and one on the image border, whose size is not seen
    second = edges_from_ltwh([[300.0, 100.0, 28.0, 80.0], [0.0, 50.0, 40.0, 40.0]])
    f._learn_sizes(first, f.measurement.observed(first))
    assert f._size_prior()[0].tolist() == [30.0, 90.0]  # one detection is not enough
    f._learn_sizes(second, f.measurement.observed(second))
    mean, std = f._size_prior()
    # mean (10 + 14) / 2, (30 + 40) / 2; std sqrt(mean of squares - square of mean)
    assert mean == pytest.approx([12.0, 35.0]) and std == pytest.approx([2.0, 5.0])
    g = make()
    for _ in range(2):  # two boxes of one size: no spread, so the 1 px floor of the variance
        g._learn_sizes(first, g.measurement.observed(first))
    assert g._size_prior()[1].tolist() == [1.0, 1.0]


@pytest.mark.filterwarnings("ignore:capacity = 16")
def test_a_new_filter_is_empty_and_counts_its_steps():
    f = make(border_margin=5.0)
    assert (f.n, f.steps, f.iterations) == (0, 0, 0) and not f.slot_used.any()
    assert f.measurement.border_margin == 5.0
    z = edges(person(905.0))
    for _ in range(2):
        f.step(z, np.ones(1))
    assert f.steps == 2 and f.iterations >= 1


# -- the step's wiring: time step, classes, coasting, gating, loopy BP's settings -------------


def test_step_takes_its_dt_and_a_filter_stepped_with_dt_equals_one_configured_with_it():
    z = edges(person(905.0))
    stepped, configured = make(capacity=0), make(capacity=0, fps=4.0)
    for _ in range(3):
        stepped.step(z, np.ones(1), dt=0.25)
        configured.step(z, np.ones(1))
    assert stepped.dt == 0.25 and stepped.n == configured.n
    for name in ("mass", "mean", "cov", "det", "occ", "coast", "label"):
        assert np.array_equal(getattr(stepped, name)[:stepped.n],
                              getattr(configured, name)[:configured.n])


@pytest.mark.parametrize("detection_class,taken", [(2, True), (1, False)])
def test_an_object_takes_only_a_detection_of_its_own_class(detection_class, taken):
    """An object of class 2 next to a detection: of class 2 it is hit (a hit child with d = 1
    and most of the mass); of class 1 the pair is impossible, so the object fares exactly as
    in a frame without detections, and the detection starts a Bernoulli of class 1."""
    def stepped(z, classes):
        f = make(clutter_rate=clutter_rate(1e-7))
        load(f, [0.8], [0], det=0.9)
        f.slot_class[0] = 2
        f.step(z, np.ones(len(z)), classes=classes)
        return f

    f = stepped(edges(person(905.0, 396.0)), np.array([detection_class]))
    mine = f.label[:f.n] == 0
    assert (f.det[:f.n][mine] == 1.0).any() == taken
    alone = stepped(np.zeros((0, 2, 2)), np.zeros(0, dtype=np.int64))
    if taken:
        assert f.existence()[0] > 0.9 > alone.existence()[0]
    else:
        assert f.existence()[0] == alone.existence()[0]
        assert f.slot_used[1] and f.slot_class[1] == 1
    assert f.slot_class.dtype == np.int64  # class ids stay integers


def test_components_coast_once_more_than_half_their_mass_was_missed():
    """The coasting model (velocity relaxing with coast_velocity_time) predicts a component
    whose coasting time exceeds half a step; the others keep the configured motion (constant
    velocity): a merged component's coasting time is its children's mass-weighted mean."""
    f = make()
    dt = f.config.dt
    coast = np.array([0.0, 0.5 * dt, 0.6 * dt, dt, 3 * dt])
    states = np.stack([person(900.0 + 40 * k, vx=30.0, vy=-12.0) for k in range(5)])
    load(f, np.full(5, 0.5), np.full(5, -1), states)
    f.coast[:5] = coast
    f._predict()
    for k in range(5):
        F = f.coast_motion.F if coast[k] > 0.5 * dt else f.motion.F
        assert np.allclose(f.mean[k], states[k] @ F.T, rtol=1e-14, atol=0)
    assert f.mean[0, 0, 1] == 30.0 and f.mean[2, 0, 1] < 30.0 * 0.8


def test_objects_not_confirmed_and_the_poisson_part_are_not_occludable():
    """Occlusion explains the misses of confirmed objects only: a Bernoulli short of
    confirm_hits and the Poisson part miss with 1 - d whatever v and q, and their o is carried
    unchanged; a missed detectable source that cannot be occluded was undetectable (d' = 0)."""
    f = make(FixedTerms(0.6, 0.3))
    load(f, [0.8, 0.5], [0, -1], det=0.9, occ=0.5)
    f.slot_hits[0], f.slot_age[0] = 1, 1
    f._update(*EMPTY)
    g = groups(f)
    assert f.existence()[0] == pytest.approx(0.08 / 0.28, rel=1e-12)
    assert f.mass[g[-1]].tolist() == [pytest.approx(0.05, rel=1e-12)]
    assert f.det[:2].tolist() == [0.0, 0.0] and f.occ[:2].tolist() == [0.5, 0.5]
    assert f.slot_hidden[0] == 0.0


def test_slot_hidden_is_the_probability_that_the_miss_was_occlusions_doing():
    """P(occluded | miss) = d o (1 - v + v q) / miss, miss = 1 - d (1 - o + o v) + d o v q,
    mass-weighted over an object's components; 0 for every other slot, whatever it held."""
    d, o, v, q = 0.7, 0.6, 0.6, 0.3
    f = make(FixedTerms(v, q))
    load(f, [0.5, 0.3, 0.4], [0, 0, 2], det=d, occ=o)
    f.det[1], f.occ[1] = 0.4, 0.9
    f.slot_hidden[:] = 0.7
    f._update(*EMPTY)

    def hidden_and_miss(d, o):
        return d * o * (1 - v + v * q), 1 - d * (1 - o + o * v) + d * o * v * q

    (h0, m0), (h1, m1) = hidden_and_miss(d, o), hidden_and_miss(0.4, 0.9)
    expected = [(0.5 * h0 + 0.3 * h1) / (0.5 * m0 + 0.3 * m1), 0.0, h0 / m0, 0.0]
    assert f.slot_hidden.tolist() == pytest.approx(expected, rel=1e-12)
    assert f.slot_hidden[1] == 0.0 and f.slot_hidden[3] == 0.0


def test_a_new_bernoullis_existence_weighs_the_poisson_part_against_clutter_per_area():
    """One Poisson component at one detection, no objects: the new Bernoulli's existence is
    L_0 / (L_0 + kappa p_F), L_0 = w d p(z | x), with p_F uniform over the image and over box
    areas, clutter_rate / (W H max(area, 1 px^2)): a box smaller than a pixel counts as one
    pixel. clutter_rate is chosen so that the existence is exactly 1/2."""
    for half in ((0.25, 0.5), (0.5, 0.5), (20.0, 60.0)):
        state = person(900.0, 400.0, half=half)
        z = edges(state)
        area = max(4 * half[0] * half[1], 1.0)
        probe = make()
        load(probe, [0.5], [-1], np.stack([state]), det=0.9)
        lik = np.exp(probe.measurement.loglik(probe.mean[:1], probe.cov[:1], z,
                                              probe.measurement.observed(z)))[0, 0]
        L0 = 0.5 * 0.9 * lik
        f = make(clutter_rate=L0 * 1920.0 * 1080.0 * area)
        load(f, [0.5], [-1], np.stack([state]), det=0.9)
        f.slot_coast[:], f.slot_class[:], f.slot_hidden[:] = 0.7, 5, 0.3  # a slot used before
        f._update(z, f.measurement.observed(z), np.ones(1))
        assert f.slot_used.tolist() == [True, False, False, False]
        assert f.existence()[0] == pytest.approx(0.5, rel=1e-12)
        # the new Bernoulli's slot starts afresh: one frame, one hit (this detection), not
        # coasting, class 0 (no classes given), a serial never used before
        assert (f.slot_age[0], f.slot_hits[0], f.slot_detection[0]) == (1, 1, 0)
        assert (f.slot_coast[0], f.slot_class[0], f.slot_hidden[0]) == (0.0, 0, 0.0)
        assert f.slot_serial[0] == 0 and f._next_serial == 1


def association_edge(gating: bool, ratio: float) -> float:
    """One confirmed object (r 0.8, d 0.9) and one detection 60 px off, with clutter such
    that L = ratio miss kappa. Returns the object's existence after the update."""
    probe = make()
    load(probe, [0.8], [0], det=0.9)
    z = edges(person(960.0, 400.0))
    lik = np.exp(probe.measurement.loglik(probe.mean[:1], probe.cov[:1], z,
                                          probe.measurement.observed(z)))[0, 0]
    big_l, miss_obj = 0.8 * 0.9 * lik, 1 - 0.8 * 0.9
    assert np.exp(-300) < big_l < 1e-12
    kappa = big_l / (ratio * miss_obj)
    f = make(gating=gating, clutter_rate=kappa * 1920.0 * 1080.0 * 40.0 * 120.0)
    load(f, [0.8], [0], det=0.9)
    f._update(z, f.measurement.observed(z), np.ones(1))
    return f.existence()[0]


@pytest.mark.parametrize("gating,ratio,kept", [(True, 0.5e-9, False), (True, 2e-9, True),
                                               (False, 0.5e-9, True), (False, 1e-12, True)])
def test_association_edges_below_the_floor_are_left_out_only_under_gating(gating, ratio, kept):
    """An edge with L_ij < EDGE_FLOOR miss_i w_new_j (1e-9) cannot reach p_hit = 1e-9: under
    gating it is left out and the object is simply missed, r' = r (1 - d) / miss_obj; kept, the
    exact one-edge association gives p_hit = ratio / (1 + ratio) and r' = that times
    (1 - p_hit) (its hit child is below prune_mass)."""
    got = association_edge(gating, ratio)
    pure_miss = 0.8 * 0.1 / (1 - 0.8 * 0.9)
    p_hit = ratio / (1 + ratio) if kept else 0.0
    assert got == pytest.approx(pure_miss * (1 - p_hit), rel=1e-13, abs=0)
    assert (abs(got / pure_miss - 1) > 1e-13) == kept


def two_by_two(**settings) -> GaussianMixturePMB:
    """Two confirmed objects and two detections between them: a loop in the association
    graph, so loopy BP takes several iterations."""
    f = make(clutter_rate=clutter_rate(1e-9), **settings)
    load(f, [0.9, 0.9], [0, 1], np.stack([person(900.0), person(930.0)]), det=0.9)
    z = np.concatenate([edges(person(910.0)), edges(person(920.0))])
    f._update(z, f.measurement.observed(z), np.ones(2))
    return f


def test_loopy_bp_stops_at_the_configured_tolerance_and_iteration_limit():
    default = two_by_two().iterations
    assert default > 3
    assert two_by_two(lbp_max_iterations=3).iterations == 3
    assert two_by_two(lbp_tolerance=1e-2).iterations < default
    assert two_by_two(lbp_tolerance=1e-12).iterations > default


def test_gated_pairs_are_those_whose_boxes_overlap_their_objects_gate():
    """Above DENSE_PAIRS pairs, a component and a detection pair up when the detection's box
    overlaps the gate of the component's object (the union of its components' gates) or, for
    the Poisson part, the component's own gate; an axis with both edges on the border has no
    extent. Checked against every pair by brute force, with their log-likelihoods."""
    rng = np.random.default_rng(7)
    f = make(capacity=256)
    labels = np.sort(np.concatenate([np.full(40, -1), rng.integers(0, 4, 40)]))
    n, M = len(labels), 60
    means = np.stack([person(*rng.uniform([-300, -200], [2220, 1280]), half=rng.uniform(5, 60, 2))
                      for _ in range(n)])  # some outside the image
    load(f, np.full(n, 0.1), labels, means)
    f.cov[:n] *= rng.uniform(0.2, 5.0, n)[:, None, None, None]
    centre, half = rng.uniform([0, 0], [1920, 1080], (M, 2)), rng.uniform(5, 80, (M, 2))
    z = np.clip(np.stack([centre - half, centre + half], axis=-1), 0, [[1920], [1080]])
    z[0, 0] = [0.0, 1920.0]  # a box as wide as the image: its horizontal axis unmeasured
    observed = f.measurement.observed(z)
    assert n * M > 4096 and not observed[0, 0].any()
    outside = (means[:, 0, 0] < -100) | (means[:, 0, 0] > 2020)
    slots = np.flatnonzero(f.slot_used)
    A = len(slots)
    row_of_slot = np.full(len(f.slot_used), A)
    row_of_slot[slots] = np.arange(A)
    rows = np.where(labels >= 0, row_of_slot[np.maximum(labels, 0)], A)
    mean, cov = f.mean[:n], f.cov[:n]
    pk, pj, loglik, (cand_row, cand_col, cand_of_pair) = f._pairs(mean, cov, z, observed,
                                                                  rows, A)
    zhat, S = f.measurement.innovation(mean, cov)
    gate = f.measurement.gates(zhat, S, f.config.gate_sigmas)
    unit = gate.copy()
    for row in range(A):
        mine = rows == row
        unit[mine, :, 0] = gate[mine, :, 0].min(axis=0)
        unit[mine, :, 1] = gate[mine, :, 1].max(axis=0)
    box = z.copy()
    box[~observed.any(axis=2)] = [-np.inf, np.inf]
    overlap = ((unit[:, None, :, 0] < box[None, :, :, 1])
               & (box[None, :, :, 0] < unit[:, None, :, 1])).all(axis=2)
    expected = set(zip(*np.nonzero(overlap), strict=True))
    assert set(zip(pk.tolist(), pj.tolist(), strict=True)) == expected and len(pk) == len(
        expected)
    assert 0 < len(expected) < n * M
    assert any(outside[k] and j == 0 for k, j in expected)  # reached by the full-width box
    full = f.measurement.loglik(mean, cov, z, observed)
    np.testing.assert_allclose(loglik, full[pk, pj], rtol=1e-10)
    assert np.array_equal(cand_row[cand_of_pair], rows[pk])
    assert np.array_equal(cand_col[cand_of_pair], pj)
    objects = cand_row < A  # one candidate per (object, detection); per component for Poisson
    assert len(set(zip(cand_row[objects].tolist(), cand_col[objects].tolist(),
                       strict=True))) == objects.sum()


def test_at_most_dense_pairs_every_pair_is_listed_and_above_only_gated_ones():
    f = make(capacity=0)
    for n, dense in ((64, True), (65, False)):
        f._reserve(n)
        load(f, np.full(n, 0.1), np.full(n, -1))
        z = np.concatenate([edges(person(100.0 + 25 * j, 300.0)) for j in range(64)])
        observed = f.measurement.observed(z)
        # (rows all 0 with A = 0: every component is the Poisson part's)
        pk, pj, _, cand = f._pairs(f.mean[:n], f.cov[:n], z, observed, np.zeros(n, int), 0)
        assert (len(pk) == n * 64) == dense
        if dense:  # component-major, and no object row: no candidate edge
            assert np.array_equal(pk, np.repeat(np.arange(n), 64))
            assert np.array_equal(pj, np.tile(np.arange(64), n))
            assert len(cand[0]) == len(cand[1]) == 0


def test_each_poisson_component_is_gated_on_its_own():
    """Above DENSE_PAIRS pairs, a detection's Poisson term L_0 sums only the components whose
    own gate (3 edge standard deviations here) it overlaps: the new Bernoulli's existence is
    the sum of its hit children l_k / (L_0 + kappa) above prune_mass, with that L_0, worked out
    here from the per-pair likelihoods."""
    rng = np.random.default_rng(11)
    n = 4200
    f = make(capacity=0, gate_sigmas=3.0, clutter_rate=clutter_rate(1e-9))
    f._reserve(n)
    means = np.stack([person(*rng.uniform([705, 196], [1105, 596])) for _ in range(n)])
    load(f, np.full(n, 0.01), np.full(n, -1), means, det=0.9, cov_diag=(900.0, 100.0, 400.0))
    z = edges(person(905.0, 396.0))
    observed = f.measurement.observed(z)
    zhat, S = f.measurement.innovation(f.mean[:n], f.cov[:n])
    gate = f.measurement.gates(zhat, S, 3.0)
    inside = ((gate[:, :, 0] < z[0, :, 1]) & (z[0, :, 0] < gate[:, :, 1])).all(axis=1)
    lik = np.exp(f.measurement.loglik(f.mean[:n], f.cov[:n], z, observed)[:, 0])
    L0 = (0.01 * 0.9 * lik[inside]).sum()
    assert 0 < inside.sum() < n and (0.01 * 0.9 * lik[~inside]).sum() > 1e-9 * L0
    f._update(z, observed, np.ones(1))
    child = 0.01 * 0.9 * lik[inside] / (L0 + 1e-9)  # the hit children, pruned below 1e-5
    assert f.existence()[0] == pytest.approx(child[child > 1e-5].sum(), rel=1e-12)
    assert child[child > 1e-5].sum() > 0.9


def test_children_are_pooled_per_parent_miss_child_first_then_hits_by_detection():
    """Without merging, an object's children follow its components' order: per parent the
    miss child (the parent's state), then its hit children in the order of the detections
    (each pulled towards its detection)."""
    f = make(clutter_rate=clutter_rate(1e-7))
    load(f, [0.4, 0.4], [0, 0], np.stack([person(900.0), person(1000.0)]), det=0.9)
    z = np.concatenate([edges(person(x)) for x in (1003.0, 903.0, 998.0, 897.0)])
    f._update(z, f.measurement.observed(z), np.ones(4))
    assert f.n == 6 and (f.label[:6] == 0).all()
    shift = f.mean[:6, 0, 0] - np.repeat([900.0, 1000.0], 3)
    assert np.sign(shift).tolist() == [0, 1, -1, 0, 1, -1]
    assert (f.det[[0, 3]] < 1).all() and (f.det[[1, 2, 4, 5]] == 1).all()


def test_an_update_that_outgrows_the_pool_keeps_every_child():
    """A growing pool (capacity 0) that receives more children than it holds doubles and
    ends with exactly what a pool large enough from the start holds."""
    results = []
    for capacity in (0, 4096):
        f = make(capacity=capacity, clutter_rate=clutter_rate(1e-12))
        n = 250
        means = np.stack([person(880.0 + 0.2 * k, 400.0) for k in range(n)])
        load(f, np.full(n, 0.005), np.full(n, -1), means, det=0.9)
        z = np.concatenate([edges(person(x)) for x in (890.0, 905.0, 915.0)])
        f._update(z, f.measurement.observed(z), np.ones(3))
        results.append((f.n, [getattr(f, a)[:f.n].copy() for a in f._POOL]))
    assert results[0][0] == results[1][0] > INITIAL_POOL
    for a, b in zip(results[0][1], results[1][1], strict=True):
        assert np.array_equal(a, b)


def test_per_slot_bookkeeping_of_hits_misses_and_coasting_time():
    """After an update a used slot holds the detection it took (p_hit > 1/2) or -1, one more
    tracked frame, one more hit if it took one, and its coasting time: 0 after a hit, one dt
    more after a miss. A detection it only may have taken (p_hit <= 1/2) is not counted;
    unused slots keep their counts and coasting time (their detection is -1)."""
    f = make(clutter_rate=clutter_rate(1e-7))
    load(f, [0.8, 0.8, 0.8], [0, 1, 3], np.stack([person(900.0), person(1300.0),
                                                  person(500.0)]), det=0.9)
    f.slot_coast[:] = [0.2, 0.3, 0.4, 0.5]
    f.slot_detection[:] = [5, 5, 5, 5]
    f.slot_age[2], f.slot_hits[2] = 7, 7
    z = np.concatenate([edges(person(1302.0)), edges(person(525.0))])  # slot 3: p_hit 0.27
    f._update(z, f.measurement.observed(z), np.ones(2))
    hits, age = f.config.confirm_hits, f.config.confirm_window
    assert f.slot_detection.tolist() == [-1, 0, -1, -1]
    assert f.slot_hits.tolist() == [hits, hits + 1, 7, hits]
    assert f.slot_age.tolist() == [age + 1, age + 1, 7, age + 1]
    assert f.slot_coast.tolist() == pytest.approx([0.2 + f.dt, 0.0, 0.4, 0.5 + f.dt], rel=1e-15)
    assert 0 < f.existence()[3] and np.isin(f.label[:f.n], [0, 1, 3]).any()


def test_confirmed_slots_are_used_ones_with_confirm_hits_or_more():
    f = make(confirm_hits=3)
    f.slot_used[:] = [True, True, True, False]
    f.slot_hits[:] = [3, 2, 4, 9]
    assert f.confirmed().tolist() == [True, False, True, False]


def test_a_doomed_bernoulli_in_slot_zero_goes_with_all_its_components():
    f = make()
    load(f, [0.5, 0.3, 0.5], [0, 0, 1], det=0.5)
    f.slot_age[0], f.slot_hits[0] = 4, 1  # 1 hit of 4 frames: 3 of 5 is out of reach
    f._update(*EMPTY)
    assert f.slot_used.tolist() == [False, True, False, False]
    assert set(f.label[:f.n].tolist()) == {1}


def test_ties_in_existence_keep_the_older_bernoulli_then_the_earlier_measurement():
    """Under a hard max_labels, equal existences rank in a fixed order: existing Bernoullis
    by slot, then new ones by measurement."""
    rng = np.random.default_rng(12)
    L, M = 24, 16
    f = make(max_labels=L)
    f.slot_used[:] = True
    r_old, r_new = rng.choice([0.5, 0.3, 0.2], L), rng.choice([0.5, 0.3, 0.2], M)
    mass = np.concatenate([r_old, r_new])
    label = np.concatenate([np.arange(L), np.full(M, -1)])
    newborn = np.concatenate([np.full(L, -1), np.arange(M)])
    with pytest.warns(RuntimeWarning, match="max_labels = 24"):
        out = f._assign_labels(mass, label, newborn, M)
    r_all = np.concatenate([r_old, r_new])
    ranked = sorted(range(L + M), key=lambda i: (-r_all[i], i))[:L]
    kept = np.zeros(L + M, dtype=bool)
    kept[ranked] = True
    assert ((out >= 0) == kept).all() and 0 < kept[L:].sum() < M and f.slot_used.all()


def test_the_labels_warning_names_the_step_and_counts_exactly():
    """The report of recycled labels: the step it happened at (steps taken + 1), how many
    Bernoullis were eligible, how many went with the largest existence lost, and how many of
    them were above report_existence (strictly: one at exactly 0.5 is not)."""
    f = make(max_labels=2)
    f.steps = 6
    f.slot_used[:] = True
    mass = np.array([0.9, 0.5, 0.8, 0.6])
    with pytest.warns(RuntimeWarning) as record:
        f._assign_labels(mass, np.array([0, 1, -1, -1]), np.array([-1, -1, 0, 1]), 2)
    assert str(record[0].message).startswith(
        "max_labels = 2 reached at step 7: 4 Bernoullis held existence >= 0.001, the 2 "
        "weakest (existence up to 0.6; 1 of them above report_existence) were recycled")


def test_duplicates_merge_when_the_cell_keys_do_not_pack():
    """Cells far too small to merge anything but identical states, over a spread too wide for
    one 62-bit key: the lexsort path still brings equal keys together (whatever comes before
    them) and merges exactly those, and nothing else."""
    f = make()
    far = person(1800.0, 1000.0, vx=400.0, vy=-300.0)
    states = [person(900.0), person(900.0, vx=5.0), person(900.0), far, person(900.0)]
    mean = np.stack(states)
    cov = np.tile(np.diag([25.0, 100.0, 4.0]), (5, 2, 1, 1))
    mass, det = np.array([0.1, 0.2, 0.3, 0.4, 0.05]), np.array([0.9, 0.8, 0.7, 0.6, 0.5])
    label = np.array([0, -1, 1, 0, 0])
    assert not _packed_order(_cell_keys(mean, label, np.full(6, 1e-6)))[0]
    out = f._merge(mass, mean, cov, det, det.copy(), np.zeros(5), label)
    assert len(out[0]) == 4
    merged = np.flatnonzero(np.isclose(out[0], 0.15))
    assert len(merged) == 1 and out[6][merged[0]] == 0
    assert out[3][merged[0]] == pytest.approx((0.1 * 0.9 + 0.05 * 0.5) / 0.15, rel=1e-12)
    assert sorted(out[0].tolist()) == pytest.approx([0.15, 0.2, 0.3, 0.4], rel=1e-15)


@pytest.mark.parametrize("seed", [134, 156, 198])
def test_select_keeps_exactly_the_heaviest_for_any_room(seed):
    """Random pools and capacities, including ones where a partition one place off would
    keep a wrong child."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(20, 3000))
    room = int(rng.integers(3, n - 3))
    flat = rng.random(n)
    f = make(capacity=room + N_BIRTH)
    with pytest.warns(RuntimeWarning, match=f"capacity = {room + N_BIRTH} "):
        keep = f._select(flat)
    assert np.array_equal(keep, np.sort(np.argsort(-flat)[:room]))


def test_the_capacity_warning_names_the_step():
    f = make()
    f.steps = 11
    with pytest.warns(RuntimeWarning, match=r"capacity = 16 Gaussian components reached at "
                                            r"step 12: 20 were above prune_mass, the 9 "):
        f._select(np.linspace(0.1, 0.3, 20))


def test_motion_and_survival_for_a_step_of_dt():
    """The motion models and the survival probability of a step of dt seconds, for the
    configured dt and for one given to the step (rebuilt when dt returns)."""
    f = make(position_noise=2.0, velocity_noise=7.0, size_noise=0.5, velocity_time=4.0,
             coast_velocity_time=0.3, death_rate=0.2)
    for dt in (f.config.dt, 0.25, f.config.dt, 0.25):
        f._use_dt(dt)
        assert f.dt == dt
        assert f.motion == ConstantVelocity(dt, 2.0, 7.0, 0.5, 4.0)
        assert f.coast_motion == ConstantVelocity(dt, 2.0, 7.0, 0.5, 0.3)
        assert f.survival_inside == pytest.approx(np.exp(-0.2 * dt), rel=1e-15)


def test_object_means_are_the_first_two_object_moments():
    f = make()
    load(f, [0.3, 0.1, 0.5], [0, 0, 2])
    r, means = f.object_means()
    r2, means2, _ = f.object_moments()
    assert np.array_equal(r, r2) and np.array_equal(means, means2)
    assert r.tolist() == pytest.approx([0.4, 0.0, 0.5, 0.0], rel=1e-15)
    assert means[0, 0, 0] == pytest.approx((0.3 * 900.0 + 0.1 * 940.0) / 0.4, rel=1e-15)
