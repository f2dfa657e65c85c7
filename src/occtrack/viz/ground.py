"""One frame of 3D boxes on the ground, seen from above (`occtrack.tracker.ground`): the sensor
and its camera's field of view, the frame's detections shaded by score, the true boxes faintly,
the tracks with their ids (dashed while coasting; orange while held hidden, with the angular
shadows of the nearer boxes that hide them), and a legend. x across (right), z up the page
(forward), metres, in the frame's camera coordinates; the sensor at the origin.

    from occtrack.viz.ground import draw_ground_frame
    draw_ground_frame("frame.png", boxes3d, scores, tracks, truth, fov=field_of_view(P2, 1242))

Every patch carries a gid naming what it draws (`KINDS`), so that a caller (or a test) can
find them again on the axes.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from occtrack.tracker.ground import ground_corners
from occtrack.viz.frame import check_new
from occtrack.viz.output import save

FIXED_FOV = (-math.pi / 4, math.pi / 4)
"""Bearings (rad, atan2(x, z): 0 straight ahead, positive to the right) of the field of view's
edges when no calibration gives them: 90 degrees about straight ahead."""
KINDS = ("truth", "detection", "track", "coasting", "hidden", "shadow")
"""The gids of the patches drawn: a true box, a detection, a track that took a detection, one
coasting, one held while hidden (`GroundTracks.occluded`), the shadow of a box hiding one."""
MARGIN = 4.0  # m beyond the boxes, around the default window
MIN_WINDOW = ((-15.0, 15.0), (-5.0, 30.0))  # x, z (m): the least the default window shows
SHADOW_REACH = 200.0  # m: how far a shadow is drawn (past any window)

DETECTION = "#c2188f"
TRACK = "#1f4fd1"
HIDDEN = "#f07d00"
TRUTH = "0.55"
SHADOW = "0.5"


def field_of_view(P2: np.ndarray, image_width: float) -> tuple[float, float]:
    """The bearings (rad, atan2(x, z)) of the rays through the left and right edges of the
    image (u = 0 and u = width, at the principal point's row) of a KITTI calibration's P2, in
    its rectified camera coordinates. The rays leave camera 2's centre, a few centimetres from
    the camera 0 origin the boxes are given in; the picture draws them from the origin."""
    P2 = np.asarray(P2, dtype=float).reshape(3, 4)
    inverse = np.linalg.inv(P2[:, :3])
    cy = P2[1, 2]
    rays = inverse @ np.array([[0.0, cy, 1.0], [float(image_width), cy, 1.0]]).T
    left, right = np.arctan2(rays[0], rays[2])
    return float(left), float(right)


def box_bearings(footprints: np.ndarray, sensor=(0.0, 0.0)) -> tuple[np.ndarray, ...]:
    """Each footprint's (K, 4, 2) angular interval (lo, hi) seen from `sensor` (bearings
    atan2(x, z), radians, about its centre's bearing, so lo may be below -pi or hi above pi),
    the corners at lo and hi (K, 2) each, and its centre's range (K,)."""
    rel = np.asarray(footprints, dtype=float).reshape(-1, 4, 2) - np.asarray(sensor, float)
    centre = rel.mean(axis=1)
    bearing = np.arctan2(centre[:, 0], centre[:, 1])
    delta = np.arctan2(rel[..., 0], rel[..., 1]) - bearing[:, None]
    delta = (delta + np.pi) % (2 * np.pi) - np.pi
    k = np.arange(len(rel))
    lo_at, hi_at = delta.argmin(axis=1), delta.argmax(axis=1)
    return (bearing + delta[k, lo_at], bearing + delta[k, hi_at], rel[k, lo_at] + sensor,
            rel[k, hi_at] + sensor, np.hypot(centre[:, 0], centre[:, 1]))


def _overlap(lo_a, hi_a, lo_b, hi_b) -> np.ndarray:
    """Whether intervals a (one) and b (many) overlap, the same angles a turn apart."""
    return np.any([(np.minimum(hi_a, hi_b + turn) > np.maximum(lo_a, lo_b + turn))
                   for turn in (-2 * np.pi, 0.0, 2 * np.pi)], axis=0)


def hiding_boxes(hidden: np.ndarray, occluders: np.ndarray, sensor=(0.0, 0.0)) -> np.ndarray:
    """The occluders (footprints (N, 4, 2)) that may hide any of the `hidden` footprints
    (K, 4, 2) from `sensor`: nearer (centre range) than the hidden box, and overlapping its
    angular interval. Returns the sorted indices of those occluders, each once."""
    if len(hidden) == 0 or len(occluders) == 0:
        return np.zeros(0, dtype=int)
    a_lo, a_hi, _, _, a_d = box_bearings(hidden, sensor)
    b_lo, b_hi, _, _, b_d = box_bearings(occluders, sensor)
    found = set()
    for k in range(len(a_d)):
        hit = _overlap(a_lo[k], a_hi[k], b_lo, b_hi) & (b_d < a_d[k] - 1e-6)
        found.update(np.flatnonzero(hit).tolist())
    return np.array(sorted(found), dtype=int)


def shadow_polygon(footprint: np.ndarray, sensor=(0.0, 0.0),
                   reach: float = SHADOW_REACH, steps: int = 12) -> np.ndarray:
    """(steps + 2, 2) the region a footprint (4, 2) hides from `sensor` out to `reach` m: its
    corner at one edge of its angular interval, the arc at `reach` across the interval, its
    corner at the other edge (the box itself closes it)."""
    lo, hi, at_lo, at_hi, _ = box_bearings(footprint[None], sensor)
    angles = np.linspace(lo[0], hi[0], steps)
    arc = np.asarray(sensor, float) + reach * np.stack([np.sin(angles), np.cos(angles)], axis=1)
    return np.vstack([at_lo, arc, at_hi])


def _footprints(boxes3d) -> np.ndarray:
    boxes = np.asarray(boxes3d, dtype=float).reshape(-1, 7)
    return ground_corners(boxes)[..., [0, 2]]


def default_limits(*footprints: np.ndarray, sensor=(0.0, 0.0),
                   margin: float = MARGIN) -> tuple[tuple[float, float], tuple[float, float]]:
    """(x, z) limits holding the sensor, `MIN_WINDOW` and every footprint given, `margin` m
    beyond them."""
    points = np.vstack([np.asarray(sensor, float).reshape(1, 2),
                        *(np.asarray(f, float).reshape(-1, 2) for f in footprints)])
    lo = np.minimum(points.min(axis=0) - margin, [MIN_WINDOW[0][0], MIN_WINDOW[1][0]])
    hi = np.maximum(points.max(axis=0) + margin, [MIN_WINDOW[0][1], MIN_WINDOW[1][1]])
    return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))


def draw_ground_frame(ax_or_path, detections=None, scores=None, tracks=None, truth=None, *,
                      fov: tuple[float, float] | None = FIXED_FOV, sensor=(0.0, 0.0),
                      limits=None, title: str | None = None, shadows: bool = True,
                      overwrite: bool = False, dpi: int = 100):
    """Draw one frame from above (see the module) on a matplotlib axis, or to a new picture.

    Args:
        ax_or_path: an axis to draw on (cleared first), or the path of a picture to write
            (whole or not at all; refused if it exists unless `overwrite`).
        detections: (M, 7) KITTI boxes h w l x y z rotation_y in the frame's camera
            coordinates; drawn magenta, filled by their `scores` (M,) in [0, 1] (None: 1).
        tracks: the frame's `GroundTracks` (or anything with ids, boxes3d, detection_index
            and occluded): blue with their ids, dashed while coasting (detection_index -1),
            orange while held hidden (occluded).
        truth: (T, 7) true boxes, drawn faint grey.
        fov: bearings (rad, atan2(x, z)) of the camera's left and right edges, drawn as two
            rays from the sensor (`field_of_view`; default `FIXED_FOV`, 90 degrees); None: none.
        sensor: the sensor's (x, z), the origin of the camera frame.
        limits: ((x0, x1), (z0, z1)) in m; default: every detection and track and the sensor
            (`default_limits`).
        title: the axis title.
        shadows: draw faintly the angular shadow of each nearer box (a detection or a coasting
            track) overlapping a hidden track's angles, out from the sensor.

    Returns:
        the axis, or the path written.
    """
    if isinstance(ax_or_path, (str, Path)):
        path = check_new(ax_or_path, overwrite)
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        det = _footprints(np.zeros((0, 7)) if detections is None else detections)
        shown = _footprints(np.zeros((0, 7)) if tracks is None else tracks.boxes3d)
        window = limits or default_limits(det, shown, sensor=sensor)
        (x0, x1), (z0, z1) = window
        plot = 6.0  # in: the axes' width; the legend goes on their right
        height = min(max(plot * (z1 - z0) / (x1 - x0) + 0.8, 4.0), 12.0)
        fig, ax = plt.subplots(figsize=(plot + 2.4, height))
        _draw(ax, detections, scores, tracks, truth, fov, sensor, window, title, shadows)
        save(fig, path, overwrite, dpi=dpi, bbox_inches="tight", pad_inches=0.15)
        return path
    _draw(ax_or_path, detections, scores, tracks, truth, fov, sensor, limits, title, shadows)
    return ax_or_path


def _polygon(ax, corners, kind: str, **style):
    from matplotlib.patches import Polygon

    patch = Polygon(corners, closed=True, **style)
    patch.set_gid(kind)
    ax.add_patch(patch)
    return patch


def _draw(ax, detections, scores, tracks, truth, fov, sensor, limits, title, shadows) -> None:
    from matplotlib.colors import to_rgb
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ax.clear()
    sensor = np.asarray(sensor, dtype=float).reshape(2)
    det = _footprints(np.zeros((0, 7)) if detections is None else detections)
    score = (np.ones(len(det)) if scores is None
             else np.clip(np.asarray(scores, dtype=float).reshape(-1), 0.0, 1.0))
    if len(score) != len(det):
        raise ValueError(f"{len(det)} detections but {len(score)} scores")
    true = _footprints(np.zeros((0, 7)) if truth is None else truth)
    if tracks is None:
        ids = np.zeros(0, dtype=int)
        shown = np.zeros((0, 4, 2))
        coasting = hidden = np.zeros(0, dtype=bool)
    else:
        ids = np.asarray(tracks.ids).reshape(-1)
        shown = _footprints(tracks.boxes3d)
        coasting = np.asarray(tracks.detection_index).reshape(-1) < 0
        hidden = np.asarray(tracks.occluded, dtype=bool).reshape(-1) & coasting
    (x0, x1), (z0, z1) = limits or default_limits(det, shown, sensor=sensor)
    handles = []

    if shadows and hidden.any():
        occluders = np.concatenate([det, shown[coasting & ~hidden]])
        for n in hiding_boxes(shown[hidden], occluders, sensor):
            _polygon(ax, shadow_polygon(occluders[n], sensor), "shadow", facecolor=SHADOW,
                     edgecolor="none", alpha=0.13, zorder=0)
        handles.append(Patch(facecolor=SHADOW, alpha=0.25, label="shadow of a nearer box"))
    for corners in true:
        _polygon(ax, corners, "truth", fill=False, edgecolor=TRUTH, lw=0.8, alpha=0.7,
                 zorder=1)
    if len(true):
        handles.append(Patch(fill=False, edgecolor=TRUTH, lw=0.8, label="true box"))
    r, g, b = to_rgb(DETECTION)
    for corners, s in zip(det, score, strict=True):
        _polygon(ax, corners, "detection", facecolor=(r, g, b, 0.05 + 0.5 * s),
                 edgecolor=(r, g, b, 1.0), lw=0.9, zorder=2)
    if len(det):
        handles.append(Patch(facecolor=(r, g, b, 0.3), edgecolor=DETECTION, lw=0.9,
                             label="detection (fill: score)"))
    for track, corners, coast, held in zip(ids, shown, coasting, hidden, strict=True):
        colour = HIDDEN if held else TRACK
        kind = "hidden" if held else "coasting" if coast else "track"
        _polygon(ax, corners, kind, fill=False, edgecolor=colour, lw=2.0 if held else 1.5,
                 ls="--" if coast else "-", zorder=3)
        right = corners[corners[:, 0].argmax()]
        ax.annotate(str(int(track)), right, xytext=(3, 0), textcoords="offset points",
                    fontsize=7, color=colour, va="center", zorder=4, clip_on=True)
    for kind, label, colour, ls in (("track", "track (took a detection)", TRACK, "-"),
                                    ("coasting", "track coasting", TRACK, "--"),
                                    ("hidden", "track held while hidden", HIDDEN, "--")):
        if (kind == "track" and (~coasting).any()) or (kind == "coasting" and (
                coasting & ~hidden).any()) or (kind == "hidden" and hidden.any()):
            handles.append(Patch(fill=False, edgecolor=colour, ls=ls, lw=1.5, label=label))

    if fov is not None:
        reach = 2 * max(abs(x0), abs(x1), abs(z0), abs(z1)) + 10
        for bearing in fov:
            ax.plot([sensor[0], sensor[0] + reach * math.sin(bearing)],
                    [sensor[1], sensor[1] + reach * math.cos(bearing)], color="0.35", lw=0.8,
                    ls=":", zorder=1)
        handles.insert(0, Line2D([], [], color="0.35", lw=0.8, ls=":",
                                 label=f"camera's field of view "
                                       f"({math.degrees(fov[1] - fov[0]):.0f}\N{DEGREE SIGN})"))
    ax.plot(*sensor, marker="^", color="k", ms=9, ls="none", zorder=5)
    handles.insert(0, Line2D([], [], marker="^", color="k", ms=8, ls="none", label="sensor"))

    ax.set_xlim(x0, x1)
    ax.set_ylim(z0, z1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, right)")
    ax.set_ylabel("z (m, forward)")
    ax.grid(alpha=0.25, lw=0.5)
    ax.legend(handles=handles, fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0, frameon=False)
    if title:
        ax.set_title(title, fontsize=9.5)
