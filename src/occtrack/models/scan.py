"""The likelihood of a whole 2-D lidar scan given several objects, under measurement-wise
occlusion (paper sections IV and V): `models.beam`'s one-object beam likelihood made exact for
any number of objects on a beam, and split per object for a tracker.

The model (the paper's deterministic restricted measurement-wise occlusion, and the "measurement-
wise" sensor of `occtrack.scenarios.lidar`): on beam b, every object k the beam reaches (its near
surface at range rho_bk, `scan_geometry.disc_ranges`) returns with probability P_D at
N(rho_bk, sigma^2), independently; clutter returns are Poisson, `clutter_rate` a beam, uniform on
[0, R] (R = max_range, kappa = clutter_rate / R per metre); the sensor reports the nearest
return, or none before R. Objects the beam misses take no part.

Nothing is before z when no clutter return is (e^{-kappa z}) and each object's return is absent
or beyond z,

    m_k(z) = 1 - P_D Phi((z - rho_k) / sigma)      (k is missed, or hidden by the return at z),

so the survival function of the nearest return is S(z) = e^{-kappa z} prod_k m_k(z) and its
density, -dS/dz with h_k(z) = P_D N(z; rho_k, sigma^2) = -m_k'(z), is

    p(z | X) = e^{-kappa z} [kappa prod_k m_k + sum_k h_k prod_{k' != k} m_k'],   0 <= z < R,
    P(none | X) = S(R) = e^{-clutter_rate} prod_k m_k(R).

Against no object (clutter alone: kappa e^{-kappa z}, e^{-clutter_rate}) the shared clutter
factor cancels and the beam's likelihood ratio is

    Lambda(z | X) = prod_k m_k + sum_k g_k prod_{k' != k} m_k',   g_k = h_k / kappa,

(prod_k m_k(R) for no return). For one object it is `beam.likelihood_ratio`,
m + g = 1 - P_D Phi + P_D N / kappa (which takes no return as 1 - P_D, m(R) for rho << R).
Lambda is the "epsilon" part plus the real part of the dual-number product
prod_k (m_k + epsilon g_k), epsilon^2 = 0: one object makes a return, or none does, never two,
which is the paper's eq. "new_individual_MM" summed over which source is nearest. Products are
taken with prefix and suffix products over each beam's objects, never by dividing out a factor
(m_k can be 0 when P_D = 1), so the leave-one-out terms are exact.

For a tracker, per beam and object:
- which source made z (`source_probabilities`): object k with g_k prod_{k' != k} m_k' / Lambda,
  clutter with prod_k m_k / Lambda;
- object k's own factor given the others (`object_ratios`), Lambda(z | X) / Lambda(z | X - k)
  = m_k + g_k prod_{k' != k} m_k' / Lambda(z | X - k): exactly 1 on a beam that misses k, and in
  section V's three regimes (`regimes`) about g_k (hit: z near rho_k), 1 - P_D (passed: z well
  beyond rho_k, or no return: the beam went through where k would be, negative information) and
  1 (hidden: z well short of rho_k, a nearer return hides k; the paper's "short" return);
- its log-likelihood ratio over the scan (`object_log_ratios`, `scan_log_ratios`): the sum of
  the logs of those factors over the beams.

Uncertain ranges: for rho_k ~ N(mean, v), independently between objects (a multi-Bernoulli's
objects are), E m_k and E h_k are the same expressions with sigma^2 + v for sigma^2, and Lambda
is multilinear in the objects' factors, so E Lambda is Lambda of the expected factors (`var`
everywhere; for one object, `beam.gaussian_likelihood_ratio`). A disc's range is linearised in
its centre, v = grad^T Sigma grad (`range_variance`): exact for a range that is Gaussian, and
poor on the beams that graze the disc, where the slope grows without bound; whether a beam
reaches the disc at all is decided at the mean. The expectation is per beam: an object's ranges
on neighbouring beams move together, so the product over beams of expectations is not the
expectation of the product.

The returns are Gaussian on the whole line: the mass P_D Phi(-rho_k / sigma) below 0 (the
simulator puts it at 0) is outside [0, R], negligible for rho_k of a few sigma.

Written by hand: the closed form is the paper's (no library has this sensor model), numpy is
enough, and scipy gives Phi.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from occtrack.models.beam import SQRT_2PI, BeamModel, regime
from occtrack.models.scan_geometry import disc_range_gradient, disc_ranges


def _returned(z: np.ndarray, model: BeamModel) -> np.ndarray:
    """Beams with a return before max_range (inf, or anything at or beyond R, is none)."""
    return np.asarray(z, float) < model.max_range


def beam_terms(z: np.ndarray, rho: np.ndarray, model: BeamModel,
               var: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(m, g), each (B, K), for returns z (B,) and ranges rho (B, K) (inf: the beam misses the
    object): m = 1 - P_D Phi((z - rho) / s), g = P_D N(z; rho, s^2) / kappa with
    s^2 = sigma^2 + var; on a beam with no return m is taken at R and g is 0."""
    z, rho = np.asarray(z, float), np.asarray(rho, float)
    seen = _returned(z, model)
    at = np.where(seen, z, model.max_range)[:, None]
    s = model.sigma if var is None else np.sqrt(model.sigma**2 + np.asarray(var, float))
    with np.errstate(invalid="ignore"):
        t = np.where(np.isfinite(rho), (at - rho) / s, -np.inf)
    m = 1.0 - model.p_d * ndtr(t)
    h = model.p_d * np.exp(-0.5 * t**2) / (SQRT_2PI * s)
    return m, np.where(seen[:, None], h / model.kappa, 0.0)


def _dual_products(m: np.ndarray, g: np.ndarray):
    """P = prod_k m_k, Q = sum_k g_k prod_{k' != k} m_k' per beam (B,), and the same without
    each object, P_-k and Q_-k (B, K): the dual-number product prod (m_k + epsilon g_k) and its
    leave-one-out, by prefix and suffix products over the objects that matter on each beam
    (m != 1 or g != 0; the rest are the identity), so no factor is ever divided out."""
    b, k = m.shape
    active = (m != 1.0) | (g != 0.0)
    depth = int(active.sum(axis=1).max(initial=0))
    order = np.argsort(~active, axis=1, kind="stable")[:, :depth]
    live = np.take_along_axis(active, order, axis=1)
    mc = np.where(live, np.take_along_axis(m, order, axis=1), 1.0)
    gc = np.where(live, np.take_along_axis(g, order, axis=1), 0.0)
    pre_p, pre_q = np.ones((b, depth + 1)), np.zeros((b, depth + 1))
    suf_p, suf_q = np.ones((b, depth + 1)), np.zeros((b, depth + 1))
    for j in range(depth):
        pre_p[:, j + 1] = pre_p[:, j] * mc[:, j]
        pre_q[:, j + 1] = pre_q[:, j] * mc[:, j] + pre_p[:, j] * gc[:, j]
        i = depth - 1 - j
        suf_p[:, i] = suf_p[:, i + 1] * mc[:, i]
        suf_q[:, i] = suf_q[:, i + 1] * mc[:, i] + suf_p[:, i + 1] * gc[:, i]
    p, q = pre_p[:, depth], pre_q[:, depth]
    p_out, q_out = np.repeat(p[:, None], k, axis=1), np.repeat(q[:, None], k, axis=1)
    loo_p = pre_p[:, :depth] * suf_p[:, 1:]
    loo_q = pre_q[:, :depth] * suf_p[:, 1:] + pre_p[:, :depth] * suf_q[:, 1:]
    rows = np.broadcast_to(np.arange(b)[:, None], order.shape)
    p_out[rows[live], order[live]] = loo_p[live]
    q_out[rows[live], order[live]] = loo_q[live]
    return p, q, p_out, q_out


def beam_likelihood_ratio(z: np.ndarray, rho: np.ndarray, model: BeamModel,
                          var: np.ndarray | None = None) -> np.ndarray:
    """Lambda(z_b | X) (B,): each beam's likelihood with the objects at ranges rho (B, K) over
    that with none (clutter alone)."""
    p, q, _, _ = _dual_products(*beam_terms(z, rho, model, var))
    return p + q


def beam_likelihood(z: np.ndarray, rho: np.ndarray, model: BeamModel,
                    var: np.ndarray | None = None) -> np.ndarray:
    """p(z_b | X) (B,): the density of the nearest return at z_b (per metre), or on a beam with
    no return the probability of none before max_range."""
    z = np.asarray(z, float)
    seen = _returned(z, model)
    clutter = np.where(seen, model.kappa * np.exp(-model.kappa * np.where(seen, z, 0.0)),
                       np.exp(-model.clutter_rate))
    return clutter * beam_likelihood_ratio(z, rho, model, var)


def survival(z: np.ndarray, rho: np.ndarray, model: BeamModel) -> np.ndarray:
    """S(z_b) = P(no return before z_b) = e^{-kappa z} prod_k m_k(z) (B,), for 0 <= z <= R."""
    z = np.asarray(z, float)
    t = np.where(np.isfinite(rho), (z[:, None] - rho) / model.sigma, -np.inf)
    return np.exp(-model.kappa * z) * np.prod(1.0 - model.p_d * ndtr(t), axis=1)


def source_probabilities(z: np.ndarray, rho: np.ndarray, model: BeamModel,
                         var: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Which source made each beam's return: P(object k | z_b, X) (B, K) and P(clutter) (B,);
    both 0 on a beam with no return (nothing made it)."""
    m, g = beam_terms(z, rho, model, var)
    p, q, p_k, _ = _dual_products(m, g)
    total = p + q
    seen = _returned(z, model) & (total > 0)
    safe = np.where(seen, total, 1.0)
    return (np.where(seen[:, None], g * p_k / safe[:, None], 0.0),
            np.where(seen, p / safe, 0.0))


def object_ratios(z: np.ndarray, rho: np.ndarray, model: BeamModel,
                  var: np.ndarray | None = None) -> np.ndarray:
    """Lambda(z_b | X) / Lambda(z_b | X - k) (B, K): what object k adds to each beam given the
    others; exactly 1 on a beam that misses it. A beam the others alone make impossible
    (P_D = 1 and a return well beyond one of them) is impossible with k too: 1 there."""
    p, q, p_k, q_k = _dual_products(*beam_terms(z, rho, model, var))
    without = p_k + q_k
    ok = without > 0
    return np.where(ok, (p + q)[:, None] / np.where(ok, without, 1.0), 1.0)


def object_log_ratios(z: np.ndarray, rho: np.ndarray, model: BeamModel,
                      var: np.ndarray | None = None) -> np.ndarray:
    """Each object's log-likelihood ratio over the scan given the others (K,): the sum over the
    beams that reach it of log Lambda(z_b | X) / Lambda(z_b | X - k)."""
    with np.errstate(divide="ignore"):
        return np.log(object_ratios(z, rho, model, var)).sum(axis=0)


def regimes(z: np.ndarray, rho: np.ndarray, model: BeamModel, width: float = 3.0) -> np.ndarray:
    """Section V's simplification per beam and object (B, K): "hit" (|z - rho| <= width
    sigma), "passed" (z beyond rho, or no return), "hidden" (z short of rho) or "off" (the
    beam misses the object)."""
    z = np.where(_returned(z, model), np.asarray(z, float), np.inf)
    rho = np.asarray(rho, float)
    with np.errstate(invalid="ignore"):
        r = regime(rho, z[:, None], model, width)
    return np.where(np.isfinite(rho), r, "off")


def range_variance(origin: np.ndarray, angles: np.ndarray, centre: np.ndarray,
                   radius: float | np.ndarray, cov: np.ndarray) -> np.ndarray:
    """v (B, K): the variance of each disc's range along each beam for a centre ~ N(centre,
    cov (K, 2, 2)), linearised at the mean."""
    g = disc_range_gradient(origin, angles, centre, radius)
    cov = np.asarray(cov, float).reshape(-1, 2, 2)
    return (g[..., 0] ** 2 * cov[:, 0, 0] + g[..., 0] * g[..., 1] * (cov[:, 0, 1] + cov[:, 1, 0])
            + g[..., 1] ** 2 * cov[:, 1, 1])


def scan_log_ratios(origin: np.ndarray, angles: np.ndarray, ranges: np.ndarray,
                    centre: np.ndarray, radius: float | np.ndarray, model: BeamModel,
                    cov: np.ndarray | None = None) -> np.ndarray:
    """Each disc's log-likelihood ratio (K,) over one scan (sensor at `origin`, beams at world
    `angles` (B,), reported `ranges` (B,), inf for none) given the other discs; with `cov`
    (K, 2, 2) the centres are uncertain and the ranges linearised (module docstring)."""
    rho = disc_ranges(origin, angles, centre, radius)
    var = None if cov is None else range_variance(origin, angles, centre, radius, cov)
    return object_log_ratios(np.asarray(ranges, float), rho, model, var)
