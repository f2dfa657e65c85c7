"""occtrack: occlusion-aware multi-object tracking.

Implements "Measurement-wise Occlusion in Multi-object Tracking" (Motro and Ghosh): a Poisson
multi-Bernoulli tracker in which occlusion is one swappable step (none, object-wise,
measurement-wise), and the paper's four uses of it.

    from occtrack import Tracker, TrackerConfig

    tracker = Tracker(TrackerConfig(image_size=(1920, 1080), fps=30))
    tracks = tracker.update(boxes_xyxy, scores, classes)   # once per frame

`import occtrack` stays light (no numpy): the names below are loaded on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_LAZY = {
    "Tracker": "occtrack.tracker.tracker",
    "Tracks": "occtrack.tracker.tracker",
    "TrackResult": "occtrack.tracker.tracker",
    "TrackerConfig": "occtrack.config",
    "OcctrackError": "occtrack.errors",
}

__all__ = ["OcctrackError", "TrackResult", "Tracker", "TrackerConfig", "Tracks", "__version__"]

if TYPE_CHECKING:  # what type checkers and IDEs see; at run time __getattr__ loads them
    from occtrack.config import TrackerConfig
    from occtrack.errors import OcctrackError
    from occtrack.tracker.tracker import Tracker, TrackResult, Tracks


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'occtrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
