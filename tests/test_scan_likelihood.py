"""The multi-object scan likelihood (`occtrack.models.scan`) against what it claims to be: the
nearest-return density of the measurement-wise beam model, checked by enumerating which objects
returned and which source is nearest (plain floats), by integrating it, by sampling the model
and by the lidar scene's own sensor; the one-object case is `models.beam`; the geometry against
a ray marched in small steps."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad

from occtrack.config.lidar import LidarSceneConfig
from occtrack.models import scan
from occtrack.models.beam import BeamModel, gaussian_likelihood_ratio, likelihood_ratio
from occtrack.models.scan_geometry import disc_range_gradient, disc_ranges
from occtrack.scenarios.lidar.raycast import Shapes, cast
from occtrack.scenarios.lidar.scene import beam_angles, measure

MODEL = BeamModel(p_d=0.8, sigma=0.3, clutter_rate=0.5, max_range=12.0)
OBJECTS = {2: [4.0, 4.5], 3: [3.0, 3.4, 6.0]}


# -- brute force: which objects returned, which source is nearest --------------------------------

def _phi(t):
    return 0.5 * (1.0 + math.erf(t / math.sqrt(2.0)))


def _normal(z, mean, s):
    return math.exp(-0.5 * ((z - mean) / s) ** 2) / (math.sqrt(2 * math.pi) * s)


def _enumerate(z, rho, model):
    """p(nearest return at z) and P(source | z) summed over the 2^K sets of objects that
    returned and, in each, over the source that is nearest (the others beyond z, no clutter
    before z). z = None: the probability of no return before R."""
    p_d, s, kappa = model.p_d, model.sigma, model.kappa
    by_source = [0.0] * (len(rho) + 1)  # objects, then clutter
    for returned in itertools.product((False, True), repeat=len(rho)):
        weight = math.prod(p_d if r else 1 - p_d for r in returned)
        ks = [k for k, r in enumerate(returned) if r]
        if z is None:
            by_source[-1] += weight * math.exp(-model.clutter_rate) * math.prod(
                1 - _phi((model.max_range - rho[k]) / s) for k in ks)
            continue
        beyond = {k: 1 - _phi((z - rho[k]) / s) for k in ks}
        no_clutter = math.exp(-kappa * z)
        for k in ks:
            by_source[k] += weight * no_clutter * _normal(z, rho[k], s) * math.prod(
                beyond[j] for j in ks if j != k)
        by_source[-1] += weight * no_clutter * kappa * math.prod(beyond.values())
    return sum(by_source), by_source


@pytest.mark.parametrize("k", [2, 3])
def test_density_matches_enumeration(k):
    """The closed form e^{-kappa z}[kappa prod m + sum h prod m'] is the sum over which
    objects returned and which source is nearest, at returns around and between the objects,
    and the no-return probability likewise; the source posteriors too."""
    rho = OBJECTS[k]
    zs = np.r_[np.linspace(0.0, MODEL.max_range - 1e-9, 61), np.array(rho) + 0.1]
    got = scan.beam_likelihood(zs, np.tile(rho, (len(zs), 1)), MODEL)
    objects, clutter = scan.source_probabilities(zs, np.tile(rho, (len(zs), 1)), MODEL)
    for i, z in enumerate(zs):
        total, by_source = _enumerate(z, rho, MODEL)
        assert got[i] == pytest.approx(total, rel=1e-12, abs=1e-300)
        assert np.allclose(np.r_[objects[i], clutter[i]], np.array(by_source) / total,
                           rtol=1e-10, atol=1e-14)
    none = scan.beam_likelihood(np.array([np.inf]), np.array([rho]), MODEL)[0]
    assert none == pytest.approx(_enumerate(None, rho, MODEL)[0], rel=1e-12)
    assert np.all(scan.source_probabilities(np.array([np.inf]), np.array([rho]), MODEL)[0] == 0)


@pytest.mark.parametrize("rho", [[], [5.0], OBJECTS[2], OBJECTS[3], [2.0, 11.5, 30.0]])
def test_density_and_no_return_sum_to_one(rho):
    """The density over [0, R] and the probability of no return make 1 (objects several sigma
    from 0, so no return falls below it; one beyond R and one straddling it), and the density
    is minus the survival function's slope, S(R) the no-return probability."""
    rho_row = np.array([rho], float).reshape(1, -1)

    def density(z):
        return scan.beam_likelihood(np.array([z]), rho_row, MODEL)[0]

    inside = [r for r in rho if 0 < r < MODEL.max_range]
    mass, err = quad(density, 0.0, MODEL.max_range, points=inside or None, limit=200,
                     epsabs=1e-12, epsrel=1e-12)
    none = scan.beam_likelihood(np.array([np.inf]), rho_row, MODEL)[0]
    assert mass + none == pytest.approx(1.0, abs=1e-9)
    zs = np.linspace(0.5, MODEL.max_range - 0.5, 23)
    rows = np.repeat(rho_row, len(zs), axis=0)
    step = 1e-5
    slope = (scan.survival(zs + step, rows, MODEL) - scan.survival(zs - step, rows, MODEL)) / (
        2 * step)
    assert np.allclose(-slope, scan.beam_likelihood(zs, rows, MODEL), rtol=1e-6, atol=1e-9)
    end = scan.survival(np.array([MODEL.max_range]), rho_row, MODEL)[0]
    assert end == pytest.approx(none, rel=1e-12)


def test_histogram_of_sampled_nearest_returns():
    """200 000 beams drawn from the generative model (each object returns with P_D at
    N(rho, sigma^2); clutter's first return is the first arrival of a Poisson process of
    kappa per metre; nearest kept, none at or past R): each bin's count is within 4 standard
    errors (sqrt(N p (1 - p))) of N times the density integrated over the bin (quad)."""
    rng = np.random.default_rng(5)
    rho, n = np.array(OBJECTS[3]), 200_000
    returns = np.where(rng.random((n, 3)) < MODEL.p_d,
                       rho + MODEL.sigma * rng.standard_normal((n, 3)), np.inf)
    clutter = rng.exponential(1 / MODEL.kappa, n)
    z = np.minimum(returns.min(axis=1), clutter)
    z = np.where(z < MODEL.max_range, z, np.inf)
    assert np.all(z[np.isfinite(z)] >= 0)
    edges = np.unique(np.r_[0.0, MODEL.max_range, np.linspace(0, MODEL.max_range, 13),
                            (rho[:, None] + MODEL.sigma * np.arange(-3, 4)).ravel()])
    counts = np.r_[np.histogram(z[np.isfinite(z)], edges)[0], np.count_nonzero(np.isinf(z))]
    row = rho[None, :]
    probs = [quad(lambda x: scan.beam_likelihood(np.array([x]), row, MODEL)[0], a, b,
                  epsabs=1e-12)[0] for a, b in itertools.pairwise(edges)]
    probs.append(scan.beam_likelihood(np.array([np.inf]), row, MODEL)[0])
    p = np.array(probs)
    assert p.sum() == pytest.approx(1.0, abs=1e-9)
    se = np.sqrt(n * p * (1 - p))
    assert np.all(np.abs(counts - n * p) <= 4 * se), (counts - n * p) / se


def test_one_object_is_the_single_beam_ratio():
    """K = 1 gives models.beam.likelihood_ratio at every return, and its Gaussian form with an
    uncertain range; no return gives m(R) = 1 - P_D Phi((R - rho) / sigma), the 1 - P_D of
    models.beam for an object well inside R."""
    z = np.linspace(0.0, MODEL.max_range - 1e-9, 97)
    for x in (0.5, 3.0, 6.2, 11.0):
        got = scan.beam_likelihood_ratio(z, np.full((len(z), 1), x), MODEL)
        assert np.allclose(got, likelihood_ratio(z, x, MODEL), rtol=1e-13, atol=0)
        for v in (0.01, 0.7):
            var = np.full((len(z), 1), v)
            expected = [gaussian_likelihood_ratio(zi, x, v, MODEL) for zi in z]
            got = scan.beam_likelihood_ratio(z, np.full((len(z), 1), x), MODEL, var)
            assert np.allclose(got, expected, rtol=1e-13, atol=0)
        none = scan.beam_likelihood_ratio(np.array([np.inf]), np.array([[x]]), MODEL)[0]
        assert none == pytest.approx(1 - MODEL.p_d * _phi((MODEL.max_range - x) / MODEL.sigma))
    none = scan.beam_likelihood_ratio(np.array([np.inf]), np.array([[3.0]]), MODEL)[0]
    assert none == pytest.approx(1 - MODEL.p_d, rel=1e-12)


def test_regimes_and_their_factors():
    """Three well-separated objects on one beam: a return far short of an object leaves it a
    factor of about 1 (hidden), far beyond it or none about 1 - P_D (passed: the beam went
    through it), on it a large factor (hit); each factor is the likelihood with the object
    over that without it (its column dropped), and the regimes name them."""
    rho = np.array([[3.0, 6.0, 9.0]])
    z = np.array([1.0, 6.05, 11.0, np.inf])
    rows = np.repeat(rho, len(z), axis=0)
    ratios = scan.object_ratios(z, rows, MODEL)
    full = scan.beam_likelihood_ratio(z, rows, MODEL)
    for k in range(3):
        without = scan.beam_likelihood_ratio(z, np.delete(rows, k, axis=1), MODEL)
        assert np.allclose(ratios[:, k], full / without, rtol=1e-12)
    assert np.allclose(ratios[0], 1.0, atol=1e-12)  # all hidden behind the return at 1 m
    assert ratios[1, 0] == pytest.approx(1 - MODEL.p_d, rel=1e-9)  # passed
    assert ratios[1, 1] > 10  # hit: P_D N(z; rho, sigma^2) / kappa is about 25
    assert ratios[1, 2] == pytest.approx(1.0, abs=1e-9)  # hidden
    assert np.allclose(ratios[2:], 1 - MODEL.p_d, rtol=1e-9)  # passed, or no return
    assert scan.regimes(z, rows, MODEL).tolist() == [
        ["hidden"] * 3, ["passed", "hit", "hidden"], ["passed"] * 3, ["passed"] * 3]
    logs = scan.object_log_ratios(z, rows, MODEL)
    assert np.allclose(logs, np.log(ratios).sum(axis=0))


def test_certain_detection_has_exact_zeros():
    """With P_D = 1 a return well beyond an object is impossible (the object's factor exactly
    0, its log -inf, no NaN from a divided-out zero), and an object's factor on a beam the
    others alone already rule out is 1."""
    sure = BeamModel(p_d=1.0, sigma=0.01, clutter_rate=0.5, max_range=12.0)
    rows = np.array([[3.0, 6.0]] * 3)
    z = np.array([3.0, 6.0, 9.0])
    ratios = scan.object_ratios(z, rows, sure)
    assert ratios[0, 0] > 1 and ratios[0, 1] == 1.0  # hit the first, the second hidden
    assert ratios[1].tolist() == [0.0, 1.0]  # the first would have returned before 6 m
    assert ratios[2].tolist() == [1.0, 1.0]  # either alone rules 9 m out
    assert scan.beam_likelihood_ratio(z, rows, sure).tolist()[1:] == [0.0, 0.0]
    assert scan.object_log_ratios(z[1:2], rows[:1], sure).tolist() == [-np.inf, 0.0]


def test_uncertain_ranges_average_the_likelihood():
    """With each object's range N(mean, v), independently, the closed form with sigma^2 + v is
    the average of Lambda over sampled ranges (Monte Carlo, within 4 standard errors)."""
    rng = np.random.default_rng(2)
    mean, v = np.array([4.0, 4.6]), np.array([0.04, 0.09])
    n = 100_000
    draws = mean + np.sqrt(v) * rng.standard_normal((n, 2))
    for z in (3.5, 4.1, 4.7, 7.0, np.inf):
        sample = scan.beam_likelihood_ratio(np.full(n, z), draws, MODEL)
        closed = scan.beam_likelihood_ratio(np.array([z]), mean[None], MODEL, v[None])[0]
        se = sample.std() / math.sqrt(n)
        assert abs(sample.mean() - closed) <= 4 * se + 1e-12


# -- geometry --------------------------------------------------------------------------------------

def _marched_range(o, angle, c, a, step=2e-4, far=12.0):
    """The first t >= 0 with |o + t u - c| <= a, found by stepping along the ray and bisecting
    the step where it enters (only the inside test: no quadratic)."""
    u = (math.cos(angle), math.sin(angle))

    def inside(t):
        return np.hypot(o[0] + t * u[0] - c[0], o[1] + t * u[1] - c[1]) <= a

    steps = np.arange(0.0, far, step)
    hits = np.flatnonzero(inside(steps))
    if len(hits) == 0:
        return math.inf
    if hits[0] == 0:
        return 0.0
    lo, hi = steps[hits[0] - 1], steps[hits[0]]
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if inside(mid) else (mid, hi)
    return hi


def test_disc_ranges_against_a_marched_ray():
    """Near-surface ranges of discs in front of, around and behind the sensor (and one with the
    sensor inside) along beams that hit, graze and miss them; inf for a miss. Beams within
    a step of grazing (a chord shorter than the march's step) are left out."""
    rng = np.random.default_rng(3)
    origin = np.array([0.3, -0.2])
    centres = np.array([[3.0, 0.5], [-2.0, -1.0], [0.0, 4.0], [0.35, -0.1]])
    radius = np.array([0.5, 0.25, 1.0, 0.3])
    angles = np.r_[rng.uniform(-np.pi, np.pi, 40),
                   np.arctan2(*(centres - origin)[:, ::-1].T)]  # straight at each centre
    got = disc_ranges(origin, angles, centres, radius)
    checked = 0
    for b, angle in enumerate(angles):
        u = np.array([math.cos(angle), math.sin(angle)])
        for k, (c, a) in enumerate(zip(centres, radius, strict=True)):
            p = c - origin
            gap = abs(u[0] * p[1] - u[1] * p[0])
            if 0 < a**2 - gap**2 < 1e-3 * a:
                continue
            expected = _marched_range(origin, angle, c, a)
            assert got[b, k] == pytest.approx(expected, abs=1e-9), (b, k)
            checked += 1
    assert checked > 150 and np.isinf(got).sum() > 100 and np.isfinite(got).sum() > 8


def test_range_gradient_is_the_slope():
    """disc_range_gradient against central differences of disc_ranges in the centre, and
    range_variance against the sampled ranges of a centre drawn from its covariance."""
    origin = np.zeros(2)
    centre = np.array([[4.0, 0.1], [2.0, -0.3]])
    angles = np.linspace(-0.15, 0.15, 31)
    grad = disc_range_gradient(origin, angles, centre, 0.25)
    rho = disc_ranges(origin, angles, centre, 0.25)
    step = 1e-6
    for axis in range(2):
        shift = np.zeros(2)
        shift[axis] = step
        with np.errstate(invalid="ignore"):  # inf - inf off the disc
            diff = (disc_ranges(origin, angles, centre + shift, 0.25)
                    - disc_ranges(origin, angles, centre - shift, 0.25)) / (2 * step)
        well_inside = np.isfinite(rho) & np.isfinite(diff) & (np.abs(grad[..., 1]) < 3)
        assert well_inside.sum() > 10
        assert np.allclose(grad[..., axis][well_inside], diff[well_inside], atol=1e-5)
    assert np.all(grad[np.isinf(rho)] == 0)
    cov = np.array([[[0.02**2, 0.0], [0.0, 0.01**2]], [[0.01**2, 5e-5], [5e-5, 0.01**2]]])
    draws = np.random.default_rng(6).standard_normal((20_000, 2))
    for k in range(2):
        # beams through the centre and 0.1 m beside it, where rho is still nearly linear
        for offset in (0.0, 0.1):
            angle = np.arctan2(centre[k, 1], centre[k, 0]) + np.arcsin(
                offset / np.hypot(*centre[k]))
            moved = centre[k] + draws @ np.linalg.cholesky(cov[k]).T
            sampled = disc_ranges(origin, [angle], moved, 0.25)[0]
            v = scan.range_variance(origin, [angle], centre, 0.25, cov)[0, k]
            assert np.var(sampled) == pytest.approx(v, rel=0.05)


def test_objects_a_beam_misses_change_nothing():
    """An object no beam reaches leaves every beam's likelihood the same to the bit, has a log
    ratio of exactly 0, and its factor on each beam is exactly 1; so is an object's factor on
    the beams that miss it."""
    model = BeamModel(p_d=0.98, sigma=0.02, clutter_rate=5 / 720, max_range=20.0)
    origin = np.zeros(2)
    angles = np.linspace(-0.3, 0.3, 61)
    centres = np.array([[3.0, 0.0], [5.0, 0.3], [6.0, 0.05]])
    rng = np.random.default_rng(4)
    rho = disc_ranges(origin, angles, centres, 0.25)
    z = np.where(rng.random(61) < 0.3, np.inf,
                 np.minimum(rho.min(axis=1), 20.0) + 0.05 * rng.standard_normal(61))
    behind = np.array([[-5.0, 0.0]])
    rho_more = disc_ranges(origin, angles, np.r_[centres, behind], 0.25)
    assert np.isinf(rho_more[:, 3]).all()
    assert np.array_equal(scan.beam_likelihood_ratio(z, rho, model),
                          scan.beam_likelihood_ratio(z, rho_more, model))
    logs = scan.scan_log_ratios(origin, angles, z, np.r_[centres, behind], 0.25, model)
    assert logs[3] == 0.0 and np.array_equal(logs[:3], scan.object_log_ratios(z, rho, model))
    ratios = scan.object_ratios(z, rho, model)
    assert np.all(ratios[np.isinf(rho)] == 1.0)


def test_uncertain_centres_reduce_to_certain_ones():
    """scan_log_ratios with a zero covariance is the same as without; a covariance widens
    the hit (a smaller factor at the hit, a larger one near it)."""
    model = BeamModel(p_d=0.9, sigma=0.05, clutter_rate=0.01, max_range=20.0)
    origin, angles = np.zeros(2), np.array([0.0])
    centre = np.array([[3.25, 0.0]])
    sharp = scan.scan_log_ratios(origin, angles, np.array([3.0]), centre, 0.25, model)
    zero = scan.scan_log_ratios(origin, angles, np.array([3.0]), centre, 0.25, model,
                                np.zeros((1, 2, 2)))
    blurred = scan.scan_log_ratios(origin, angles, np.array([3.0]), centre, 0.25, model,
                                   np.diag([0.04, 0.04])[None])
    off = [scan.scan_log_ratios(origin, angles, np.array([3.3]), centre, 0.25, model, cov)
           for cov in (None, np.diag([0.04, 0.04])[None])]
    assert np.array_equal(sharp, zero) and blurred[0] < sharp[0] and off[1][0] > off[0][0]


# -- the lidar scene's own sensor -----------------------------------------------------------------

def test_scene_sensor_matches_the_density():
    """4000 scans of the lidar scene's measurement-wise sensor (`scene.measure`: 720 beams,
    clutter spread over them, nearest return) of three static people in a row, partly behind
    one another: on every beam that reaches one (and a few that reach none), the reported
    ranges fall into 8 bins of equal probability under the closed form, plus "none", each
    count within 4 standard errors (sqrt(N p (1 - p))) of N p; the chi-square over all of
    them is within 4 of its standard deviations of its mean."""
    config = LidarSceneConfig(sensor="measurement-wise", range_noise=0.1, p_d=0.7,
                              clutter_per_scan=180.0, max_range=10.0, people=0)
    model = BeamModel(p_d=config.p_d, sigma=config.range_noise,
                      clutter_rate=config.clutter_per_scan / config.beams,
                      max_range=config.max_range)
    centres = np.array([[3.0, 0.0], [4.5, 0.15], [6.0, -0.1]])
    shapes = Shapes(centres, np.zeros(3), np.full(3, 0.5), np.full(3, 0.5), np.ones(3, bool))
    angles = beam_angles(config)
    dist = cast(np.zeros(2), angles, shapes)
    assert np.allclose(dist, disc_ranges(np.zeros(2), angles, centres, 0.25))
    beams = np.r_[np.flatnonzero(np.isfinite(dist).any(axis=1)), [0, 180, 360]]
    assert np.count_nonzero(np.isfinite(dist[beams]).sum(axis=1) >= 2) >= 5
    rng = np.random.default_rng(11)
    n = 4000
    z = np.array([measure(dist, config, rng)[beams] for _ in range(n)])  # (n, beams)

    grid = np.linspace(0.0, config.max_range, 20_001)
    below_r = np.minimum(grid, np.nextafter(config.max_range, 0))  # R itself is "none"
    rows = np.repeat(dist[beams], len(grid), axis=0)
    dens = scan.beam_likelihood(np.tile(below_r, len(beams)), rows, model).reshape(len(beams), -1)
    cdf = np.c_[np.zeros(len(beams)), np.cumsum((dens[:, 1:] + dens[:, :-1]) / 2, axis=1)
                * (grid[1] - grid[0])]
    none = scan.beam_likelihood(np.full(len(beams), np.inf), dist[beams], model)
    assert np.allclose(cdf[:, -1] + none, 1.0, atol=1e-6)
    chi2, cells = 0.0, 0
    for i in range(len(beams)):
        quantiles = np.linspace(0, cdf[i, -1], 9)
        edges = np.interp(quantiles, cdf[i], grid)
        edges[0], edges[-1] = 0.0, config.max_range
        seen = z[:, i][np.isfinite(z[:, i])]
        counts = np.r_[np.histogram(seen, edges)[0], n - len(seen)]
        p = np.r_[np.diff(np.interp(edges, grid, cdf[i])), none[i]]
        se = np.sqrt(n * p * (1 - p))
        assert np.all(np.abs(counts - n * p) <= 4 * se), (beams[i], (counts - n * p) / se)
        chi2 += np.sum((counts - n * p) ** 2 / (n * p))
        cells += len(p) - 1
    assert abs(chi2 - cells) <= 4 * math.sqrt(2 * cells), (chi2, cells)
