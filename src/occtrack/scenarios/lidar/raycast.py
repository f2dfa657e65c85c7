"""Exact ray casting of every beam against every object at once: what a scanning range sensor
sees, and what hides what.

The ray/disc and ray/rectangle intervals (and their maths) live in
`occtrack.models.scan_geometry`, on the models' floor, where the scan likelihood uses them too;
here they are cast against a scene's shapes.

Everything is an array over (beams, objects): no Python loop over either.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occtrack.models.scan_geometry import box_interval, disc_interval, first_surface


@dataclass(frozen=True)
class Shapes:
    """K objects: centre (K, 2) m, heading (K,) rad, length and width (K,) m (a disc's are its
    diameter), disc (K,) bool (else a rectangle)."""

    centre: np.ndarray
    heading: np.ndarray
    length: np.ndarray
    width: np.ndarray
    disc: np.ndarray

    def __len__(self) -> int:
        return len(self.disc)


def cast(origin: np.ndarray, angles: np.ndarray, shapes: Shapes) -> np.ndarray:
    """Range along each beam (world angles, (B,)) to each object, (B, K): infinite where the
    beam misses it."""
    origin = np.asarray(origin, float)
    u = np.c_[np.cos(angles), np.sin(angles)]
    entry = np.full((len(u), len(shapes)), np.inf)
    exit_ = np.full_like(entry, -np.inf)
    d, r = shapes.disc, ~shapes.disc
    if d.any():
        entry[:, d], exit_[:, d] = disc_interval(origin, u, shapes.centre[d], shapes.length[d] / 2)
    if r.any():
        entry[:, r], exit_[:, r] = box_interval(origin, u, shapes.centre[r], shapes.heading[r],
                                                shapes.length[r] / 2, shapes.width[r] / 2)
    return first_surface(entry, exit_)


def nearest(dist: np.ndarray, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Per beam, the object its first surface belongs to (-1: none before max_range) and that
    range (inf: none)."""
    if dist.shape[1] == 0:
        return np.full(len(dist), -1), np.full(len(dist), np.inf)
    k = np.argmin(dist, axis=1)
    d = dist[np.arange(len(dist)), k]
    seen = d < max_range
    return np.where(seen, k, -1), np.where(seen, d, np.inf)


def beam_counts(dist: np.ndarray, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Per object: beams that would reach it were it alone (`clear`: it is in the field of
    view, in range and some beam passes through its angular span) and beams whose first
    surface it is (`visible`). Fully occluded: clear > 0 and visible == 0."""
    clear = np.count_nonzero(dist < max_range, axis=0)
    k, _ = nearest(dist, max_range)
    visible = np.bincount(k[k >= 0], minlength=dist.shape[1])
    return clear, visible
