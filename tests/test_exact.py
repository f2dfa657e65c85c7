"""The exact engine against Monte Carlo sampling of the same generative model, and its errors."""

from __future__ import annotations

from collections import Counter
from fractions import Fraction as F

import numpy as np
import pytest

from occtrack.exact import DiscreteModel, ImpossibleObservation, posterior

# Three cells at increasing depth; nearer cells hide farther ones with some probability.
SHADOW = ((0, F(1, 2), F(3, 4)), (0, 0, F(1, 3)), (0, 0, 0))
MODEL = dict(
    cells=("near", "middle", "far"),
    existence=(F(3, 5), F(1, 2)),
    location=((F(1, 2), F(1, 4), F(1, 4)), (F(1, 5), F(2, 5), F(2, 5))),
    measurement=((F(7, 10), F(1, 10), 0), (F(1, 10), F(7, 10), F(1, 10)),
                 (0, F(1, 5), F(7, 10))),
    clutter=(F(1, 10), F(1, 20), F(1, 10)),
    shadow=SHADOW,
)


def sample_observation(rng: np.random.Generator, occlusion: str):
    """One draw of (object cells, observed multiset) from the generative model, written
    independently of the engine: objects, then measurements, then nearest-first occlusion."""
    m = MODEL
    cells = []
    for r, loc in zip(m["existence"], m["location"], strict=True):
        cells.append(rng.choice(3, p=[float(p) for p in loc]) if rng.random() < r else None)

    def occlude(items):
        visible = []
        for c in sorted(items):  # cell index is depth
            hide = 1.0
            for a in visible:
                hide *= 1 - float(SHADOW[a][c])
            if rng.random() < hide:
                visible.append(c)
        return visible

    emitters = [c for c in cells if c is not None]
    if occlusion == "object-wise":
        emitters = occlude(emitters)
    measurements = []
    for c in emitters:
        row = [float(p) for p in m["measurement"][c]]
        u = rng.random()
        cum = np.cumsum(row)
        hit = int(np.searchsorted(cum, u, side="right"))
        if hit < 3:
            measurements.append(hit)
    for z, rate in enumerate(m["clutter"]):
        measurements += [z] * rng.poisson(float(rate))
    if occlusion == "measurement-wise":
        measurements = occlude(measurements)
    return cells, Counter(measurements)


@pytest.mark.parametrize("occlusion", ["none", "object-wise", "measurement-wise"])
def test_exact_posterior_matches_monte_carlo(occlusion):
    observed = [0, 2]
    exact = posterior(DiscreteModel(occlusion=occlusion, **MODEL), observed)
    rng = np.random.default_rng(12345)
    target = Counter(observed)
    accepted = exists = at_near = 0
    for _ in range(60_000):
        cells, seen = sample_observation(rng, occlusion)
        if seen != target:
            continue
        accepted += 1
        if cells[1] is not None:
            exists += 1
            at_near += cells[1] == 0
    assert accepted > 1000
    p_hat = exists / accepted
    p = float(exact.existence[1])
    se = max(np.sqrt(p * (1 - p) / accepted), 1e-9)
    assert abs(p_hat - p) < 4 * se, (p_hat, p, se)
    q = float(exact.location[1][0])
    q_hat = at_near / exists
    se = np.sqrt(q * (1 - q) / exists)
    assert abs(q_hat - q) < 4 * se, (q_hat, q, se)


def test_single_object_is_bayes_rule():
    model = DiscreteModel(cells=("a", "b"), existence=(F(1, 2),), location=((F(1, 3), F(2, 3)),),
                          measurement=((F(3, 4), 0), (0, F(1, 2))))
    post = posterior(model, [])
    # P(no measurement, exists) = 1/2 (1/3 1/4 + 2/3 1/2) = 5/24; P(absent) = 1/2.
    assert post.existence[0] == F(5, 24) / (F(5, 24) + F(1, 2))
    assert post.location[0] == (F(1, 12) / F(5, 12), F(4, 12) / F(5, 12))


def test_impossible_observation_is_named():
    model = DiscreteModel(occlusion="measurement-wise",
                          **{**MODEL, "clutter": (0, 0, 0),
                             "shadow": ((0, 1, 1), (0, 0, 1), (0, 0, 0))})
    with pytest.raises(ImpossibleObservation, match=r"observing \[near, far\] has probability 0"):
        posterior(model, [0, 2])


def test_measurement_wise_miss_term_is_the_papers():
    """One object, no clutter, a visible measurement from elsewhere is impossible without
    clutter, so use two objects: the far object's miss term gains P_D q (paper eq. 16)."""
    model = DiscreteModel(cells=("near", "far"), existence=(1, F(1, 2)),
                          location=((1, 0), (0, 1)),
                          measurement=((F(4, 5), 0), (F(1, 5), F(3, 5))),
                          occlusion="measurement-wise", shadow=((0, 1), (0, 0)))
    post = posterior(model, [0])
    # Far object: produces nothing with 1 - P_D = 1/5, a hidden measurement in "far" (3/5), or a
    # measurement in "near" (1/5) that must then be the one seen while the near object misses.
    # Present: 1/2 [4/5 (1/5 + 3/5) + 1/5 1/5]; absent: 1/2 4/5.
    present = F(1, 2) * (F(4, 5) * (F(1, 5) + F(3, 5)) + F(1, 5) * F(1, 5))
    absent = F(1, 2) * F(4, 5)
    assert post.existence[1] == present / (present + absent)


@pytest.mark.parametrize("change,message", [
    ({"shadow": ((0, 1, 0), (1, 0, 0), (0, 0, 0))}, "acyclic"),
    ({"shadow": ((1, 0, 0), (0, 0, 0), (0, 0, 0))}, "acyclic"),
    ({"location": ((F(1, 2), F(1, 4), F(1, 8)), (1, 0, 0))}, "distribution"),
    ({"existence": (F(3, 2), F(1, 2))}, "outside"),
    ({"measurement": ((F(3, 4), F(1, 2), 0), (0, 1, 0), (0, 0, 1))}, "at most 1"),
    ({"clutter": (-1, 0, 0)}, "non-negative"),
])
def test_invalid_models_are_refused(change, message):
    with pytest.raises(ValueError, match=message):
        DiscreteModel(**{**MODEL, **change})
