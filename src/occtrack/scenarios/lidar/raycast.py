"""Exact ray casting of every beam against every object at once: what a scanning range sensor
sees, and what hides what.

A beam is the ray o + t u, t >= 0 (u a unit vector). Each object is a convex shape, so the ray
meets it in one interval [entry, exit] of t, or not at all; the beam's range to the object is
max(entry, 0) when exit >= max(entry, 0) (a sensor inside a shape sees it at 0), else infinite.

- disc, centre c, radius r: with p = c - o, t_c = u.p and d^2 = |p|^2 - t_c^2 (the squared
  distance from c to the beam's line), the interval is t_c -+ sqrt(r^2 - d^2) where d <= r;
- rectangle, centre c, heading h, half-length a (along h) and half-width b: in the box's frame
  (axes e1 = (cos h, sin h), e2 = (-sin h, cos h)) the ray is q + t v with q = R(-h)(o - c) and
  v = R(-h) u, and each axis keeps it inside a slab: |q_i + t v_i| <= half_i, the interval
  -q_i / v_i -+ half_i / |v_i|. The box is the slabs' intersection (Kay and Kajiya's slab
  test). A direction component of exactly 0 is nudged to 1e-12 (the slab's interval then
  spans about 10^12 m, or misses by as much: the limits of a ray along the slab).

Everything is an array over (beams, objects): no Python loop over either.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TINY = 1e-12


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


def disc_interval(origin: np.ndarray, u: np.ndarray, centre: np.ndarray,
                  radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[entry, exit] of every ray (B, 2 unit directions from `origin`) through every disc
    (K centres, radii), (B, K) each; entry > exit where a ray's line misses a disc."""
    p = centre - origin
    t_c = u @ p.T
    half2 = radius**2 - (np.sum(p**2, axis=1) - t_c**2)
    half = np.sqrt(np.maximum(half2, 0.0))
    miss = half2 < 0
    return np.where(miss, np.inf, t_c - half), np.where(miss, -np.inf, t_c + half)


def box_interval(origin: np.ndarray, u: np.ndarray, centre: np.ndarray, heading: np.ndarray,
                 half_length: np.ndarray,
                 half_width: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[entry, exit] of every ray through every rectangle, (B, K) each, by the slab test."""
    cos, sin = np.cos(heading), np.sin(heading)
    q = origin - centre
    entry, exit_ = np.full((len(u), len(centre)), -np.inf), np.full((len(u), len(centre)), np.inf)
    for e_x, e_y, half in ((cos, sin, half_length), (-sin, cos, half_width)):
        v = np.outer(u[:, 0], e_x) + np.outer(u[:, 1], e_y)
        v = np.where(np.abs(v) < TINY, np.where(v < 0, -TINY, TINY), v)
        middle = -(q[:, 0] * e_x + q[:, 1] * e_y) / v
        reach = half / np.abs(v)
        entry, exit_ = np.maximum(entry, middle - reach), np.minimum(exit_, middle + reach)
    return entry, exit_


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
    start = np.maximum(entry, 0.0)
    return np.where(exit_ >= start, start, np.inf)


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
