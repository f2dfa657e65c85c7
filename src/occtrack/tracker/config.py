"""The box tracker's settings live in the schema on the bottom floor, `occtrack.config`."""

from occtrack.config import OCCLUSION_NAMES, TrackerConfig, load_toml

__all__ = ["OCCLUSION_NAMES", "TrackerConfig", "load_toml"]
