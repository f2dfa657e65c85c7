"""What the scan tracker learns of its scene while it tracks (issue 41): the static scene
(`models.static_scene`), an occupancy grid, and the births it keeps off walls."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.config.scan import ScanTrackerConfig
from occtrack.models.scan_geometry import disc_ranges
from occtrack.models.static_scene import StaticScene
from occtrack.tracker.scan import ScanTracker


def wall_scan(origin, angles, x=4.0):
    """Ranges from `origin` to the wall x = `x` (inf where a beam points away)."""
    c = np.cos(angles)
    with np.errstate(divide="ignore"):
        r = np.where(c > 1e-9, (x - origin[0]) / c, np.inf)
    return np.where(r < 5.0, r, np.inf)


def test_a_wall_seen_scan_after_scan_is_static_and_free_space_is_not():
    scene = StaticScene(max_range=5.0, cell=0.1)
    angles = np.linspace(-0.5, 0.5, 101)
    origin = np.zeros(2)
    wall = wall_scan(origin, angles)
    points = origin + wall[:, None] * np.c_[np.cos(angles), np.sin(angles)]
    seg = np.zeros(len(points), dtype=np.int64)
    assert scene.static_probability(points, seg, 1)[0] == 0.5  # never seen: even odds
    for _ in range(10):
        scene.add_scan(origin, angles, wall)
    assert scene.static_probability(points, seg, 1)[0] > 0.9
    # a person stepping into the free space before the wall
    person = np.array([[2.0, 0.0], [2.02, 0.05]])
    assert scene.static_probability(person, np.zeros(2, np.int64), 1)[0] < 0.1
    # the grid follows the sensor and remembers the wall where it stands
    size = scene.log_odds.shape
    scene.add_scan(np.array([1.0, 0.3]), angles, wall_scan(np.array([1.0, 0.3]), angles))
    assert scene.log_odds.shape == size
    assert scene.static_probability(points, seg, 1)[0] > 0.9


def test_births_at_static_scene_are_weighed_by_the_chance_something_moved_there():
    """A segment's birth mass is the configured one times 1 - its static probability."""
    config = ScanTrackerConfig(max_range=10.0, radius=0.1, clutter_per_scan=1.0,
                               static_scene=True)  # (the post 3 m off: no edge birth)
    tracker = ScanTracker(config, beams=245, rate=10.0)
    angles = np.linspace(-0.75, 0.75, 245)
    post = disc_ranges(np.zeros(2), angles, np.array([[3.0, 0.5]]), 0.1).min(axis=1)
    z = np.where(post < 10.0, post, np.inf)
    for i in range(20):
        tracker.update(z, angles, i / 10.0)
    segments = tracker.segments
    assert len(segments) == 1 and segments.static[0] > 0.95
    births = tracker.filter.birth_model
    mass, _, _ = births.components(segments, None, 0.1, 5)
    assert mass[0] == pytest.approx(config.birth_mass * (1 - segments.static[0]))
