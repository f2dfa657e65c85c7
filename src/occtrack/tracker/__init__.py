"""The Gaussian-mixture Poisson multi-Bernoulli trackers with pluggable occlusion: boxes
(`Tracker`) and 2-D lidar scans (`ScanTracker`), one filter."""

from occtrack.config import OCCLUSION_NAMES, TrackerConfig
from occtrack.tracker.boxes import BOX_FORMATS, BoxFormat
from occtrack.tracker.scan import ScanTracker, ScanTrackResult, ScanTracks
from occtrack.tracker.tracker import Tracker, TrackResult, Tracks

__all__ = ["BOX_FORMATS", "OCCLUSION_NAMES", "BoxFormat", "ScanTrackResult", "ScanTracker",
           "ScanTracks", "TrackResult", "Tracker", "TrackerConfig", "Tracks"]
