"""The Gaussian-mixture Poisson multi-Bernoulli trackers with pluggable occlusion: boxes
(`Tracker`) and 2-D lidar scans (`ScanTracker`), one filter."""

from typing import TYPE_CHECKING, Any

from occtrack.config import OCCLUSION_NAMES, TrackerConfig
from occtrack.tracker.boxes import BOX_FORMATS, BoxFormat
from occtrack.tracker.tracker import FrameReport, Tracker, TrackResult, Tracks

if TYPE_CHECKING:
    from occtrack.tracker.scan import ScanTracker, ScanTrackResult, ScanTracks

_SCAN = ("ScanTracker", "ScanTrackResult", "ScanTracks")


def __getattr__(name: str) -> Any:
    """The scan tracker on first use: it brings scipy.special, which the box tracker's import
    does without (`import occtrack; occtrack.Tracker` stays under 0.2 s)."""
    if name in _SCAN:
        from occtrack.tracker import scan

        return getattr(scan, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = ["BOX_FORMATS", "OCCLUSION_NAMES", "BoxFormat", "FrameReport", "ScanTrackResult",
           "ScanTracker", "ScanTracks", "TrackResult", "Tracker", "TrackerConfig", "Tracks"]
