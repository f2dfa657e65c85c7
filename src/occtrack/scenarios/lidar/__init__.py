"""Lidar: `beams`, the Monte Carlo check of section V's beam likelihood on single beams;
`scene`, a scanning sensor watching people walk past (`raycast` the geometry, `world` the
walkers). Names re-exported so `from occtrack.scenarios.lidar import ...` keeps working."""

from occtrack.scenarios.lidar.beams import (
    binned_ratio,
    empirical_ratio,
    probe_bins,
    simulate_beams,
)
from occtrack.scenarios.lidar.scene import (
    LidarScan,
    Occlusions,
    beam_angles,
    full_occlusions,
    simulate_scene,
)

__all__ = ["LidarScan", "Occlusions", "beam_angles", "binned_ratio", "empirical_ratio",
           "full_occlusions", "probe_bins", "simulate_beams", "simulate_scene"]
