"""The Gaussian-mixture Poisson multi-Bernoulli box tracker with pluggable occlusion."""

from occtrack.config import OCCLUSION_NAMES, TrackerConfig
from occtrack.tracker.boxes import BOX_FORMATS, BoxFormat
from occtrack.tracker.tracker import Tracker, TrackResult, Tracks

__all__ = ["BOX_FORMATS", "OCCLUSION_NAMES", "BoxFormat", "TrackResult", "Tracker",
           "TrackerConfig", "Tracks"]
