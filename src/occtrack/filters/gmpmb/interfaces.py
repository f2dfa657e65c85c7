"""What the filter asks of a measurement model and a birth model: the seams along which one
Poisson multi-Bernoulli filter serves several sensors (DESIGN section 3: "one filter, several
measurement models"). The box tracker's are `occtrack.models.box.BoxMeasurement` and the
image-edge births built from `TrackerConfig` (`occtrack.models.birth.EdgeBirths` and the
learnt size prior, kept inside the filter); the lidar scan tracker's are
`occtrack.models.scan_segments.ScanMeasurement` and `ScanBirths`.

The filter's state per component is (2, 3): per axis (centre, velocity, half-size), in the
model's frame (`region_size`: components whose centre leaves [0, W] x [0, H] take
`exit_survival`). A step's measurements `z` are whatever the model gives meaning to (box edges
(M, 2, 2), segments of a scan); the filter only takes `len(z)` and hands `z` back to the model,
and to the occlusion model through `OcclusionContext.measurements`.

Three methods are optional (the filter calls them where the model has them):
`tracked_components(labelled)` before a frame's likelihoods, with `labelled` (K,) bool marking
the components of tracked objects (the rest are the Poisson part), for a model whose likelihood
differs between them; `learn_association(label, taken, confirmed, dt)` after the frame's
association, for a model that learns from the detections the tracks took (the box model's heavy
tail does both, `occtrack.models.edge_tail`); and `in_view(means)` (K,) bool after the
prediction, for a sensor that sees less than the region (a lidar's beams span and range,
`occtrack.models.scan_segments`): a component out of view takes `exit_survival`, as one out of
the region does.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np


class MeasurementModel(Protocol):
    """p(z_j | x_k) of the standard model (each object makes at most one measurement), the
    clutter density kappa p_F(z_j), gating, and the update of a component by a measurement.

    Only ratios between the weights of one measurement matter to the association (loopy BP's
    marginals, the new Bernoulli's existence and the children's masses are unchanged when
    p(z_j | x_k) of every k and kappa p_F(z_j) are multiplied by one constant c_j), so a model
    may give both in units of its own choosing per measurement."""

    region_size: np.ndarray

    def observed(self, z: Any) -> Any:
        """What of each measurement was measured (boxes: the edges not on the border); handed
        back to every other call."""

    def learn(self, z: Any, observed: Any) -> None:
        """Learn what the model learns online from a step's measurements."""

    def innovation(self, means: np.ndarray, covs: np.ndarray) -> tuple[Any, Any]:
        """The predicted measurements of every component, (zhat, S), in the model's terms."""

    def gates(self, zhat: Any, S: Any, sigmas: float) -> np.ndarray:
        """Each component's gate (K, 2, 2): an axis-aligned box that every measurement it can
        take overlaps."""

    def gate_boxes(self, z: Any, observed: Any) -> np.ndarray:
        """Each measurement's extent (M, 2, 2) for the gates."""

    def loglik_pairs(self, means: np.ndarray, zhat: Any, S: Any, z: Any, observed: Any,
                     k: np.ndarray, j: np.ndarray) -> np.ndarray:
        """log p(z_j | component k) of the pairs (k[e], j[e])."""

    def clutter_density(self, z: Any, observed: Any, scores: np.ndarray) -> np.ndarray:
        """kappa p_F(z_j) of each measurement (M,), in the units of `loglik_pairs`."""

    def update_rows(self, means: np.ndarray, covs: np.ndarray, rows: np.ndarray, z: Any,
                    observed: Any, measurement: np.ndarray) -> None:
        """In place: component rows[i] updated by measurement measurement[i]."""


class BirthModel(Protocol):
    """The Poisson part's new components of a step."""

    def components(self, z: Any, observed: Any, dt: float,
                   step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Masses (B,), means (B, 2, 3) and covariances (B, 2, 3, 3) of the births of a step of
        dt seconds (step: steps taken before this one) with measurements z."""
