"""Multi-object tracking metrics."""
