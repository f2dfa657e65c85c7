"""Occlusion for the lidar scan tracker, behind the one interface (`occlusion.base`): what a
scan's nearer returns say about an object that made no segment.

Measurement-wise (paper section IV, deterministic restricted: a return hides everything
farther along its beam), at the segment level: object k's segment is hidden when every beam
that reaches its disc has its return short of the disc,

    q(c) = prod over the beams b through the disc at c of P(rho_b(c) + noise > z_b)
         = prod_b (1 - Phi((z_b - rho_b(c)) / sigma))

for a disc at a known centre c (section V's "short return" term per beam; a beam with no
return, or one beyond the disc, hides nothing: its factor is about 0; beams from
`ScanMeasurement.component_beams`), and q_k its expectation over the predicted centre by a
5 x 5 Gauss-Hermite grid. The beams of one disc are not independent: a product over beams of
per-beam expectations would have a track whose centre is uncertain by a few centimetres "seen
passing" on every beam at its edge. One clear beam through the disc makes q(c) about 0: an
object partly in view is expected to make a segment. The filter's miss term is then
1 - d + d o q_k (`occtrack.filters.gmpmb`), and the hidden share of a missed component's
density moves to where it could be hidden: the moments of p(x) q(x) / q_k on the same grid
(`OcclusionTerms.hidden_centre`), section V's "the object's density takes the miss branch".
`none`: q = 0.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from occtrack.occlusion._occlusion import _hidden_at
from occtrack.occlusion.base import NoOcclusion, OcclusionContext, OcclusionModel, OcclusionTerms

# Gauss-Hermite (probabilists'), 5 nodes an axis: exact to degree 9. (3 nodes put 1/6 of the
# mass at 1.7 standard deviations, where the true tail holds 4.5 %: a track near the edge of
# its cover was pulled back, and slowed, by a sixth of its mass every scan.)
_x, _w = np.polynomial.hermite_e.hermegauss(5)
NODES, WEIGHTS = tuple(_x), tuple(_w / _w.sum())


class ScanMeasurementWise:
    name = "measurement-wise"

    def terms(self, ctx: OcclusionContext) -> OcclusionTerms:
        K = len(ctx.means)
        model, z = ctx.measurement_model, ctx.measurements
        if K == 0:
            return OcclusionTerms(np.ones(0), np.zeros(0))
        centre, cov = model.innovation(ctx.means, ctx.covs)
        # the expectation over the centre by a 5 x 5 Gauss-Hermite grid (the axes are
        # independent blocks, so P is diagonal): at each node the disc is known, and so is
        # which beams reach it
        sd = np.sqrt(np.stack([cov[:, 0, 0], cov[:, 1, 1]], axis=1))
        nodes = np.array([(a, b) for a in NODES for b in NODES])
        weights = np.array([wa * wb for wa in WEIGHTS for wb in WEIGHTS])
        points = (centre[:, None, :] + nodes[None] * sd[:, None, :]).reshape(-1, 2)
        q_points = self.hidden_at(model, points, z).reshape(K, len(nodes))
        wq = q_points * weights
        q = wq.sum(axis=1)
        # the centre's moments given hidden, p(x) q(x) / q, on the same nodes
        share = wq / np.maximum(q, 1e-300)[:, None]
        xs = points.reshape(K, len(nodes), 2)
        mean_h = np.einsum("kn,kni->ki", share, xs)
        var_h = np.einsum("kn,kni->ki", share, (xs - mean_h[:, None, :]) ** 2)
        none = q < 1e-12
        mean_h[none], var_h[none] = centre[none], sd[none] ** 2
        return OcclusionTerms(np.ones(K), q, None, model.to_filter(mean_h),
                              var_h * model.unit**2)

    @staticmethod
    def hidden_at(model, centre: np.ndarray, z) -> np.ndarray:
        """q of discs at known centres (K, 2): prod over the beams through each of
        P(its return would lie beyond z_b) (none reached: 0, nothing hides it)."""
        beam = model.beam
        return _hidden_at(np.ascontiguousarray(centre, float), z.origin, z.angle, z.range,
                          beam.max_range, beam.sigma, model.radius)


SCAN_OCCLUSION_MODELS: dict[str, Callable[[], OcclusionModel]] = {
    "none": NoOcclusion,
    "measurement-wise": ScanMeasurementWise,
}


def scan_occlusion(name: str) -> OcclusionModel:
    """The scan occlusion model called `name` (one of SCAN_OCCLUSION_MODELS)."""
    try:
        return SCAN_OCCLUSION_MODELS[name]()
    except KeyError:
        raise ValueError(f"unknown scan occlusion model {name!r}; choose from "
                         f"{', '.join(SCAN_OCCLUSION_MODELS)}") from None
