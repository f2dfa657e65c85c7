"""Where a scanning sensor's beams meet discs and rectangles: the geometry both the lidar scene
(`occtrack.scenarios.lidar.raycast`, which simulates scans) and the scan likelihood
(`occtrack.models.scan`, which scores them) need, kept here on the models' floor so the
likelihood does not reach up into the scenarios.

A beam is the ray o + t u, t >= 0 (u a unit vector). Each object is a convex shape, so the ray
meets it in one interval [entry, exit] of t, or not at all; the beam's range to the object is
max(entry, 0) when exit >= max(entry, 0) (a sensor inside a shape sees it at 0), else infinite
(`first_surface`).

- disc, centre c, radius a: with p = c - o, t_c = u.p and d^2 = |p|^2 - t_c^2 (the squared
  distance from c to the beam's line), the interval is t_c -+ sqrt(a^2 - d^2) where d <= a;
- rectangle, centre c, heading h, half-length a (along h) and half-width b: in the box's frame
  (axes e1 = (cos h, sin h), e2 = (-sin h, cos h)) the ray is q + t v with q = R(-h)(o - c) and
  v = R(-h) u, and each axis keeps it inside a slab: |q_i + t v_i| <= half_i, the interval
  -q_i / v_i -+ half_i / |v_i|. The box is the slabs' intersection (Kay and Kajiya's slab
  test). A direction component of exactly 0 is nudged to 1e-12 (the slab's interval then
  spans about 10^12 m, or misses by as much: the limits of a ray along the slab).

The range of a disc's near surface, rho(c) = t_c - sqrt(a^2 - d^2), moves with the centre as

    d rho / d c = u + d / sqrt(a^2 - d^2) n,    n = (-u_y, u_x), d = n.p (signed),

(`disc_range_gradient`): along the beam one for one, across it more and more steeply towards
the disc's edge, where the beam grazes it and the slope is unbounded (a linearised range is a
poor guide on the outermost beams).

Everything is an array over (beams, objects): no Python loop over either.
"""

from __future__ import annotations

import math

import numpy as np

from occtrack.models._models import beam_window, near_range  # noqa: F401 (compiled)

TINY = 1e-12
TURN = 2.0 * math.pi


def directions(angles: np.ndarray) -> np.ndarray:
    """Unit vectors (B, 2) of beams at world angles (B,) rad."""
    angles = np.asarray(angles, float)
    return np.c_[np.cos(angles), np.sin(angles)]


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


def first_surface(entry: np.ndarray, exit_: np.ndarray) -> np.ndarray:
    """The range at which a ray first meets a shape it crosses in [entry, exit]: max(entry, 0),
    or inf where the interval is empty or wholly behind the sensor."""
    start = np.maximum(entry, 0.0)
    return np.where(exit_ >= start, start, np.inf)


def disc_ranges(origin: np.ndarray, angles: np.ndarray, centre: np.ndarray,
                radius: float | np.ndarray) -> np.ndarray:
    """rho (B, K): the range along each beam (world angles (B,)) to the near surface of each
    disc (centres (K, 2)), inf where the beam misses it."""
    origin, centre = np.asarray(origin, float), np.asarray(centre, float).reshape(-1, 2)
    radius = np.broadcast_to(np.asarray(radius, float), (len(centre),))
    return first_surface(*disc_interval(origin, directions(angles), centre, radius))


def disc_range_gradient(origin: np.ndarray, angles: np.ndarray, centre: np.ndarray,
                        radius: float | np.ndarray) -> np.ndarray:
    """d rho / d c (B, K, 2) where the beam meets the disc in front of the sensor (zeros where
    it misses, or where the sensor is inside the disc and rho is 0 whatever c does; a beam
    exactly tangent, where the slope is infinite, gets just u)."""
    origin, centre = np.asarray(origin, float), np.asarray(centre, float).reshape(-1, 2)
    radius = np.broadcast_to(np.asarray(radius, float), (len(centre),))
    u = directions(angles)
    n = np.c_[-u[:, 1], u[:, 0]]
    p = centre - origin
    d = n @ p.T
    entry, exit_ = disc_interval(origin, u, centre, radius)
    live = (entry > 0) & (exit_ >= entry)
    half = np.sqrt(np.maximum(radius**2 - d**2, 0.0))
    slope = np.divide(d, half, out=np.zeros_like(d), where=live & (half > 0))
    grad = u[:, None, :] + slope[:, :, None] * n[:, None, :]
    return np.where(live[:, :, None], grad, 0.0)
