"""The static scene a 2-D laser sees, learnt online: an occupancy grid (issue 41, item 3).

Walls, posts and bushes return segments scan after scan from the same place; a person's legs
return from where the beams went through a moment before. The grid keeps, per cell of `cell`
m, the log-odds that something static stands there (Moravec and Elfes' occupancy grid, with
Thrun, Burgard and Fox's inverse sensor model, "Probabilistic Robotics" ch. 9): every scan,
the cell a return falls in gains `hit` log-odds, the cells its beam passed through lose
`miss`, clamped to [-`clamp`, `clamp`] so that the map follows a scene that changes (a car
that leaves, a person who stood still and walks on). A segment's probability of being static
scene is the mean, over its returns, of their cells' occupancy *before* the scan is added:
a return in a cell seen empty is something that moved there.

The scan tracker gives a segment's birth the probability that it is not static scene
(`models.scan_segments.ScanBirths`): leg_tracker's rule that a person is born only in free
space (Leigh et al., ICRA 2015), as a probability rather than a threshold. A cell never seen
has log-odds 0 (even odds).

The grid is a square of side 2 (max_range + cell) about the sensor, scrolled with it whole
cells at a time (cells that scroll out are forgotten, those that scroll in start unknown), so
its memory is bounded by the sensor's reach and never grows with time.

Written by hand: a grid of a few thousand cells and numpy's `bincount`; the robotics
libraries that keep occupancy grids (ROS's costmap_2d, OctoMap) need ROS or C++ builds.
"""

from __future__ import annotations

import math

import numpy as np


class StaticScene:
    """An occupancy grid about the sensor (see the module).

    Args:
        max_range: the sensor's range, m (the grid covers it on every side).
        cell: the side of a cell, m.
        hit, miss: the log-odds a return adds to its cell and a beam takes from each cell it
            passes through.
        clamp: the largest log-odds either way.
    """

    def __init__(self, max_range: float, cell: float = 0.1, hit: float = 0.85,
                 miss: float = 0.4, clamp: float = 3.5):
        for name, value in (("max_range", max_range), ("cell", cell), ("hit", hit),
                            ("miss", miss), ("clamp", clamp)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, not {value}")
        self.cell, self.hit, self.miss, self.clamp = float(cell), hit, miss, clamp
        self.max_range = float(max_range)
        self.size = 2 * (int(math.ceil(max_range / cell)) + 1)
        self.reset()

    def reset(self) -> None:
        self.log_odds = np.zeros((self.size, self.size))
        self.corner = None  # integer cell index of the grid's [0, 0] in the world

    def _scroll(self, origin: np.ndarray) -> None:
        """Put the sensor at the grid's centre, moving what is known with it."""
        corner = np.floor(origin / self.cell).astype(np.int64) - self.size // 2
        if self.corner is None:
            self.corner = corner
            return
        dx, dy = (int(v) for v in corner - self.corner)
        if dx == 0 and dy == 0:
            return
        moved = np.zeros_like(self.log_odds)
        n = self.size
        if abs(dx) < n and abs(dy) < n:
            moved[max(-dx, 0):n - max(dx, 0), max(-dy, 0):n - max(dy, 0)] = \
                self.log_odds[max(dx, 0):n - max(-dx, 0), max(dy, 0):n - max(-dy, 0)]
        self.log_odds = moved
        self.corner = corner

    def _cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Flat grid index of each world point (P, 2) and whether it lies on the grid."""
        ij = np.floor(points / self.cell).astype(np.int64) - self.corner
        on = np.all((ij >= 0) & (ij < self.size), axis=1)
        return ij[:, 0] * self.size + ij[:, 1], on

    def static_probability(self, points: np.ndarray, segment: np.ndarray,
                           segments: int) -> np.ndarray:
        """The probability (M,) that each of `segments` segments is static scene: the mean
        occupancy of its returns' cells (`points` (P, 2) world, `segment` (P,) its index);
        0.5 for a segment with no return on the grid."""
        if self.corner is None or segments == 0:
            return np.full(segments, 0.5)
        flat, on = self._cells(np.asarray(points, float).reshape(-1, 2))
        p = np.full(len(flat), 0.5)
        p[on] = 1.0 / (1.0 + np.exp(-self.log_odds.ravel()[flat[on]]))
        total = np.bincount(segment, weights=p, minlength=segments)
        count = np.bincount(segment, minlength=segments)
        return np.divide(total, count, out=np.full(segments, 0.5), where=count > 0)

    def add_scan(self, origin: np.ndarray, angle: np.ndarray, ranges: np.ndarray) -> None:
        """Add a scan (world angles, ranges m, inf: no return, from the sensor at `origin`):
        the cells with a return rise, the others the beams pass through fall (a beam with
        no return passes through out to max_range), each once a scan."""
        origin = np.asarray(origin, float)
        self._scroll(origin)
        reach = np.where(np.isfinite(ranges), ranges, self.max_range)
        reach = np.minimum(reach, self.max_range)
        u = np.c_[np.cos(angle), np.sin(angle)]
        # free: samples every half cell along each beam up to a cell short of its return
        steps = np.arange(0.0, self.max_range, self.cell / 2)
        along = steps[None, :] < (reach - self.cell)[:, None]
        b, s = np.nonzero(along)
        free = origin + steps[s][:, None] * u[b]
        flat, on = self._cells(free)
        passed = np.unique(flat[on])
        hit = np.isfinite(ranges) & (ranges < self.max_range)
        flat, on = self._cells(origin + ranges[hit][:, None] * u[hit])
        returned = np.unique(flat[on])
        grid = self.log_odds.ravel()  # (a view: the grid is C-contiguous)
        grid[np.setdiff1d(passed, returned, assume_unique=True)] -= self.miss
        grid[returned] += self.hit
        np.clip(self.log_odds, -self.clamp, self.clamp, out=self.log_odds)
