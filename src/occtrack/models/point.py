"""Point measurements for the one PMB filter: the cluster-then-track baseline of the lidar
scan tracker (issue 24). Each scan's returns are clustered into the segments of
`occtrack.models.scan_segments` (the same cut: range jumps, gaps), each cluster reduced to one
point, the centre of the disc its returns fit (`Segments.centre`), and the points are tracked
with a linear-Gaussian model:

    p(z_j | x_k) = N(z_j; c_k, P_k + r^2 I),   c_k, P_k the component's centre and its
                                                covariance (world, m), r = `noise` m;

clutter kappa p_F(z) = clutter_per_scan / (pi R^2): the scan's spurious returns, each a
cluster of its own, spread evenly over the sensor's disc of range R. The update is the Kalman
update of the same model, per axis (the filter keeps the axes as independent blocks). Nothing
of the beams reaches the filter: a cluster says where something is, not where nothing is.

The filter's frame, births (`ScanBirths`, at the clusters) and the conversions are the scan
model's; only the measurement model differs.
"""

from __future__ import annotations

import numpy as np

from occtrack.models.beam import BeamModel
from occtrack.models.scan_segments import ScanMeasurement, Segments

LOG_2PI = float(np.log(2 * np.pi))


class PointMeasurement(ScanMeasurement):
    """Clusters of a scan as points, N(z; centre, P + noise^2 I) (module docstring)."""

    def __init__(self, beam: BeamModel, radius: float, noise: float, clutter_per_scan: float,
                 jump: float = 0.3, gap: int = 1, unit: float = 100.0,
                 origin: tuple[float, float] = (0.0, 0.0)):
        super().__init__(beam, radius, jump, gap, unit, origin)
        self.noise = float(noise)
        self.clutter = float(clutter_per_scan) / (np.pi * beam.max_range**2)

    def points(self, z: Segments) -> np.ndarray:
        """The clusters' points (M, 2), world."""
        return z.centre

    def innovation(self, means: np.ndarray, covs: np.ndarray):
        """Predicted points (K, 2) and their covariances P + r^2 I (K, 2, 2), world."""
        centre, P = super().innovation(means, covs)
        return centre, P + self.noise**2 * np.eye(2)

    def gates(self, zhat: np.ndarray, S: np.ndarray, sigmas: float) -> np.ndarray:
        sd = np.sqrt(np.stack([S[:, 0, 0], S[:, 1, 1]], axis=1))
        c = self.to_filter(zhat)
        reach = sigmas * sd * self.unit
        return np.stack([c - reach, c + reach], axis=-1)

    def gate_boxes(self, z: Segments, observed: np.ndarray) -> np.ndarray:
        p = self.to_filter(self.points(z))
        return np.stack([p, p], axis=-1)

    def loglik_pairs(self, means, zhat, S, z, observed, k, j) -> np.ndarray:
        k, j = np.asarray(k, np.int64), np.asarray(j, np.int64)
        return gaussian_loglik(self.points(z)[j], zhat[k], S[k])

    def clutter_density(self, z: Segments, observed, scores) -> np.ndarray:
        return np.full(len(z), self.clutter)

    def update_rows(self, means, covs, rows, z, observed, measurement) -> None:
        """Kalman update, in place, per axis, in the filter's units."""
        rows = np.asarray(rows, np.int64)
        if len(rows) == 0:
            return
        p = self.to_filter(self.points(z)[np.asarray(measurement, np.int64)])
        r2 = (self.noise * self.unit) ** 2
        for axis in range(2):
            P = covs[rows, axis]  # (n, 3, 3)
            s = P[:, 0, 0] + r2
            gain = P[:, :, 0] / s[:, None]
            innov = p[:, axis] - means[rows, axis, 0]
            means[rows, axis] += gain * innov[:, None]
            covs[rows, axis] = P - gain[:, :, None] * P[:, 0, None, :]


def gaussian_loglik(z: np.ndarray, mean: np.ndarray, S: np.ndarray) -> np.ndarray:
    """log N(z; mean, S) of rows (n, 2), S (n, 2, 2)."""
    r = z - mean
    w = np.linalg.solve(S, r[..., None])[..., 0]
    return -0.5 * (np.sum(r * w, axis=1) + np.log(np.linalg.det(S)) + 2 * LOG_2PI)
