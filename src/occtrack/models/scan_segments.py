"""A 2-D lidar scan as measurements for the one PMB filter (issue 24, item 2): segments of
neighbouring beams, each one detection of at most one disc, scored with section V's per-beam
likelihood (`occtrack.models.scan`) extended to objects with extent.

Segments. The returns of a scan are cut into runs of beams, in angular order, whose ranges
differ by less than `jump` (+ 4 sigma) from one returned beam to the next, with at most `gap`
beams without a return between them (a beam's own miss does not split a person); a 360-degree
scan's last run joins its first across the wrap. Each run is one measurement z_j: the standard
model (an object makes at most one measurement) at the segment level.

The disc a segment fits. For each segment the centre c_j of a disc of the known radius a
that best fits its points (Gauss-Newton on sum (|p_b - c| - a)^2; a one-beam segment's disc
sits right behind its point): where births go, and where each (component, segment) pair's
ranges are first linearised, rho_b(c) ~ rho_b(c_j) + H_b (c - c_j), H_b = d rho_b / d c
(`scan_geometry`'s gradient), on the segment's beams that meet that disc at a slope up to
`MAX_SLOPE` (the hit beams; the grazing ones, whose slope has no bound, are left out). The
pair then iterates (an iterated EKF, `pair_fit`): linearised again at the posterior centre,
`ITERATIONS` times, c_j below standing for the last point. A segment of one or two beams says
little across the beams, and its own disc, centred on them, can lie far across from where the
object is; linearised there, an update would drag a track sideways.

The (component, segment) likelihood, against clutter on every beam (the units of
`models.scan`: the ratio Lambda of each beam to clutter alone):

    log p(z_j | x_k) = n_j log(P_D / kappa)
                       + log N(z_j; rho(c_j) + H (m_k - c_j), H P_k H' + sigma^2 I)
                       + sum over the other beams b that may reach the disc of log m_b,

- the hit beams: the fit beams of the segment, their ranges jointly Gaussian given the
  component's centre N(m_k, P_k): with P_k = 0 and m_k = c_j it is sum log g_b, g_b =
  P_D N(z_b; rho_b, sigma^2) / kappa of `models.scan.beam_terms`; with an uncertain centre it is
  the exact Gaussian integral of the linearised ranges (the expectation of the product over
  beams, not the product of per-beam expectations, which would charge an uncertain track once
  a beam, n_j times, for the same two unknown coordinates);
- every other beam that may reach the disc where the hit beams put it (the centre's
  posterior given them, which is what the product over the other beams is conditioned on), by
  its return, m_b = 1 - P_D Phi((z_b -
  rho_b) / s_b), s_b^2 = sigma^2 + H_b P_k H_b' (`models.scan.beam_terms` with
  `range_variance`): a return well beyond the disc, or none, is a beam that passed through
  where the object would be (about 1 - P_D: negative information); a return well short of it
  hides it (about 1: no information); beams that miss the disc are factor 1. Whether a beam
  reaches the disc is uncertain with the centre: with reach_b = P(the beam's line passes
  within a of the centre) the factor is 1 - reach_b (1 - m_b), m_b itself for a beam through
  a known disc. (Decided at the mean instead, one beam at the edge of a hidden track's disc
  that passes its occluder turns "hidden" into "passed" and kills the track.)

Closed form per pair: with A_j = sum H_b' H_b, the residuals e_b = z_b - rho_b(c_j), d = m_k -
c_j, b = H' e - A d and E = |e - H d|^2, the quadratic is (E - b' (sigma^2 I + P A)^-1 P b) /
sigma^2 and log det S = n log sigma^2 + log det(I + P A / sigma^2) (Woodbury), so a pair costs
a 2 x 2 solve. The update of component k by segment j is the Kalman update of the same
linear-Gaussian model (`update_rows`), the (x, y) cross-covariance it creates dropped (the
filter keeps the axes as independent blocks).

Only ratios within one segment matter to the association (`filters.gmpmb.interfaces`): each
segment's log-likelihoods are shifted by minus the best of its pairs, and its clutter density
(Lambda = 1 for clutter on every beam) by the same amount, so a 60-beam segment's e^600
neither overflows nor sends the clutter to zero. The shift is found in `loglik_pairs` and kept
on the segments, which the filter asks for `clutter_density` afterwards.

The filter's frame: centimetres, origin at the corner of the square [-R, R]^2 about the
sensor's position at the start (R = max_range), so that the box tracker's units (lengths in
object sizes, a smallest size of 4 px) serve unchanged; `to_world` / `to_filter` convert.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

# _gaussian_hits: log N(z_j; rho(c_j) + H (m - c_j), H P H' + sigma^2 I) per pair from the
# segment's fit statistics (A = H'H, Hr = H'e, rr = e'e, n beams), the component's centre m
# and covariance P (the Woodbury forms of the module docstring), and the centre's posterior
# given the hit beams, m + w and P - (sigma^2 I + P A)^-1 P A P (compiled: numpy's per-pair
# 2 x 2 algebra was a sixth of the time on a real robot's scans)
from occtrack.models._models import _gaussian_hits, _linearise, _other_beams
from occtrack.models.beam import BeamModel

ITERATIONS = 3  # iterated EKF: linearisations a (component, segment) pair
MAX_SLOPE = 5.0  # hit beams: |d rho / d c| across the beam at most this
SPREAD = 6.0  # beams looked at: the disc's span widened by this many centre deviations
RADIUS_VAR = 1e-6  # (filter units^2) a disc's radius is known; a small variance keeps P regular


@dataclass
class Segments:
    """One scan cut into segments. Beams (B,): world angles, ranges (inf: none; a beam
    without a return that a segment bridges takes its neighbours' mean), origin (2,).
    Segment j holds beams beam[start[j]:start[j + 1]]; centre (M, 2) the disc it fits; per
    segment the fit statistics of its hit beams (`fit_beam` marks them, flat like `beam`):
    n (M,), A (M, 2, 2), Hr (M, 2), rr (M,); box (M, 2, 2) the extent of its points in the
    filter frame; offset (M,) the shift of its log-likelihoods (set by `loglik_pairs`)."""

    origin: np.ndarray
    angle: np.ndarray
    range: np.ndarray
    beam: np.ndarray
    start: np.ndarray
    centre: np.ndarray
    fit_beam: np.ndarray
    n: np.ndarray
    A: np.ndarray
    Hr: np.ndarray
    rr: np.ndarray
    box: np.ndarray
    segment_of_beam: np.ndarray
    offset: np.ndarray = field(default_factory=lambda: np.zeros(0))
    static: np.ndarray | None = None  # (M,) the probability each is static scene, if known
    clutter_log: np.ndarray | None = None  # (M,) log of its clutter against the uniform model

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """The returns of the segments in the world (P, 2) and the segment of each (P,)."""
        r = self.range[self.beam]
        u = np.c_[np.cos(self.angle[self.beam]), np.sin(self.angle[self.beam])]
        keep = np.isfinite(r)  # (a bridged beam without a return has its neighbours' mean)
        seg = np.repeat(np.arange(len(self)), np.diff(self.start))
        return self.origin + r[keep][:, None] * u[keep], seg[keep]

    def __len__(self) -> int:
        return len(self.start) - 1

    @property
    def size(self) -> np.ndarray:
        """Beams a segment (M,)."""
        return np.diff(self.start)


def cut(angle: np.ndarray, ranges: np.ndarray, sigma: float, jump: float,
        gap: int) -> tuple[np.ndarray, np.ndarray]:
    """(beam, start): the returned beams in segment order and the segments' offsets into it.
    Angles must be sorted; a scan spanning 360 degrees joins across the wrap."""
    B = len(angle)
    idx = np.flatnonzero(np.isfinite(ranges))
    if len(idx) == 0:
        return idx, np.zeros(1, np.int64)
    z = ranges[idx]
    limit = jump + 4.0 * sigma
    breaks = (np.diff(idx) - 1 > gap) | (np.abs(np.diff(z)) > limit)
    start = np.r_[0, np.flatnonzero(breaks) + 1, len(idx)]
    step = (angle[-1] - angle[0]) / max(B - 1, 1)
    full_circle = B > 1 and abs(angle[-1] - angle[0] + step - 2 * np.pi) < 0.5 * step
    if full_circle and len(start) > 2:
        wrap_gap = B - 1 - idx[-1] + idx[0]
        if wrap_gap <= gap and abs(z[-1] - z[0]) <= limit:
            # the last segment joins the first: put its beams in front
            last = start[-2]
            idx = np.r_[idx[last:], idx[:last]]
            start = np.r_[0, start[1:-2] + (len(idx) - last), len(idx)]
    return idx.astype(np.int64), start.astype(np.int64)


def beams_in_arcs(angle: np.ndarray, low: np.ndarray, high: np.ndarray):
    """Flat (arc, beam) of the beams (sorted world angles) inside each arc [low, high]
    (radians, at most half a turn wide; an empty arc has high < low), the arcs taken modulo a
    turn."""
    turn = 2.0 * np.pi
    base = np.floor((low - angle[0]) / turn) * turn if len(angle) else low * 0
    ks, bs = [], []
    for shift in (0.0, turn, 2 * turn):
        lo = np.searchsorted(angle, low - base + shift - turn, side="left")
        hi = np.searchsorted(angle, high - base + shift - turn, side="right")
        count = np.maximum(hi - lo, 0)
        k = np.repeat(np.arange(len(low)), count)
        first = np.repeat(lo - (np.cumsum(count) - count), count)
        ks.append(k)
        bs.append(first + np.arange(int(count.sum())))
    k, b = np.concatenate(ks), np.concatenate(bs)
    order = np.lexsort((b, k))
    return k[order], b[order].astype(np.int64)


def _disc_hits(origin, u, centre, radius):
    """Per beam (rows of u) and its disc centre (rows of centre): range rho to the near surface,
    gradient H (d rho / d c) and whether the beam meets it at a slope <= MAX_SLOPE."""
    n = np.c_[-u[:, 1], u[:, 0]]
    p = centre - origin
    t_c = np.sum(u * p, axis=1)
    d = np.sum(n * p, axis=1)
    half2 = radius**2 - d**2
    half = np.sqrt(np.maximum(half2, 0.0))
    rho = t_c - half
    slope = np.divide(d, half, out=np.full_like(d, np.inf), where=half > 0)
    ok = (half2 > 0) & (rho > 0) & (np.abs(slope) <= MAX_SLOPE)
    H = u + np.where(ok, slope, 0.0)[:, None] * n
    return rho, H, ok


class ScanMeasurement:
    """The scan measurement model for `GaussianMixturePMB` (`filters.gmpmb.interfaces`):
    discs of `radius` m seen by `beam` (P_D, sigma, clutter per beam, max range)."""

    def __init__(self, beam: BeamModel, radius: float, jump: float = 0.3, gap: int = 1,
                 unit: float = 100.0, origin: tuple[float, float] = (0.0, 0.0)):
        self.beam = beam
        self.radius = float(radius)
        self.jump, self.gap = float(jump), int(gap)
        self.unit = float(unit)
        R = beam.max_range
        self.corner = np.asarray(origin, float) - R  # world point at the filter's (0, 0)
        self.region_size = np.full(2, 2.0 * R * self.unit)
        self.view: tuple[np.ndarray, float, float, bool] | None = None  # the last scan's

    def recentre(self, sensor: npt.ArrayLike) -> np.ndarray:
        """Put the filter's square about `sensor` (world, m), so that the survival region
        goes where the sensor goes; returns the shift (2,) that carries a point of the old
        filter frame into the new one (filter units), for `GaussianMixturePMB.move_image`."""
        corner = np.asarray(sensor, float) - self.beam.max_range
        shift = (self.corner - corner) * self.unit
        self.corner = corner
        return shift

    def in_view(self, means: np.ndarray) -> np.ndarray:
        """Whether each filter state's centre (K,) lies in the last scan's field of view:
        nearer than max_range and within the beams' angular span (all when no scan has been
        seen). The filter's optional survival hook (`filters.gmpmb.interfaces`): a disc whose
        centre leaves the view is gone from this sensor, as a box whose centre leaves the
        image is, and takes `exit_survival`; so no track is reported where no beam looks."""
        return self.sees(self.to_world(means)[0])

    def sees(self, points: np.ndarray) -> np.ndarray:
        """Whether each world point (K, 2) lies in the last scan's field of view (`in_view`)."""
        if self.view is None:
            return np.ones(len(points), dtype=bool)
        origin, low, high, round_ = self.view
        p = np.asarray(points, float).reshape(-1, 2) - origin
        near = np.hypot(p[:, 0], p[:, 1]) < self.beam.max_range
        if round_:
            return near
        off = np.abs(np.angle(np.exp(1j * (np.arctan2(p[:, 1], p[:, 0]) - (low + high) / 2))))
        return near & (off <= (high - low) / 2)

    # -- frames ---------------------------------------------------------------------------

    def to_world(self, means: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centres (K, 2) and velocities (K, 2) in the world (m, m/s) of filter states."""
        return (means[:, :, 0] / self.unit + self.corner, means[:, :, 1] / self.unit)

    def centre_covariance(self, covs: np.ndarray) -> np.ndarray:
        """World centre covariances (K, 2, 2), m^2 (the axes are independent blocks)."""
        out = np.zeros((len(covs), 2, 2))
        out[:, 0, 0] = covs[:, 0, 0, 0]
        out[:, 1, 1] = covs[:, 1, 0, 0]
        return out / self.unit**2

    def to_filter(self, centre: np.ndarray) -> np.ndarray:
        """World points (..., 2) in the filter frame."""
        return (np.asarray(centre, float) - self.corner) * self.unit

    # -- segments -------------------------------------------------------------------------

    def segments(self, angle: np.ndarray, ranges: np.ndarray,
                 origin: np.ndarray = (0.0, 0.0)) -> Segments:
        """A scan (world angles sorted, ranges with inf for none, sensor at `origin`) as
        segments, each with the disc it fits and that fit's statistics."""
        # contiguous: the compiled kernels read the scan through pointers
        angle, origin = np.ascontiguousarray(angle, float), np.ascontiguousarray(origin, float)
        if len(angle) > 1:  # the field of view: the beams' span (all round when it closes)
            step = (angle[-1] - angle[0]) / (len(angle) - 1)
            self.view = (origin.copy(), float(angle[0]), float(angle[-1]),
                         bool(angle[-1] - angle[0] + 1.5 * step >= 2 * np.pi))
        ranges = np.where(np.asarray(ranges, float) < self.beam.max_range, ranges, np.inf)
        beam, start = cut(angle, ranges, self.beam.sigma, self.jump, self.gap)
        M = len(start) - 1
        seg = np.repeat(np.arange(M), np.diff(start))
        u = np.c_[np.cos(angle[beam]), np.sin(angle[beam])]
        z = ranges[beam]
        points = origin + z[:, None] * u
        centre = _fit_discs(points, seg, M, origin, self.radius)
        rho, H, ok = _disc_hits(origin, u, centre[seg], self.radius)
        e = np.where(ok, z - rho, 0.0)
        Hok = np.where(ok[:, None], H, 0.0)
        n = np.bincount(seg, weights=ok.astype(float), minlength=M)
        A = np.zeros((M, 2, 2))
        for a in range(2):
            for b in range(2):
                A[:, a, b] = np.bincount(seg, weights=Hok[:, a] * Hok[:, b], minlength=M)
        Hr = np.stack([np.bincount(seg, weights=Hok[:, a] * e, minlength=M)
                       for a in range(2)], axis=1)
        rr = np.bincount(seg, weights=e * e, minlength=M)
        pf = self.to_filter(points)
        box = np.zeros((M, 2, 2))
        if M:
            for a in range(2):
                box[:, a, 0] = np.minimum.reduceat(pf[:, a], start[:-1])
                box[:, a, 1] = np.maximum.reduceat(pf[:, a], start[:-1])
        of_beam = np.full(len(angle), -1, np.int64)
        of_beam[beam] = seg
        filled = ranges.copy()
        _fill_bridged(filled, of_beam, beam, seg)
        return Segments(origin, angle, filled, beam, start, centre, ok, n, A, Hr, rr, box,
                        of_beam, np.zeros(M))

    # -- the filter's interface -----------------------------------------------------------

    def observed(self, z: Segments) -> np.ndarray:
        return np.ones(len(z), dtype=bool)

    def learn(self, z: Segments, observed: np.ndarray) -> None:
        pass

    def innovation(self, means: np.ndarray, covs: np.ndarray):
        """World centres (K, 2) and their covariances (K, 2, 2)."""
        return self.to_world(means)[0], self.centre_covariance(covs)

    def gates(self, zhat: np.ndarray, S: np.ndarray, sigmas: float) -> np.ndarray:
        """The disc widened by `sigmas` centre standard deviations, filter frame (K, 2, 2)."""
        sd = np.sqrt(np.stack([S[:, 0, 0], S[:, 1, 1]], axis=1))
        reach = (self.radius + sigmas * sd) * self.unit
        c = self.to_filter(zhat)
        return np.stack([c - reach, c + reach], axis=-1)

    def gate_boxes(self, z: Segments, observed: np.ndarray) -> np.ndarray:
        return z.box

    def component_beams(self, centre: np.ndarray, cov: np.ndarray, z: Segments):
        """The beams that may reach each disc (centre (K, 2) world, covariance (K, 2, 2)):
        flat (k, beam, rho, range variance H P H', reach). reach = P(|d| < a) for the
        beam's signed distance d ~ N(n.(c - o), n' P n) from the centre (1 or 0 for a known
        centre); rho and H at the mean, on a beam that misses the mean disc at its closest
        approach. The beams looked at are those within the disc's angular half-width widened
        by SPREAD centre standard deviations. (The array form of what `raw_loglik` and the
        scan occlusion compute in compiled loops.)"""
        origin = z.origin
        p = centre - origin
        dist = np.hypot(p[:, 0], p[:, 1])
        bearing = np.arctan2(p[:, 1], p[:, 0])
        spread = SPREAD * np.sqrt(np.maximum(cov[:, 0, 0], cov[:, 1, 1]))
        half = np.arcsin(np.clip((self.radius + spread) / np.maximum(dist, 1e-9), 0.0, 1.0))
        half = np.where(dist - self.radius < self.beam.max_range, half, -1.0)
        k, b = beams_in_arcs(z.angle, bearing - half - 1e-9, bearing + half + 1e-9)
        u = np.c_[np.cos(z.angle[b]), np.sin(z.angle[b])]
        nvec = np.c_[-u[:, 1], u[:, 0]]
        pk = centre[k] - origin
        t_c = np.sum(u * pk, axis=1)
        d = np.sum(nvec * pk, axis=1)
        half_chord = np.sqrt(np.maximum(self.radius**2 - d**2, 0.0))
        rho = t_c - half_chord
        slope = np.divide(d, half_chord, out=np.zeros_like(d), where=half_chord > 0)
        H = u + slope[:, None] * nvec
        lateral = np.sqrt(np.einsum("pi,pij,pj->p", nvec, cov[k], nvec))
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = (ndtr((self.radius - d) / lateral) - ndtr((-self.radius - d) / lateral))
        exact = (np.abs(d) < self.radius).astype(float)
        reach = np.where(lateral > 0, reach, exact)
        live = (rho > 0) & (reach > 1e-12)
        k, b, rho, H, reach = k[live], b[live], rho[live], H[live], reach[live]
        var = np.einsum("pi,pij,pj->p", H, cov[k], H)
        return k, b, rho, var, reach

    def loglik_pairs(self, means: np.ndarray, zhat: np.ndarray, S: np.ndarray, z: Segments,
                     observed: np.ndarray, k: np.ndarray, j: np.ndarray) -> np.ndarray:
        """log p(z_j | component k) of the pairs, shifted per segment (module docstring)."""
        k, j = np.asarray(k, np.int64), np.asarray(j, np.int64)
        raw = self.raw_loglik(zhat, S, z, k, j)
        M = len(z)
        best = np.full(M, -np.inf)
        np.maximum.at(best, j, raw)
        z.offset = np.where(np.isfinite(best), -best, 0.0)
        return raw + z.offset[j]

    def linearise(self, at: np.ndarray, z: Segments, j: np.ndarray):
        """The fit statistics (A = H'H, Hr = H'e, rr = e'e, n) of segment j[e]'s beams for a
        disc at `at[e]` (P, 2): the beams that meet it at a slope <= MAX_SLOPE, their ranges
        linearised there (rho(c) ~ rho(at) + H (c - at), e = z - rho(at))."""
        return _linearise(np.ascontiguousarray(at, float), np.ascontiguousarray(j, np.int64),
                          z.start, z.beam, z.angle, z.range, z.origin, self.radius, MAX_SLOPE)

    def pair_fit(self, centre: np.ndarray, cov: np.ndarray, z: Segments, j: np.ndarray):
        """Per pair (component centre (P, 2), covariance (P, 2, 2), segment j (P,)): the
        iterated extended Kalman fit of the disc to the segment's ranges, linearised first at
        the segment's own disc, then at each posterior mean in turn (`ITERATIONS` times: a
        small segment's own disc is ambiguous across the beam, and the component's prior
        settles where along the beam's edge the disc lies). Returns the linearisation point,
        its statistics (A, Hr, rr, n), log N of the hit beams and the centre's posterior."""
        at = z.centre[j]
        sigma2 = self.beam.sigma**2
        for _ in range(ITERATIONS):
            stats = self.linearise(at, z, j)
            log_n, post, post_cov = _gaussian_hits(centre, cov, at, *stats, sigma2)
            last = at
            at = post
        return last, stats, log_n, post, post_cov

    def raw_loglik(self, centre: np.ndarray, cov: np.ndarray, z: Segments, k: np.ndarray,
                   j: np.ndarray) -> np.ndarray:
        """The unshifted log p(z_j | x_k) of the pairs (k[e], j[e]): the hit beams' Gaussian
        plus the log m_b of the component's other beams (module docstring)."""
        model = self.beam
        _, stats, log_hit, post, post_cov = self.pair_fit(centre[k], cov[k], z, j)
        log_hit = log_hit + stats[3] * np.log(model.p_d / model.kappa)
        # the component's other beams, where the hit beams put it: each pair's posterior disc
        # (`component_beams` and `beam_terms` in one compiled loop)
        other = _other_beams(post, post_cov, np.asarray(j, np.int64), z.origin, z.angle,
                             z.range, z.segment_of_beam, self.radius, model.max_range,
                             model.p_d, model.sigma, SPREAD)
        return log_hit + other

    def clutter_density(self, z: Segments, observed: np.ndarray,
                        scores: np.ndarray) -> np.ndarray:
        """Clutter on every beam is Lambda = 1 (times the clutter map's ratio, when the
        segments carry one: `models.clutter_map`); shifted as the segment's log-likelihoods."""
        log = z.offset if len(z.offset) == len(z) else np.zeros(len(z))
        if z.clutter_log is not None:
            log = log + z.clutter_log
        return np.exp(np.clip(log, -700.0, 700.0))

    def update_rows(self, means: np.ndarray, covs: np.ndarray, rows: np.ndarray, z: Segments,
                    observed: np.ndarray, measurement: np.ndarray) -> None:
        """Kalman update, in place, of component rows[i] by segment measurement[i], with the
        ranges linearised where `pair_fit` settles (module docstring), in world units."""
        rows = np.asarray(rows, np.int64)
        j = np.asarray(measurement, np.int64)
        if len(rows) == 0:
            return
        sigma2 = self.beam.sigma**2
        centre, _ = self.to_world(means[rows])
        P = self.centre_covariance(covs[rows])
        at, (A, Hr, rr, _), _, _, _ = self.pair_fit(centre, P, z, j)
        d = centre - at
        b = Hr - np.einsum("pij,pj->pi", A, d)
        M2 = sigma2 * np.eye(2) + P @ A
        w = np.linalg.solve(M2, np.einsum("pij,pj->pi", P, b)[..., None])[..., 0]
        g = (b - np.einsum("pij,pj->pi", A, w)) / sigma2  # H' S^-1 e (m^-1)
        X = (A - A @ np.linalg.solve(M2, P @ A)) / sigma2  # H' S^-1 H (m^-2)
        u2 = self.unit**2
        for axis in range(2):
            C = covs[rows, axis, :, 0]  # P[:, position] of this axis, filter units
            means[rows, axis] += C * (g[:, axis] * self.unit)[:, None] / u2
            covs[rows, axis] -= (X[:, axis, axis] / u2)[:, None, None] * (
                C[:, :, None] * C[:, None, :])


def _fill_bridged(ranges: np.ndarray, of_beam: np.ndarray, beam: np.ndarray,
                 seg: np.ndarray) -> None:
    """In place: a beam without a return that a segment bridges (between two of its returns)
    takes the mean of their ranges and the segment's index. It is read as the surface's own
    missed return (a scene whose surfaces are opaque: a missed beam still hides what is
    behind), not as a beam that passed through everything."""
    B = len(ranges)
    if len(beam) < 2:
        return
    same = seg[1:] == seg[:-1]
    step = (beam[1:] - beam[:-1]) % B
    i = np.flatnonzero(same & (step > 1))
    if len(i) == 0:
        return
    count = step[i] - 1
    first = np.repeat(beam[i] + 1, count)
    offset = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    where = (first + offset) % B
    ranges[where] = np.repeat(0.5 * (ranges[beam[i]] + ranges[beam[i + 1]]), count)
    of_beam[where] = np.repeat(seg[i], count)


def _fit_discs(points: np.ndarray, seg: np.ndarray, M: int, origin: np.ndarray,
               radius: float, iterations: int = 6) -> np.ndarray:
    """The centre (M, 2) of the disc of `radius` that best fits each segment's points (least
    squares of |p - c| - a), from the points' mean pushed back by a along its bearing; a small
    ridge keeps a one-beam segment's disc where it starts."""
    if M == 0:
        return np.zeros((0, 2))
    count = np.bincount(seg, minlength=M)
    mean = np.stack([np.bincount(seg, weights=points[:, a], minlength=M) for a in range(2)],
                    axis=1) / np.maximum(count, 1)[:, None]
    out = mean - origin
    c = mean + radius * out / np.maximum(np.hypot(out[:, 0], out[:, 1]), 1e-9)[:, None]
    ridge = 1e-3
    for _ in range(iterations):
        diff = points - c[seg]
        dist = np.maximum(np.hypot(diff[:, 0], diff[:, 1]), 1e-9)
        r = dist - radius
        J = -diff / dist[:, None]  # d r / d c
        JJ = np.zeros((M, 2, 2))
        for a in range(2):
            for b in range(2):
                JJ[:, a, b] = np.bincount(seg, weights=J[:, a] * J[:, b], minlength=M)
        Jr = np.stack([np.bincount(seg, weights=J[:, a] * r, minlength=M) for a in range(2)],
                      axis=1)
        step = np.linalg.solve(JJ + ridge * np.eye(2), -Jr[..., None])[..., 0]
        c = c + step
    return c


class ScanBirths:
    """Births where a segment is (`filters.gmpmb.interfaces.BirthModel`): each segment of at
    least `min_beams` beams adds a Poisson component at the disc it fits (still, `position_std`
    m and `speed_std` m/s about it), of mass `mass` (`edge_mass` within `edge_width` m of the
    sensor's max range, where objects walk in; `initial_mass` at the first scan), times the
    probability that the segment is not static scene where the tracker keeps a map of it
    (`Segments.static`, `models.static_scene`). A birth costs nothing where an object already
    explains the segment: loopy BP gives the segment to it, and the birth's miss child,
    unlabelled, fades."""

    def __init__(self, model: ScanMeasurement, mass: float, edge_mass: float,
                 initial_mass: float, edge_width: float, position_std: float,
                 speed_std: float, min_beams: int = 2):
        self.model = model
        self.mass, self.edge_mass, self.initial_mass = mass, edge_mass, initial_mass
        self.edge_width = edge_width
        self.position_std, self.speed_std = position_std, speed_std
        self.min_beams = int(min_beams)

    def components(self, z: Segments, observed, dt: float, step: int):
        keep = np.flatnonzero(z.size >= self.min_beams)
        K = len(keep)
        model = self.model
        centre = z.centre[keep]
        dist = np.hypot(*(centre - z.origin).T) if K else np.zeros(0)
        edge = dist > model.beam.max_range - self.edge_width
        mass = np.where(edge, self.edge_mass, self.mass)
        if step == 0:
            mass = np.full(K, self.initial_mass)
        if z.static is not None:  # a person is born where something moved (`static_scene`)
            mass = mass * (1.0 - z.static[keep])
        means = np.zeros((K, 2, 3))
        means[:, :, 0] = model.to_filter(centre)
        means[:, :, 2] = model.radius * model.unit
        covs = np.zeros((K, 2, 3, 3))
        for axis in range(2):
            covs[:, axis, 0, 0] = (self.position_std * model.unit) ** 2
            covs[:, axis, 1, 1] = (self.speed_std * model.unit) ** 2
            covs[:, axis, 2, 2] = RADIUS_VAR
        return mass, means, covs
