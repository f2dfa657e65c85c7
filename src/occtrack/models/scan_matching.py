"""The 2-D laser's own motion from its scans alone: online scan matching for a recording without
odometry, so the scan tracker can put each scan in a fixed frame where walls and posts stay
still.

`ScanMatcher.update(angles, ranges)` takes one scan (beam angles in the sensor's frame, rad,
increasing; ranges m; `inf`, `nan`, negative and out-of-range values are no return, finite
ones the points) and returns the sensor's pose (x, y, heading) in the frame of the first scan:
x, y m, heading rad counter-clockwise, wrapped to [-pi, pi). `estimate_poses(scans)` runs one
over an `occtrack.io.scans.Scans`, a pose a scan.

Method: point-to-line ICP (A. Censi, "An ICP variant using a point-to-line metric", ICRA
2008), in its linearised least-squares form, against a small local map.

- The map is the last `map_scans` (3) keyframes, each a scan's points carried into the fixed
  frame by its estimated pose. A scan becomes a keyframe when the sensor has moved more than
  `keyframe_distance` (0.2 m) or turned more than `keyframe_angle` (5 deg) since the last one,
  or when fewer than `min_overlap` (half) of its points found a partner. A still sensor matches
  every scan to the same keyframe and does not drift; a moving one drifts by one match's error
  a keyframe, not a scan.
- Each map point carries a 2 x 2 information matrix W: a point on a surface W = n n^T, n the
  normal of the line fitted (principal axes) to its neighbours along its scan (the beams up to
  `normal_window` either side whose points lie within `normal_radius` of it, three points at
  least, the smaller scatter below `line_ratio` times the larger); an isolated return, or a
  blob that is no line (foliage, a far thin post), W = `point_weight` I (point-to-point). The
  cost is sum_i w_i e_i^T W_i e_i, e_i = R(h) p_i + t - q_i, q_i the map point nearest to the
  moved scan point p_i (`scipy.spatial.cKDTree`); the rotation is re-linearised every
  iteration, so the solution is exact at convergence.
- The search starts at the constant-velocity guess (the last pose moved on by the last step)
  and takes Gauss-Newton steps, up to `iterations` (20), with a Levenberg-Marquardt damping
  (`damping` times the mean information, shrinking 0.3-fold an iteration) so the well-pinned
  directions settle before a weakly pinned one moves, and a weak prior at the guess (`prior`)
  that keeps what the points leave open. The pairs are looked up again only after the pose
  moved by `requery` (5 mm); the search ends when a step moves less than 0.1 mm and 0.1 mrad.
- Outliers: a pair farther apart than `max_distance` (0.3 m) is none. Of the rest, the worst
  `trim` fraction (20 %) is dropped, but never a pair within `min_gate` (5 cm); so is any
  pair more than `outlier_factor` (3) times the median residual off (again never within
  `min_gate`); the rest get Cauchy weights w = 1 / (1 + r^2 / s^2), s = `kernel` (2) times
  the median residual, at least `min_scale` (1 cm). Residuals are distances to the map
  point's line (or to the point), in metres.
- People: a person walking in view is the outlier a tracker's scans always have. His points
  lie a step (10 cm and more at 1 m/s) off where the map saw him, so once the walls are
  aligned they fall past the gate or into the trimmed fraction, and the Cauchy weights mute
  the ones that still graze his old outline: a person crossing 1 to 4 m in front, hiding up
  to a fifth of an 86-degree view, adds some millimetres to the error (at most 6 mm in the
  tests' room, tests/test_scan_matching.py).
  What trimming cannot undo is a person who walks with the sensor (a robot following him)
  while the static scene pins the motion only weakly: his points then agree with "no motion"
  and outvote the rest.
- Failure: fewer than `min_correspondences` (10) pairs; a degenerate geometry (one straight
  wall, a corridor, a few far returns: the smallest eigenvalue of the normal matrix, the
  heading's row and column scaled by the points' root-mean-square range, below
  `min_information` or `min_condition` times the largest; checked after the third iteration
  too, to stop early); a result not finite, more than `max_distance` from the guess, or a
  step longer than `max_step` (0.3 m) or `max_turn` (20 deg). The pose is then the
  constant-velocity guess with the motion decayed by `decay` (0.8: a sensor that sees nothing
  slows to a stop instead of flying off), and after `patience` (3) failures in a row the map
  is re-anchored on the current scan at that guess. `update` never raises for what a scan
  holds and never returns NaN.

Not modelled: the motion during a sweep (a 10 Hz scanner sweeping 86 degrees in 24 ms moves
2.4 cm at 1 m/s while it does: no de-skewing) and loop closure (the pose drifts, slowly, as
all odometry does).

Speed: everything over points is vectorised; an iteration is some thirty numpy calls, a tree
query every second or third, and a keyframe costs a tree build and the normals. About 2 ms a
245-beam scan on one core of the project's machine under load (some 500 scans a second),
three to eight iterations a scan.

Why written by hand: scipy gives the KD-tree, the rest is numpy. The pip packages that
register point clouds are 3-D and heavier: kiss-icp (3-D lidar odometry; pydantic, typer,
rich), small_gicp and open3d (3-D, compiled; open3d hundreds of MB), simpleicp (3-D
point-to-plane; pandas, lmfit); a 2-D scan given to them as a flat 3-D cloud leaves z, roll
and pitch unconstrained. The one 2-D laser matcher on PyPI, karto-scanmatcher (OpenKarto's
correlative matcher), is a single undocumented GPL-3 binary release; the rest (csm,
laser_scan_matcher, cartographer) come with ROS.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

TURN = 2.0 * math.pi


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % TURN - math.pi


def compose(pose: np.ndarray, step: np.ndarray) -> np.ndarray:
    """pose (+) step: `step` (dx, dy, dheading), given in `pose`'s frame, applied to `pose`."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array([pose[0] + c * step[0] - s * step[1], pose[1] + s * step[0] + c * step[1],
                     wrap(pose[2] + step[2])])


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The step from pose a to pose b in a's frame: a (+) between(a, b) = b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])])


def transform(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (N, 2) of the frame at `pose` in the fixed frame."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + pose[:2]


def scan_points(angles: np.ndarray, ranges: np.ndarray, min_range: float = 0.0,
                max_range: float = math.inf) -> np.ndarray:
    """The returns of a scan as points (N, 2) in the sensor's frame, in beam order: finite
    ranges in (min_range, max_range) at finite angles; inf, nan and the rest are no return."""
    with np.errstate(invalid="ignore"):
        ok = (np.isfinite(ranges) & (ranges > min_range) & (ranges < max_range)
              & np.isfinite(angles))
    r, a = ranges[ok], angles[ok]
    return np.c_[r * np.cos(a), r * np.sin(a)]


def information(points: np.ndarray, window: int = 4, radius: float = 0.15,
                line_ratio: float = 0.1, point_weight: float = 0.1) -> np.ndarray:
    """Each point's information matrix (N, 3) as (W_xx, W_xy, W_yy): n n^T where its
    neighbours along the scan (up to `window` beams either side, within `radius` m) make a
    line of normal n, else `point_weight` I. Points in beam order."""
    n = len(points)
    if n == 0:
        return np.zeros((0, 3))
    padded = np.full((n + 2 * window, 2), np.nan)  # nan: no neighbour past either end
    padded[window:window + n] = points
    near = np.lib.stride_tricks.sliding_window_view(padded, 2 * window + 1, axis=0)
    ox, oy = near[:, 0] - points[:, :1], near[:, 1] - points[:, 1:]  # (N, 2w+1) offsets
    with np.errstate(invalid="ignore"):
        use = ox * ox + oy * oy <= radius * radius
    count = use.sum(axis=1)
    ox, oy = np.where(use, ox, 0.0), np.where(use, oy, 0.0)
    mx, my = ox.sum(axis=1) / count, oy.sum(axis=1) / count
    sxx = (ox * ox).sum(axis=1) - count * mx * mx  # the scatter about the neighbours' mean
    sxy = (ox * oy).sum(axis=1) - count * mx * my
    syy = (oy * oy).sum(axis=1) - count * my * my
    half_gap = np.hypot(0.5 * (sxx - syy), sxy)
    big = 0.5 * (sxx + syy) + half_gap
    small = 0.5 * (sxx + syy) - half_gap
    line = (count >= 3) & (small <= line_ratio * big) & (big > 0)
    along = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # the line's direction
    nx, ny = -np.sin(along), np.cos(along)
    return np.where(line[:, None], np.c_[nx * nx, nx * ny, ny * ny],
                    np.array([point_weight, 0.0, point_weight]))


def solve3(a: float, b: float, c: float, d: float, e: float, f: float, u: float, v: float,
           w: float) -> tuple[float, float, float]:
    """The solution of [[a, b, d], [b, c, e], [d, e, f]] z = (u, v, w) (symmetric), by
    cofactors in plain floats (numpy's solver costs more than the whole 3 x 3 arithmetic);
    nan when singular."""
    ca, cb, cd = c * f - e * e, d * e - b * f, b * e - c * d
    det = a * ca + b * cb + d * cd
    if det == 0.0 or not math.isfinite(det):
        return math.nan, math.nan, math.nan
    cc, ce, cf = a * f - d * d, b * d - a * e, a * c - b * b
    return ((ca * u + cb * v + cd * w) / det, (cb * u + cc * v + ce * w) / det,
            (cd * u + ce * v + cf * w) / det)


# the Levenberg-Marquardt damping shrinks by this factor an iteration; the search has converged
# when the damping is below _CONVERGED_DAMPING and a step moves less than _CONVERGED_STEP
# (m, and rad)
_DAMPING_DECAY = 0.3
_CONVERGED_DAMPING = 0.02
_CONVERGED_STEP = 1e-4
# the iteration after which a degenerate geometry ends the search
_EARLY_CHECK = 3


class ScanMatcher:
    """Online point-to-line ICP odometry of a 2-D laser (see the module docstring).

    max_distance: m; a pair farther apart is an outlier, and the guess must be right to
        about this much (the capture range).
    iterations: Gauss-Newton steps at most a scan.
    trim: the worst fraction of the pairs dropped (but never one within min_gate m).
    outlier_factor, min_gate: pairs more than outlier_factor times the median residual off
        (and more than min_gate m) are dropped too.
    kernel, min_scale: the Cauchy weights' scale, kernel times the median residual, at
        least min_scale m.
    keyframe_distance, keyframe_angle: m and rad of motion after which a scan becomes a
        keyframe; map_scans: keyframes the local map keeps; min_overlap: a scan with fewer
        of its points paired becomes a keyframe too.
    min_correspondences: fewer pairs and the match fails.
    min_condition, min_information: the scaled normal matrix's smallest eigenvalue below
        min_condition times the largest, or below min_information (the information of that
        many points on a line), and the match fails (degenerate geometry).
    prior: the weight of the constant-velocity guess, in points' information.
    damping: the first iteration's Levenberg-Marquardt damping, in mean information.
    requery: m (heading at the points' range) the pose moves before the pairs are redone.
    decay: the fraction of the last step a failed match carries on with.
    patience: failed matches in a row after which the map is re-anchored on the scan.
    max_step, max_turn: m and rad; a longer step from the last pose fails the match.
    normal_window, normal_radius, line_ratio, point_weight: the map's normals
        (`information`).
    min_range, max_range: m; returns outside (min_range, max_range) are no return.

    After `update`: `pose` (3,), `velocity` (the last step, in the previous pose's frame),
    `status` ("first", "matched" or "guess"), `failure` (why a guess: "degenerate", "too
    few pairs", ...; "" when matched), `correspondences` (pairs used at the end), `fitness`
    (their mean distance, m; nan when unmatched), `eigenvalues` (of the scaled normal
    matrix), `keyframes` (in the map).
    """

    def __init__(self, max_distance: float = 0.3, iterations: int = 20, trim: float = 0.2,
                 outlier_factor: float = 3.0, min_gate: float = 0.05, kernel: float = 2.0,
                 min_scale: float = 0.01,
                 keyframe_distance: float = 0.2, keyframe_angle: float = math.radians(5.0),
                 map_scans: int = 3, min_overlap: float = 0.5, min_correspondences: int = 10,
                 min_condition: float = 1e-3,
                 min_information: float = 0.5, prior: float = 0.04,
                 damping: float = 0.3, requery: float = 0.005, decay: float = 0.8,
                 patience: int = 3, max_step: float = 0.3, max_turn: float = 0.35,
                 normal_window: int = 4, normal_radius: float = 0.15, line_ratio: float = 0.1,
                 point_weight: float = 0.1, min_range: float = 0.0,
                 max_range: float = math.inf) -> None:
        if not max_distance > 0:
            raise ValueError(f"max_distance must be positive, not {max_distance}")
        if not iterations >= 1:
            raise ValueError(f"iterations must be at least 1, not {iterations}")
        if not 0.0 <= trim < 1.0:
            raise ValueError(f"trim must be in [0, 1), not {trim}")
        if not map_scans >= 1:
            raise ValueError(f"map_scans must be at least 1, not {map_scans}")
        if not 0.0 <= decay <= 1.0:
            raise ValueError(f"decay must be in [0, 1], not {decay}")
        self.max_distance = float(max_distance)
        self.iterations = int(iterations)
        self.trim = float(trim)
        self.outlier_factor = float(outlier_factor)
        self.min_gate = float(min_gate)
        self.kernel = float(kernel)
        self.min_scale = float(min_scale)
        self.keyframe_distance = float(keyframe_distance)
        self.keyframe_angle = float(keyframe_angle)
        self.map_scans = int(map_scans)
        self.min_overlap = float(min_overlap)
        self.min_correspondences = max(3, int(min_correspondences))
        self.min_condition = float(min_condition)
        self.min_information = float(min_information)
        self.prior = float(prior)
        self.damping = float(damping)
        self.requery = float(requery)
        self.decay = float(decay)
        self.patience = int(patience)
        self.max_step = float(max_step)
        self.max_turn = float(max_turn)
        self.normal_window = int(normal_window)
        self.normal_radius = float(normal_radius)
        self.line_ratio = float(line_ratio)
        self.point_weight = float(point_weight)
        self.min_range = float(min_range)
        self.max_range = float(max_range)
        self.reset()

    def reset(self) -> None:
        """Forget everything: the next scan is the first, its frame the fixed one."""
        self.pose = np.zeros(3)
        self.velocity = np.zeros(3)
        self.status = "first"
        self.correspondences = 0
        self.fitness = math.nan
        self.failure = ""
        self.eigenvalues = np.zeros(3)
        self._frames: list[np.ndarray] = []
        self._key_pose: np.ndarray | None = None
        self._tree: cKDTree | None = None
        self._table = np.zeros((0, 6))
        self._failures = 0
        self._started = False

    @property
    def keyframes(self) -> int:
        return len(self._frames)

    def update(self, angles, ranges) -> np.ndarray:
        """Match one scan; the sensor's pose (x, y, heading) in the first scan's frame."""
        angles = np.asarray(angles, float).ravel()
        ranges = np.asarray(ranges, float).ravel()
        if angles.shape != ranges.shape:
            raise ValueError(f"{len(angles)} angles but {len(ranges)} ranges")
        if len(angles) > 1 and not np.all(np.diff(angles) > 0):
            order = np.argsort(angles, kind="stable")
            angles, ranges = angles[order], ranges[order]
        points = scan_points(angles, ranges, self.min_range, self.max_range)
        guess = compose(self.pose, self.velocity)
        if not self._started:  # the first scan: its frame is the fixed one
            self._started = True
            self.status, self.correspondences, self.fitness = "first", 0, math.nan
            self._add_keyframe(points, self.pose)
            return self.pose.copy()
        self.correspondences, self.fitness, self.failure = 0, math.nan, "no map"
        pose, overlap = (None, 0.0) if self._tree is None else self._match(points, guess)
        if pose is None:
            self.status, self._failures = "guess", self._failures + 1
            self.velocity = self.decay * self.velocity
            self.pose = compose(self.pose, self.velocity)
            if len(points) >= self.min_correspondences and (
                    self._tree is None or self._failures >= self.patience):
                self._frames.clear()  # re-anchored: the map starts afresh at the guess
                self._add_keyframe(points, self.pose)
            return self.pose.copy()
        self.status, self._failures = "matched", 0
        self.velocity = between(self.pose, pose)
        self.pose = pose
        step = between(self._key_pose, pose)
        if (math.hypot(step[0], step[1]) > self.keyframe_distance
                or abs(step[2]) > self.keyframe_angle or overlap < self.min_overlap):
            self._add_keyframe(points, pose)
        return self.pose.copy()

    def _add_keyframe(self, points: np.ndarray, pose: np.ndarray) -> None:
        if len(points) < self.min_correspondences:
            return
        world = transform(pose, points)
        info = information(world, self.normal_window, self.normal_radius, self.line_ratio,
                           self.point_weight)
        # rho: 1 / the largest eigenvalue of W, so that rho e^T W e is a squared distance (m^2)
        big = 0.5 * (info[:, 0] + info[:, 2]) + np.hypot(0.5 * (info[:, 0] - info[:, 2]),
                                                         info[:, 1])
        self._frames.append(np.c_[world, info, 1.0 / np.maximum(big, 1e-12)])
        del self._frames[:-self.map_scans]
        self._key_pose = pose.copy()
        self._table = np.concatenate(self._frames)
        self._tree = cKDTree(self._table[:, :2])

    def _match(self, points: np.ndarray, guess: np.ndarray) -> tuple[np.ndarray | None, float]:
        """The pose that best aligns `points` with the map, from `guess`, and the fraction of
        points that found a partner; None for the pose when the match failed (`failure`
        says why)."""
        n = len(points)
        if n < self.min_correspondences:
            self.failure = "too few points"
            return None, 0.0
        x0, x1, x2 = (float(v) for v in guess)
        # the heading's lever: the points' root-mean-square range, m; the normal matrix with
        # the heading's row and column divided by it compares the heading's information with
        # the translation's (both per metre)
        lever2 = max(float(np.mean(points[:, 0]**2 + points[:, 1]**2)), 0.01)
        prior = self.prior
        keep_fraction = 1.0 - self.trim
        factor2, floor2 = self.outlier_factor**2, self.min_gate**2
        kernel2, min_scale2 = self.kernel**2, self.min_scale**2
        max_distance, table, query = self.max_distance, self._table, self._tree.query
        lever = math.sqrt(lever2)
        overlap, used, h, queried = 0.0, 0, None, None
        for iteration in range(self.iterations):
            c, s = math.cos(x2), math.sin(x2)
            rotated = points @ np.array([[c, s], [-s, c]])
            moved = rotated + np.array([x0, x1])
            # the pairs are looked up again only when the pose has moved by more than
            # `requery` (m at the points' range) since they were: the tree's query is most of
            # an iteration's cost, and a few millimetres' move changes few pairs
            if (queried is None or abs(x0 - queried[0]) + abs(x1 - queried[1])
                    + abs(x2 - queried[2]) * lever > self.requery):
                dist, j = query(moved, distance_upper_bound=max_distance)
                sel = np.flatnonzero(dist <= max_distance)
                queried = (x0, x1, x2)
                m = len(sel)
                overlap = m / n
                if m < self.min_correspondences:
                    self.failure = "too few pairs"
                    return None, overlap
                near = table[j[sel]]  # x, y, W_xx, W_xy, W_yy, rho of the map points
                a, b, cc, rho = near[:, 2], near[:, 3], near[:, 4], near[:, 5]
                kept = max(self.min_correspondences, int(keep_fraction * m))
                half = m // 2
                kth = (half, kept - 1) if half < kept - 1 else (kept - 1, half)
            ex, ey = (moved[sel] - near[:, :2]).T
            wex, wey = a * ex + b * ey, b * ex + cc * ey
            # the squared residual in metres: the distance to the line, or to the point
            r2 = rho * (ex * wex + ey * wey)
            order = np.partition(r2, kth)
            gate2 = min(max(order[kept - 1], floor2), max(factor2 * order[half], floor2))
            use = r2 <= gate2
            used = int(np.count_nonzero(use))
            if used < self.min_correspondences:
                self.failure = "too few pairs"
                return None, overlap
            vy, vx = rotated[sel].T  # d(moved)/d(heading) = (-rotated_y, rotated_x)
            vx = -vx
            wvx, wvy = a * vx + b * vy, b * vx + cc * vy
            terms = np.empty((9, m))
            terms[0], terms[1], terms[2], terms[3], terms[4] = a, b, cc, wvx, wvy
            terms[5] = vx * wvx + vy * wvy
            terms[6], terms[7] = wex, wey
            terms[8] = vx * wex + vy * wey
            # Cauchy weights, 1 / (1 + r^2 / s^2), s = `kernel` times the median residual
            weight = use / (1.0 + r2 / max(kernel2 * order[half], min_scale2))
            hxx, hxy, hyy, hxt, hyt, htt, gx, gy, gt = (terms @ weight).tolist()
            h = (hxx, hxy, hyy, hxt, hyt, htt)
            # Levenberg-Marquardt damping, shrinking every iteration: the well-pinned
            # directions (usually the heading) settle first, a weakly pinned one follows once
            # the pairs are right instead of running off on the first, wrong ones; and a weak
            # prior at the guess, so a direction the points leave open keeps the guess
            damp = self.damping * _DAMPING_DECAY**iteration
            mu = damp * (hxx + hyy + htt / lever2) / 3.0
            off2 = wrap(x2 - guess[2])
            dx, dy, dt = solve3(hxx + prior + mu, hxy, hyy + prior + mu, hxt, hyt,
                                htt + (prior + mu) * lever2,
                                -gx - prior * (x0 - guess[0]), -gy - prior * (x1 - guess[1]),
                                -gt - prior * lever2 * off2)
            if not (math.isfinite(dx) and math.isfinite(dy) and math.isfinite(dt)):
                self.failure = "singular"
                return None, overlap
            x0, x1, x2 = x0 + dx, x1 + dy, x2 + dt
            if (damp < _CONVERGED_DAMPING and math.hypot(dx, dy) < _CONVERGED_STEP
                    and abs(dt) < _CONVERGED_STEP):
                break
            if iteration == _EARLY_CHECK and self._degenerate(h, lever):
                return None, overlap  # hopeless: no need to iterate on
        x = np.array([x0, x1, x2])
        self.fitness = float(dist[sel][use].mean())
        self.correspondences = used
        if self._degenerate(h, lever):
            return None, overlap
        if not np.all(np.isfinite(x)):
            self.failure = "singular"
            return None, overlap
        x[2] = wrap(x[2])
        step = between(guess, x)
        if math.hypot(step[0], step[1]) > self.max_distance or abs(step[2]) > self.max_turn:
            self.failure = "too far from the guess"
            return None, overlap
        step = between(self.pose, x)
        if math.hypot(step[0], step[1]) > self.max_step or abs(step[2]) > self.max_turn:
            self.failure = "too long a step"
            return None, overlap
        self.failure = ""
        return x, overlap


    def _degenerate(self, h: tuple, lever: float) -> bool:
        """Whether the normal matrix `h` (its six entries) leaves a direction open: its
        smallest eigenvalue, with the heading's row and column divided by `lever` (the
        points' root-mean-square range, so that the heading's information compares with the
        translation's, both per metre), below `min_information` or `min_condition` times the
        largest. Keeps the eigenvalues in `eigenvalues`."""
        hxx, hxy, hyy, hxt, hyt, htt = h
        lam = np.linalg.eigvalsh(np.array([[hxx, hxy, hxt / lever], [hxy, hyy, hyt / lever],
                                           [hxt / lever, hyt / lever, htt / lever**2]]))
        self.eigenvalues = lam
        if lam[0] > max(self.min_condition * lam[-1], self.min_information):
            return False
        self.failure = "degenerate"
        return True


def estimate_poses(scans, matcher: ScanMatcher | None = None, **settings) -> np.ndarray:
    """The sensor's pose (S, 3) (x, y, heading; the first scan's frame) at every scan of
    `scans` (an `occtrack.io.scans.Scans`, or any iterable of (time, angles, ranges)), by a
    `ScanMatcher` (`matcher`, else a new one made with `settings`)."""
    if matcher is None:
        matcher = ScanMatcher(**settings)
    elif settings:
        raise TypeError("give a matcher or its settings, not both")
    poses = [matcher.update(angles, ranges) for _, angles, ranges in scans]
    return np.array(poses, dtype=float).reshape(-1, 3)
