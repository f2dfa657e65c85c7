"""KITTI tracking geometry: calibration, camera poses, and 3D boxes in the image and the world.

Calibration (`DIR/calib/NNNN.txt`, one matrix a line, row-major):

    P0: 12 numbers ... P3: 12 numbers   the rectified cameras' 3x4 projections (P2: left colour)
    R0_rect: 9 numbers                  the rectifying rotation (3x3)
    Tr_velo_to_cam: 12 numbers          velodyne to camera 0 (3x4)
    Tr_imu_to_velo: 12 numbers          IMU to velodyne (3x4)

KITTI's own tracking files write `R_rect`, `Tr_velo_cam` and `Tr_imu_velo` (and may leave out
the colon); both spellings are read. Other keys are skipped.

Poses (`DIR/poses/NNNN.txt`): one line a frame, 12 numbers, the 3x4 [R|t] (row-major) of the
camera in the first frame's camera coordinates, camera to world: a point p in frame k's camera
coordinates is R p + t in the first frame's ("world"). The first line is then the identity. The
given poses are ORB-SLAM3 stereo estimates in the rectified camera 0 frame, the frame KITTI's
3D boxes are in (P2 carries camera 2's offset), so boxes and poses combine directly.

3D boxes are KITTI's `h w l x y z rotation_y` (`KittiTable.box3d`): x y z the bottom centre in
rectified camera coordinates (x right, y down, z forward), the box's length l along its heading,
rotation_y about the y axis; its corners follow KITTI devkit's `computeBox3D` order (0-3 on the
ground, 4-7 on top). A heading ry points along (cos ry, 0, -sin ry) in camera coordinates
(R_y(ry) applied to the x axis); `yaw_to_world` carries that vector with a pose and reads its
yaw back the same way.

Bad input stops a read with the file, line and problem as an `OcctrackError`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError, opening
from occtrack.io.kitti import clip_to_image, layout_root, sequence_name

SIZES = {"P0": 12, "P1": 12, "P2": 12, "P3": 12, "R0_rect": 9, "Tr_velo_to_cam": 12,
         "Tr_imu_to_velo": 12}
"""The calibration keys read, and how many numbers each holds."""
_ALIASES = {"R_rect": "R0_rect", "Tr_velo_cam": "Tr_velo_to_cam", "Tr_imu_velo": "Tr_imu_to_velo"}
ROTATION_TOL = 1e-3
"""How far a pose's R^T R may stray from the identity (the files have 9 decimals)."""


@dataclass(frozen=True)
class Calibration:
    """The matrices of a KITTI calibration file that tracking uses."""

    P2: np.ndarray  # (3, 4): rectified camera coordinates to the left colour image (px)
    R0_rect: np.ndarray  # (3, 3): camera 0 to rectified camera coordinates
    Tr_velo_to_cam: np.ndarray | None  # (3, 4): velodyne to camera 0; None when not given
    path: str = ""


def _read_lines(path: str, expected: str) -> list[str]:
    try:
        with opening(path, expected), open(path, encoding="utf-8", newline="") as fh:
            return fh.read().splitlines()
    except UnicodeDecodeError as err:
        raise OcctrackError(f"not a text file (byte {err.start} is not UTF-8)", path) from None


def _numbers(words: list[str], what: str, path: str, line: int) -> list[float]:
    values = []
    for i, word in enumerate(words, start=1):
        try:
            value = float(word)
        except ValueError:
            raise OcctrackError(f"{what}number {i} is not a number: {word!r}",
                                path, line) from None
        if not math.isfinite(value):
            raise OcctrackError(f"{what}number {i} is {word}", path, line)
        values.append(value)
    return values


def read_calib(path: str | os.PathLike) -> Calibration:
    """A KITTI calibration file: P2 and R0_rect (both required) and Tr_velo_to_cam (if given),
    every known line checked for its count of numbers and finite values."""
    path = str(path)
    found: dict[str, tuple[np.ndarray, int]] = {}
    for number, raw in enumerate(_read_lines(path, "a KITTI calibration file"), start=1):
        text = raw.strip().lstrip("\ufeff")
        if not text:
            continue
        first, *words = text.split()
        key, colon, tail = first.partition(":")  # "P2: 1 ...", "P2:1 ...", "R_rect 1 ..."
        words = [tail, *words] if tail else words
        if not colon and words[:1] == [":"]:  # "P2 : 1 ..."
            words = words[1:]
        key = _ALIASES.get(key, key)
        if key not in SIZES:
            continue
        if key in found:
            raise OcctrackError(f"{key} given twice (first at line {found[key][1]})",
                                path, number)
        if len(words) != SIZES[key]:
            raise OcctrackError(f"{key} should have {SIZES[key]} numbers, found {len(words)}",
                                path, number)
        values = _numbers(words, f"{key}: ", path, number)
        found[key] = (np.array(values, dtype=float), number)
    for key in ("P2", "R0_rect"):
        if key not in found:
            also = " (or R_rect)" if key == "R0_rect" else ""
            raise OcctrackError(f"no {key}{also} line: not a KITTI calibration file?", path)
    velo = found.get("Tr_velo_to_cam")
    return Calibration(P2=found["P2"][0].reshape(3, 4), R0_rect=found["R0_rect"][0].reshape(3, 3),
                       Tr_velo_to_cam=None if velo is None else velo[0].reshape(3, 4), path=path)


def read_poses(path: str | os.PathLike, frames: int | None = None) -> np.ndarray:
    """A pose file's (F, 3, 4) camera-to-world [R|t], one a frame (0-based: row k is frame k),
    each R checked to be a rotation. `frames` (the number of frames the caller needs, e.g. the
    detections' last frame + 1) makes a shorter file an error; a longer one is returned whole.
    Blank lines are allowed only at the end (a line is a frame)."""
    path = str(path)
    lines = _read_lines(path, "a KITTI pose file")
    while lines and not lines[-1].strip():
        lines.pop()
    rows = []
    for number, raw in enumerate(lines, start=1):
        words = raw.strip().lstrip("\ufeff").split()
        if len(words) != 12:
            found = "a blank line" if not words else f"{len(words)}"
            raise OcctrackError(f"a pose line has 12 numbers (3x4 [R|t], row-major), found "
                                f"{found} (one line a frame)", path, number)
        rows.append(_numbers(words, "", path, number))
    poses = np.array(rows, dtype=float).reshape(-1, 3, 4)
    rot = poses[:, :, :3]
    error = np.abs(np.einsum("fji,fjk->fik", rot, rot) - np.eye(3)).max(axis=(1, 2),
                                                                        initial=0.0)
    det = np.linalg.det(rot) if len(rot) else np.zeros(0)
    bad = np.flatnonzero((error > ROTATION_TOL) | (det < 0))
    if len(bad):
        k = int(bad[0])
        why = (f"R^T R differs from the identity by {error[k]:.3g} (over {ROTATION_TOL:g})"
               if error[k] > ROTATION_TOL else f"det(R) = {det[k]:.3g} (a reflection)")
        raise OcctrackError(f"the pose's 3x3 block is not a rotation: {why}", path, k + 1)
    if frames is not None and len(poses) < frames:
        raise OcctrackError(f"{len(poses)} poses, but the detections reach frame {frames - 1} "
                            f"(0-based): a pose file needs a line for every frame", path)
    return poses


def _find(path: str | os.PathLike, folder: str) -> Path | None:
    root = layout_root(path)
    if root is None:
        return None
    file = root / folder / f"{sequence_name(path)}.txt"
    return file if file.is_file() else None


def find_calib(path: str | os.PathLike) -> Path | None:
    """`DIR/calib/NNNN.txt` for a file in a KITTI layout (`DIR/label_02/NNNN.txt`,
    `DIR/det_02/NAME/NNNN.txt`), or None if there is none."""
    return _find(path, "calib")


def find_poses(path: str | os.PathLike) -> Path | None:
    """`DIR/poses/NNNN.txt` for a file in a KITTI layout, or None if there is none."""
    return _find(path, "poses")


# -- boxes ----------------------------------------------------------------------------------------

_X = np.array([1, 1, -1, -1, 1, 1, -1, -1], dtype=float) / 2
_Y = np.array([0, 0, 0, 0, -1, -1, -1, -1], dtype=float)
_Z = np.array([1, -1, -1, 1, 1, -1, -1, 1], dtype=float) / 2


def _boxes(box3d: np.ndarray) -> np.ndarray:
    box3d = np.asarray(box3d, dtype=float)
    if box3d.ndim != 2 or box3d.shape[1] != 7:
        raise ValueError(f"3D boxes are (N, 7) h w l x y z rotation_y, got {box3d.shape}")
    return box3d


def box3d_corners(box3d: np.ndarray) -> np.ndarray:
    """The (N, 8, 3) corners of (N, 7) KITTI boxes (h w l x y z rotation_y), in KITTI devkit's
    order and convention: 0-3 on the ground (y = the box's y), 4-7 on top (y - h)."""
    box3d = _boxes(box3d)
    h, w, l, x, y, z, ry = box3d.T
    cx = l[:, None] * _X  # (N, 8) in the box's frame
    cy = h[:, None] * _Y
    cz = w[:, None] * _Z
    c, s = np.cos(ry)[:, None], np.sin(ry)[:, None]
    # R_y(ry) = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return np.stack([c * cx + s * cz + x[:, None], cy + y[:, None],
                     -s * cx + c * cz + z[:, None]], axis=-1)


def footprint(box3d: np.ndarray) -> np.ndarray:
    """The (N, 4, 2) ground corners (x, z) of (N, 7) KITTI boxes, corners 0-3 of
    `box3d_corners`."""
    return box3d_corners(box3d)[:, :4, [0, 2]]


def project_boxes(box3d: np.ndarray, P2: np.ndarray, image_size: tuple[float, float],
                  min_depth: float = 0.1, round_: np.ndarray | None = None) -> np.ndarray:
    """The (N, 4) image boxes x1 y1 x2 y2 that the corners of (N, 7) KITTI boxes project to with
    `P2`, clipped to [0, width] x [0, height] (`image_size` = (width, height)). A row is NaN
    when a corner lies nearer than `min_depth` (m, camera z; behind the camera, as KITTI devkit
    drops it) or the clipped box is empty (the box is wholly outside the image); KITTI's
    unknown 3D values (z = -1000) therefore give NaN. `round_` (N,) bool: those rows project
    the elliptic cylinder inscribed in the box instead of its corners (`project_cylinders`)."""
    corners = box3d_corners(box3d)
    P2 = np.asarray(P2, dtype=float)
    image = corners @ P2[:, :3].T + P2[:, 3]  # (N, 8, 3)
    ahead = (corners[:, :, 2] >= min_depth).all(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = image[:, :, :2] / image[:, :, 2:]
        box = np.concatenate([uv.min(axis=1), uv.max(axis=1)], axis=1)
    if round_ is not None and np.any(round_):
        which = np.flatnonzero(round_)
        box[which] = project_cylinders(np.asarray(box3d, dtype=float)[which], P2)
    box = clip_to_image(box, image_size)
    keep = ahead & (box[:, 2] > box[:, 0]) & (box[:, 3] > box[:, 1])
    box[~keep] = np.nan
    return box


def project_cylinders(box3d: np.ndarray, P2: np.ndarray) -> np.ndarray:
    """The (N, 4) image boxes x1 y1 x2 y2, unclipped, of the upright elliptic cylinders
    inscribed in (N, 7) KITTI boxes (axes l / 2 along the heading and w / 2 across it, from the
    ground to h above it), every point ahead of the camera.

    A person fills that cylinder, not the box's corners: seen at 45 degrees a person's box
    projects up to sqrt(2) times as wide as the person (`occtrack.io.kitti.ROUND_TYPES`). The
    extremes are exact: a rim is p(t) = c + A cos t + B sin t, so an image coordinate
    u(t) = (a0 + a1 cos t + a2 sin t) / (c0 + c1 cos t + c2 sin t) (the numerator that row of
    P2 p(t), the denominator its last), and du/dt = 0 is linear in (cos t, sin t):

        (a2 c0 - a0 c2) cos t + (a0 c1 - a1 c0) sin t + (a2 c1 - a1 c2) = 0,

    two angles, the rim's two extremes of u; the cylinder's are those of its two rims."""
    box3d = _boxes(box3d)
    P2 = np.asarray(P2, dtype=float)
    h, w, l, x, y, z, ry = box3d.T
    c, s = np.cos(ry), np.sin(ry)
    along = np.stack([c, np.zeros_like(c), -s], axis=-1) * (l / 2)[:, None]  # (N, 3)
    across = np.stack([s, np.zeros_like(s), c], axis=-1) * (w / 2)[:, None]
    qa, qb = along @ P2[:, :3].T, across @ P2[:, :3].T  # (N, 3): cos t and sin t terms
    low, high = np.full((len(box3d), 2), np.inf), np.full((len(box3d), 2), -np.inf)
    for lift in (0.0, 1.0):  # the bottom rim, then the top
        centre = np.stack([x, y - lift * h, z], axis=-1)
        q0 = centre @ P2[:, :3].T + P2[:, 3]
        for k in (0, 1):  # u, then v
            a0, a1, a2 = q0[:, k], qa[:, k], qb[:, k]
            c0, c1, c2 = q0[:, 2], qa[:, 2], qb[:, 2]
            alpha, beta, gamma = a2 * c0 - a0 * c2, a0 * c1 - a1 * c0, a2 * c1 - a1 * c2
            radius = np.hypot(alpha, beta)
            with np.errstate(divide="ignore", invalid="ignore"):
                spread = np.arccos(np.clip(-gamma / radius, -1.0, 1.0))
                for t in (np.arctan2(beta, alpha) + spread, np.arctan2(beta, alpha) - spread):
                    ct, st = np.cos(t), np.sin(t)
                    value = (a0 + a1 * ct + a2 * st) / (c0 + c1 * ct + c2 * st)
                    low[:, k] = np.minimum(low[:, k], value)
                    high[:, k] = np.maximum(high[:, k], value)
    return np.concatenate([low, high], axis=1)


# -- poses ----------------------------------------------------------------------------------------

def _pose(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (3, 4):
        raise ValueError(f"a pose is a (3, 4) [R|t], got {pose.shape}")
    return pose[:, :3], pose[:, 3]


def to_world(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(N, 3) points in a frame's camera coordinates to the first frame's (R p + t), `pose`
    that frame's (3, 4) camera-to-world [R|t]."""
    rot, t = _pose(pose)
    return np.asarray(points, dtype=float) @ rot.T + t


def to_camera(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(N, 3) points in the first frame's camera coordinates to the frame's (R^T (p - t)): the
    inverse of `to_world`."""
    rot, t = _pose(pose)
    return (np.asarray(points, dtype=float) - t) @ rot


def _yaw(rotation_y: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """Heading vectors (cos ry, 0, -sin ry) rotated by `rot`, their yaw read back the same way
    (atan2(-z, x)): the heading about the vertical axis of the rotated frame."""
    ry = np.asarray(rotation_y, dtype=float)
    heading = np.stack([np.cos(ry), np.zeros_like(ry), -np.sin(ry)], axis=-1)
    turned = heading @ rot.T
    return np.arctan2(-turned[..., 2], turned[..., 0])


def yaw_to_world(rotation_y: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """KITTI headings (rotation_y, rad) in a frame's camera coordinates to the first frame's,
    in (-pi, pi]. For a pose turning about y alone by a, this is rotation_y + a (wrapped);
    a pose that tilts is handled by carrying the heading vector, not by adding angles."""
    rot, _ = _pose(pose)
    return _yaw(rotation_y, rot)


def yaw_to_camera(rotation_y: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Headings in the first frame's camera coordinates to the frame's: the inverse of
    `yaw_to_world` (exactly so for a pose turning about y alone)."""
    rot, _ = _pose(pose)
    return _yaw(rotation_y, rot.T)
