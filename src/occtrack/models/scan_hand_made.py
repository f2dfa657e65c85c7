"""The hand-made scan likelihood (issue 24, baselines): the same segments and the same filter
as `occtrack.models.scan_segments`, with the derived other-beam term replaced by the fixed
shape of Thrun et al.'s beam model as the separable-likelihood people trackers use it
("near: high, beyond: low, closer: uniform").

    log p(z_j | x_k) = the hit beams' Gaussian (unchanged: the "near: high" part)
                       + sum over the other beams b through the disc at the pair's mean of
                         log f(z_b - rho_b),

    f = PASSED (a fixed low factor)  the return is more than BAND sigma beyond the disc's near
                                     surface, or there is none: the beam passed through
                                     where the object would be;
    f = 1                            otherwise: a return closer (short: it hides the object,
                                     no information, "uniform") or near the surface (that
                                     beam is another segment's measurement, not this one's).

What it leaves out of the derived term: the factor's size comes from a chosen constant, not
from P_D (1 - P_D Phi), and the regime is decided at the mean disc (whether beam b crosses it,
where its surface is), not integrated over the centre's uncertainty (reach_b, s_b). PASSED
and BAND are set once, here, and not fitted to the walkway.

Occlusion: the hand-made trackers carry occlusion only inside the likelihood (the "closer:
uniform" regime); their miss has no hidden term. `ScanTrackerConfig(likelihood="hand-made")`
is run with occlusion "none" (q = 0) by `occtrack reproduce lidar`; the config allows either.
"""

from __future__ import annotations

import numpy as np

from occtrack.models._models import _other_beams_hand_made
from occtrack.models.scan_segments import ScanMeasurement

PASSED = 0.1  # the factor of a beam that passed through the disc
BAND = 3.0  # range-noise standard deviations: "near" the disc's surface


def hand_made_factor(z: np.ndarray, rho: np.ndarray, sigma: float, max_range: float,
                     passed: float = PASSED, band: float = BAND) -> np.ndarray:
    """f per beam (array form of the compiled loop): `passed` when the return z (inf or >=
    max_range: none) lies more than band sigma beyond rho, else 1."""
    z = np.where(np.asarray(z, float) < max_range, z, max_range)
    return np.where(z - np.asarray(rho, float) > band * sigma, passed, 1.0)


class HandMadeScanMeasurement(ScanMeasurement):
    """`ScanMeasurement` with the hand-made other-beam factor (module docstring)."""

    passed = PASSED
    band = BAND

    def raw_loglik(self, centre: np.ndarray, cov: np.ndarray, z, k: np.ndarray,
                   j: np.ndarray) -> np.ndarray:
        model = self.beam
        _, stats, log_hit, post, _ = self.pair_fit(centre[k], cov[k], z, j)
        log_hit = log_hit + stats[3] * np.log(model.p_d / model.kappa)
        other = _other_beams_hand_made(post, np.asarray(j, np.int64), z.origin, z.angle,
                                       z.range, z.segment_of_beam, self.radius,
                                       model.max_range, model.sigma, self.passed, self.band)
        return log_hit + other
