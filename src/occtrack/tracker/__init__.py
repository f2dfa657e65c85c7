"""The Gaussian-mixture Poisson multi-Bernoulli box tracker with pluggable occlusion."""

from occtrack.config import OCCLUSION_NAMES, TrackerConfig
from occtrack.tracker.tracker import Tracker, TrackResult, Tracks

__all__ = ["OCCLUSION_NAMES", "TrackResult", "Tracker", "TrackerConfig", "Tracks"]
