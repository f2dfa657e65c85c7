"""3D boxes on the ground plane (a lidar detector's cars and people): `GroundTracker`.

    tracker = GroundTracker()                           # ground_config(): 10 Hz
    for boxes3d, scores, classes, pose in frames:        # boxes3d (M, 7): h w l x y z ry
        tracks = tracker.update(boxes3d, scores, classes, pose=pose)
        tracks.ids, tracks.boxes3d, tracks.confidence, tracks.detection_index

Boxes are KITTI's: h, w, l in metres, x, y, z the bottom centre in the camera's coordinates
(x right, y down, z forward), rotation_y the heading about the vertical axis. `pose` (3, 4) is
the camera's pose [R | t] in a fixed world frame (KITTI's `poses/NNNN.txt`: world point =
R p + t); without poses the camera is taken as still and its own motion falls to the noise.

The state. The same GM-PMB filter as the image boxes (`Tracker`), in the same state: per
ground axis (world x, world z) the centre, velocity and half-size of the box's footprint, the
axis-aligned hull of its four ground corners in the world's axes (a car that turns keeps its
hull nearly, and the world's axes do not turn with the sensor). Metres and seconds, counted
in decimetres inside the filter (`UNIT`); the noises, in units of a box's size, serve any
sensor (`occtrack.models.box`). Elevation and heading are carried from the object's last
detection, its size (h, w, l) is the mean of its detections' sizes, each weighted by
1 / range^2 (a solid object keeps its size; a lidar's points on it fall off as 1 / r^2): an
object that took a detection reports that detection's centre and heading at its mean size, a
coasting one its last detection's heading at the filter's centre.

The sensor's motion. The filter's frame is the square of +-`reach` metres around the sensor,
re-centred on it every frame: the sensor's travel enters the prediction as the camera's shift
does in the image (an exact translation of every component), so the survival region goes with
the sensor wherever it drives.

Occlusion is the sensor's view (`occtrack.occlusion.sensor_view`): nearer boxes hide the
angles behind them, under the model `config.occlusion` names. What a miss says depends on
where the object is: a lidar detector finds nearly every car it can see within 40 m and
fewer beyond, so the filter's stationary P_D is a profile by class and range octave, learnt
from the tracker's own objects that could be seen (`occtrack.models.detection_profile`, each
object weighted by the probability that it is real), and an object missed where the
detector does not miss goes sooner. A vehicle or a walker hidden
from the sensor goes on moving: the ground's defaults (`GROUND_DEFAULTS`) keep a coasting
object's velocity (`coast_velocity_time` infinite), where the image boxes' let it fade in
0.1 s.

One place, one object. A lidar detector scores each class on its own, and one object can
come out twice (a cyclist also as a pedestrian, at a lower score). Two solid objects cannot
stand on the same ground: a box whose footprint overlaps a higher-scored box's by half of the
smaller footprint or more is dropped before the filter, with a count
(`occtrack.models.footprints`). Otherwise the second class's track is a false object for as
long as the first is a true one.

What an object's scores say (`score_evidence`). A lidar detector reports the same wall or
hedge as a car frame after frame, and once such a track is confirmed the filter takes its
detections as an object's, however low their scores. Each object's scores are therefore
weighed as evidence that it is real at all: the sum over the detections it took of
log f_O(s) / f_C(s) is the log-odds of a Bernoulli "real, or a persistent false object" with
even prior odds (scores independent given the class), and the reported confidence is the
filter's times that probability. f_O and f_C are the score densities of objects and clutter
learnt online from the filter's own association marginals
(`ScoreLearner.log_likelihood_ratio`), in bins a unit of log-odds wide (a lidar detector's
logistic scores crowd above .9, all in one of the filter's probability bins), one learner for
every class (one a class was measured worse on KITTI's walkers, whose few true detections
cannot outweigh the false tracks' in their own). docs/kitti-3d.md has the scores.

What a track follows can change: a track that followed a car can go on along a hedge when the
car leaves, and a far car's first low scores say little once it has come near. So "real" is
not fixed for life but a two-state Markov chain that flips either way at the rate
1 / `EVIDENCE_MEMORY` (`forget_evidence`): between frames the probability relaxes towards
even odds, P - 1/2 shrinking by exp(-2 dt / EVIDENCE_MEMORY), then the frame's score weighs in
(the forward recursion of that hidden Markov model). Evidence older than the memory counts
little, and a run of good scores lifts a track that began badly within a few frames.

One object's scores in consecutive frames are not independent draws: the detector sees the
same car from nearly the same place (their log-likelihood ratios correlate at about .8 from
one frame to the next on KITTI's cars and walkers). Summed as independent they overstate the
evidence, and the confidence with them; each frame's log-likelihood ratio is therefore
weighed by `SCORE_EVIDENCE_WEIGHT` (1/2: a frame's score counts as half an independent one).

A file written after the frames can also use what came after each frame (`track_kitti`): a
far car's first low scores are judged with the next `EVIDENCE_LOOKAHEAD` seconds' scores too,
the same chain run backwards (`lookahead_evidence`, the backward message of a fixed-lag
smoother), so a real object's first frames are reported with it and a false one's are not. An
online loop (`GroundTracker.update`) reports the filtered confidence.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from occtrack.config import TrackerConfig
from occtrack.models.detection_profile import DetectionProfile
from occtrack.models.footprints import DUPLICATE_OVERLAP, duplicates, footprints
from occtrack.models.score_model import ScoreLearner
from occtrack.occlusion.sensor_view import SensorViewGeometry, sensor_view_occlusion
from occtrack.tracker.boxes import as_array, check_time
from occtrack.tracker.tracker import Tracker

REACH = 80.0
"""m: the filter holds the square of +-REACH around the sensor (a lidar detector's range)."""
UNIT = 0.1
"""m: the filter's length unit on the ground. The filter's few absolute lengths are an image's
pixels (a box under 2 units wide is degenerate and leaves the survival region; an edge within
`border_margin` units of the border is the border's): in decimetres they hold for a person's
0.5 m footprint as for a car's."""
GROUND_DEFAULTS = {"fps": 10.0, "coast_velocity_time": math.inf}
"""TrackerConfig values where the ground differs from the image boxes' defaults (a KITTI
lidar's 10 Hz; a hidden object keeps its velocity); `ground_config` applies them."""
SHAPE_MEMORY = 10.0
"""s: how long an object's last detected shape is kept after it was last reported."""
SIZE_NEAR = 5.0
"""m: nearer than this an object's size is weighed as if it were this far (`_add_sizes`): a
car that near fills much of the sensor's view, and its points no longer grow as 1 / r^2."""
BOX3D_COLUMNS = "h w l x y z rotation_y"
EVIDENCE_MEMORY = SHAPE_MEMORY
"""s: an object's evidence that it is real flips at the rate 1 / EVIDENCE_MEMORY (see the
module): the tracker remembers what an object is for as long as it keeps its shape."""
SCORE_EVIDENCE_WEIGHT = 0.5
"""What one frame's score log-likelihood ratio counts for in an object's evidence (see the
module): consecutive scores of one object are correlated, so each counts as half an
independent one. Chosen with `EVIDENCE_LOOKAHEAD` on five KITTI sequences (0000, 0003, 0005,
0009, 0017) and checked on the other five (docs/kitti-3d.md)."""
EVIDENCE_LOOKAHEAD = 0.2
"""s: how far past a frame `track_kitti` looks for scores that weigh on that frame's
confidence (two frames at 10 Hz; 0: the filtered confidence, as online)."""


def forget_evidence(log_odds: float, elapsed: float, memory: float = EVIDENCE_MEMORY) -> float:
    """The log-odds that an object is real after `elapsed` seconds of a two-state chain that
    flips either way at the rate 1 / memory: P - 1/2 = tanh(log_odds / 2) / 2 shrinks by
    exp(-2 elapsed / memory) (stable where P rounds to 1)."""
    keep = math.exp(-2.0 * max(elapsed, 0.0) / memory)
    if keep >= 1.0:
        return log_odds
    return 2.0 * math.atanh(math.tanh(log_odds / 2.0) * keep)


def lookahead_evidence(llr: npt.ArrayLike, elapsed: npt.ArrayLike,
                       memory: float = EVIDENCE_MEMORY) -> float:
    """log p(later scores | real now) / p(later scores | not real now): the backward message
    of the two-state chain of `forget_evidence`. `llr` (k,) the weighted score log-likelihood
    ratios of the object's next k frames (0 where it took no detection), `elapsed` (k,) the
    seconds from each frame before to that frame. Added to a frame's filtered log-odds it
    gives the log-odds given the later frames too (a fixed-lag smoother)."""
    message = 0.0
    for ratio, dt in zip(np.asarray(llr, float)[::-1], np.asarray(elapsed, float)[::-1],
                         strict=True):
        m = ratio + message  # log ratio of the frames from that one on, given its state
        keep = math.exp(-2.0 * max(float(dt), 0.0) / memory)
        stay, flip = math.log1p(keep), math.log1p(-keep) if keep < 1 else -math.inf
        message = float(np.logaddexp(stay + m, flip) - np.logaddexp(flip + m, stay))
    return message


@dataclass(frozen=True)
class GroundTracks:
    """The objects reported at one frame, n of them, sorted by id.

    Attributes:
        ids: (n,) int track ids, unique, never reused.
        boxes3d: (n, 7) h, w, l, x, y, z, rotation_y in this frame's camera coordinates.
        existence: (n,) probability that each object exists.
        confidence: (n,) probability that each box is a real object there (`Tracks`).
        velocities: (n, 2) ground velocity (x, z) in this frame's camera axes, m / s.
        detection_index: (n,) int, the detection each object took (-1: coasting).
        classes: (n,) int class of each object, fixed for life.
        occluded: (n,) bool, coasting with its miss put down to occlusion.
        evidence: (n,) log-odds that each object is real given its scores so far (the
            confidence is the filter's times its probability; inf without score evidence).
        score_llr: (n,) what this frame's score added to `evidence` (0: no detection).
    """

    ids: np.ndarray
    boxes3d: np.ndarray
    existence: np.ndarray
    confidence: np.ndarray
    velocities: np.ndarray
    detection_index: np.ndarray
    classes: np.ndarray
    occluded: np.ndarray
    evidence: np.ndarray | None = None
    score_llr: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def coasting(self) -> np.ndarray:
        return self.detection_index < 0

    def select(self, keep: np.ndarray) -> GroundTracks:
        """The objects where `keep` (n,) bool is True, in the same order (`Tracks.select`)."""
        return GroundTracks(self.ids[keep], self.boxes3d[keep], self.existence[keep],
                            self.confidence[keep], self.velocities[keep],
                            self.detection_index[keep], self.classes[keep], self.occluded[keep],
                            None if self.evidence is None else self.evidence[keep],
                            None if self.score_llr is None else self.score_llr[keep])


def ground_config(values: dict | None = None, source: str = "configuration") -> TrackerConfig:
    """A TrackerConfig for the ground: `GROUND_DEFAULTS` under the given values."""
    return TrackerConfig.from_dict({**GROUND_DEFAULTS, **(values or {})}, source)


def check_boxes3d(boxes3d: npt.ArrayLike) -> np.ndarray:
    """(M, 7) finite boxes with positive h, w, l, or a ValueError saying which is not."""
    boxes = as_array(boxes3d, "boxes3d", f"(M, 7): {BOX3D_COLUMNS}")
    if boxes.size == 0:
        return boxes.reshape(0, 7)
    if boxes.ndim != 2 or boxes.shape[1] != 7:
        raise ValueError(f"boxes3d must be (M, 7) ({BOX3D_COLUMNS}), not {boxes.shape}")
    bad = ~np.isfinite(boxes).all(axis=1)
    if bad.any():
        raise ValueError(f"boxes3d row {int(np.argmax(bad))} is not finite")
    small = ~(boxes[:, :3] > 0).all(axis=1)
    if small.any():
        raise ValueError(f"boxes3d row {int(np.argmax(small))}: h, w and l must be positive, "
                         f"not {boxes[np.argmax(small), :3].tolist()}")
    return boxes


def check_pose(pose: npt.ArrayLike | None) -> np.ndarray:
    """A finite (3, 4) [R | t]; None: the identity."""
    if pose is None:
        return np.eye(3, 4)
    p = as_array(pose, "pose", "(a 3 x 4 matrix [R | t])")
    if p.shape != (3, 4) or not np.isfinite(p).all():
        raise ValueError(f"pose must be a finite 3 x 4 matrix [R | t], not shape {p.shape}")
    return p


def heading_vector(yaw: np.ndarray) -> np.ndarray:
    """(N, 3) the unit vector along a KITTI heading rotation_y: (cos, 0, -sin)."""
    return np.stack([np.cos(yaw), np.zeros_like(yaw), -np.sin(yaw)], axis=-1)


def heading_of(vectors: np.ndarray) -> np.ndarray:
    """The rotation_y of (N, 3) vectors (their ground-plane direction)."""
    return np.arctan2(-vectors[:, 2], vectors[:, 0])


def ground_corners(boxes3d: np.ndarray) -> np.ndarray:
    """(M, 4, 3) the four bottom corners of KITTI 3D boxes, in the boxes' camera frame."""
    xz = footprints(boxes3d)[:, ::-1]  # (clockwise in (x, z), as this has always listed them)
    y = np.broadcast_to(np.asarray(boxes3d, dtype=float).reshape(-1, 7)[:, 4, None], xz.shape[:2])
    return np.stack([xz[..., 0], y, xz[..., 1]], axis=-1)


class GroundTracker:
    """Gaussian-mixture PMB tracker of 3D boxes on the ground plane (see the module).

    Args:
        config: every setting (`TrackerConfig`; default `ground_config()`); `fps` sets the
            time step without timestamps, `occlusion` the sensor-view model; `image_size` and
            `camera_motion` are the ground tracker's own (the square around the sensor, the
            poses).
        reach: metres around the sensor that the filter holds.
        score_evidence: weigh each object's scores as evidence that it is real (see the
            module); False reports the filter's confidence alone.
        duplicate_overlap: a box whose footprint and a higher-scored box's overlap by at least
            this share of the smaller one is the same object seen twice and is dropped
            (`occtrack.models.footprints`; counted in `duplicates_dropped`); None keeps every
            box.
        evidence_weight: what one frame's score log-likelihood ratio counts for in the
            evidence (`SCORE_EVIDENCE_WEIGHT`; 1: every score an independent draw).
    """

    def __init__(self, config: TrackerConfig | None = None, reach: float = REACH,
                 score_evidence: bool = True,
                 duplicate_overlap: float | None = DUPLICATE_OVERLAP,
                 evidence_weight: float = SCORE_EVIDENCE_WEIGHT):
        if config is not None and not isinstance(config, TrackerConfig):
            raise ValueError(f"config must be a TrackerConfig, not {type(config).__name__}")
        if not (math.isfinite(reach) and reach > 0):
            raise ValueError(f"reach must be a positive number of metres, not {reach}")
        c = config or ground_config()
        self.reach = float(reach)
        self.score_evidence = bool(score_evidence)
        if duplicate_overlap is not None and not 0 < duplicate_overlap <= 1:
            raise ValueError(f"duplicate_overlap must be in (0, 1] or None, not "
                             f"{duplicate_overlap}")
        self.duplicate_overlap = duplicate_overlap
        if not (math.isfinite(evidence_weight) and evidence_weight >= 0):
            raise ValueError(f"evidence_weight must be a number >= 0, not {evidence_weight}")
        self.evidence_weight = float(evidence_weight)
        side = 2 * self.reach / UNIT
        self.config = replace(c, image_size=(side, side), camera_motion="none")
        self.geometry = SensorViewGeometry(c.occlusion_gain, *c.occlusion_ramp,
                                           sensor=np.full(2, side / 2))
        self.occlusion = sensor_view_occlusion(c.occlusion, self.geometry,
                                               c.occluder_min_existence)
        self.reset()

    def reset(self) -> None:
        """Forget every object and start again."""
        # the filter reports every object it holds, confident or not (each one's hits and
        # misses teach the detection profile); the floor is applied here (`update`)
        self.tracker = Tracker(replace(self.config, report_min_confidence=0.0), self.occlusion)
        self.detection_profile = DetectionProfile(self.config.stationary_detectability)
        self.tracker.filter.detection_profile = self._profile_of_components
        self._origin: np.ndarray | None = None  # world (x, z) of the filter frame's corner
        self._time = 0.0  # s since the first frame
        self._steps = 0
        self.duplicates_dropped = 0  # boxes dropped as another box's duplicate, so far
        self._shape: dict[int, np.ndarray] = {}  # id -> h, w, l, world y, world yaw, time
        self._size: dict[int, np.ndarray] = {}  # id -> sum of w h, w w, w l, of w; time
        c = self.config  # the score densities the evidence reads (see the module)
        self._evidence_scores = ScoreLearner(c.score_floor, c.clutter_score_power,
                                             log_odds=True)
        self._evidence: dict[int, list] = {}  # id -> [log-odds that it is real, time last seen]

    def update(self, boxes3d: npt.ArrayLike, scores: npt.ArrayLike | None = None,
               classes: npt.ArrayLike | None = None, pose: npt.ArrayLike | None = None,
               timestamp: float | None = None) -> GroundTracks:
        """Track one frame's 3D detections (M, 7) with their scores (M,) in [0, 1] (None:
        all 1), classes (M,) and the camera's pose (3, 4) in the world (None: the first
        frame's place); `timestamp` in seconds (None: 1 / fps after the last frame)."""
        boxes = check_boxes3d(boxes3d)
        P = check_pose(pose)
        R, t = P[:, :3], P[:, 3]
        given = np.ones(len(boxes)) if scores is None else \
            np.asarray(scores, dtype=float).reshape(-1)
        kept = np.arange(len(boxes))
        if self.duplicate_overlap is not None and len(given) == len(boxes) and (
                classes is None or np.size(classes) == len(boxes)):  # (else update says why)
            kept = np.flatnonzero(~duplicates(boxes, given, self.duplicate_overlap))
            self.duplicates_dropped += len(boxes) - len(kept)
        if len(kept) < len(boxes):
            scores = None if scores is None else given[kept]
            classes = None if classes is None else np.asarray(classes).reshape(-1)[kept]
        corners = ground_corners(boxes[kept]) @ R.T + t  # (M, 4, 3) in the world
        origin = t[[0, 2]] - self.reach
        shift = np.zeros(2) if self._origin is None else self._origin - origin
        low = (corners[..., [0, 2]].min(axis=1) - origin) / UNIT
        high = (corners[..., [0, 2]].max(axis=1) - origin) / UNIT
        ltwh = np.concatenate([low, high - low], axis=1)
        affine = np.array([[1.0, 0.0, shift[0] / UNIT], [0.0, 1.0, shift[1] / UNIT]])
        tracks = self.tracker.update(ltwh, scores, classes, timestamp, "ltwh", affine)
        index = tracks.detection_index.copy()  # (of the kept boxes: of the given ones)
        index[index >= 0] = kept[index[index >= 0]]
        tracks = replace(tracks, detection_index=index)
        self._origin = origin
        if timestamp is not None:
            self._time = check_time(timestamp, "timestamp")
        else:
            self._time += self.tracker.filter.dt if self._steps else 0.0
        self._steps += 1
        took = index >= 0  # (every object the filter holds, reported or not)
        self._add_sizes(tracks.ids[took], boxes[index[took]])
        odds, llr = (self._real_log_odds(tracks, given, kept) if self.score_evidence
                     else (np.full(len(tracks), np.inf), np.zeros(len(tracks))))
        real = 1.0 / (1.0 + np.exp(-odds))
        seen = took | ~tracks.occluded  # (a miss put down to occlusion says nothing of P_D)
        centres = tracks.boxes[seen, :2] + tracks.boxes[seen, 2:] / 2
        self.detection_profile.update(tracks.classes[seen], self._ranges(centres), took[seen],
                                      real[seen], self.tracker.filter.dt)
        tracks = replace(tracks, confidence=tracks.confidence * real)
        floor = self.config.report_min_confidence
        if floor > 0:
            shown = tracks.confidence >= floor
            tracks, odds, llr = tracks.select(shown), odds[shown], llr[shown]
        return self._report(tracks, boxes, R, t, origin, odds, llr)

    def _real_log_odds(self, tracks, scores: np.ndarray,
                       kept: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) the log-odds that each object is real given the scores of the detections it
        took (see the module; the filter's confidence is multiplied by its probability), and
        (n,) what this frame's score added. `scores` are the given boxes', `kept` the rows the
        filter saw (the others were duplicates)."""
        n = len(tracks)
        llr = np.zeros(n)
        took = tracks.detection_index >= 0
        self._evidence_scores.update(scores[kept], self.tracker.filter.clutter_probability,
                                     self.tracker.filter.dt)
        if took.any():
            llr[took] = self.evidence_weight * self._evidence_scores.log_likelihood_ratio(
                scores[tracks.detection_index[took]])
        odds = np.empty(n)
        for i in range(n):
            entry = self._evidence.setdefault(int(tracks.ids[i]), [0.0, self._time])
            entry[0] = forget_evidence(entry[0], self._time - entry[1]) + llr[i]
            entry[1] = self._time
            odds[i] = entry[0]
        return odds, llr

    def _ranges(self, centres: np.ndarray) -> np.ndarray:
        """(n,) m from the sensor to points (n, 2) in the filter's frame."""
        offset = centres - self.geometry.sensor
        return np.hypot(offset[:, 0], offset[:, 1]) * UNIT

    def _profile_of_components(self, means: np.ndarray, classes: np.ndarray) -> np.ndarray:
        """The filter's hook: each component's stationary P_D from the learnt profile (the
        Poisson part's, class -1, the configured one)."""
        return self.detection_profile.probability(classes, self._ranges(means[:, :, 0]))

    def _report(self, tracks, boxes: np.ndarray, R: np.ndarray, t: np.ndarray,
                origin: np.ndarray, evidence: np.ndarray, score_llr: np.ndarray) -> GroundTracks:
        n = len(tracks)
        out = np.zeros((n, 7))
        took = tracks.detection_index >= 0
        out[took] = boxes[tracks.detection_index[took]]
        out[took, :3] = self.mean_sizes(tracks.ids[took])
        if took.any():  # remember each detected object's shape, elevation and heading
            world_y = (boxes[tracks.detection_index[took], 3:6] @ R.T + t)[:, 1]
            world_yaw = heading_of(heading_vector(out[took, 6]) @ R.T)
            for i, k in enumerate(np.flatnonzero(took)):
                self._shape[int(tracks.ids[k])] = np.array(
                    [*out[k, :3], world_y[i], world_yaw[i], self._time])
        coast = np.flatnonzero(~took)
        if len(coast):
            centre = (tracks.boxes[coast, :2] + tracks.boxes[coast, 2:] / 2) * UNIT + origin
            shape = np.array([self._shape.get(int(tracks.ids[k]), self._fallback(
                tracks.boxes[k], t)) for k in coast]).reshape(-1, 6)
            world = np.stack([centre[:, 0], shape[:, 3], centre[:, 1]], axis=-1)
            out[coast, :3] = shape[:, :3]
            out[coast, 3:6] = (world - t) @ R
            out[coast, 6] = heading_of(heading_vector(shape[:, 4]) @ R)
        self._forget(tracks.ids)
        v = np.zeros((n, 3))
        v[:, [0, 2]] = tracks.velocities * UNIT
        velocities = (v @ R)[:, [0, 2]]
        return GroundTracks(tracks.ids, out, tracks.existence, tracks.confidence, velocities,
                            tracks.detection_index, tracks.classes, tracks.occluded, evidence,
                            score_llr)

    def _add_sizes(self, ids: np.ndarray, boxes: np.ndarray) -> None:
        """Count the sizes (h, w, l) of the (n, 7) `boxes` that objects `ids` (n,) took into
        their means (`mean_sizes`), each weighted by 1 / r^2 (r the box's range, `SIZE_NEAR`
        at least): a solid object keeps its size, and a lidar's points on it, whose spread
        sets the variance of a size read from them, fall off as 1 / r^2."""
        weight = 1.0 / np.maximum(np.hypot(boxes[:, 3], boxes[:, 5]), SIZE_NEAR) ** 2
        for k, key in enumerate(ids.tolist()):
            total = self._size.setdefault(int(key), np.zeros(5))
            total[:3] += weight[k] * boxes[k, :3]
            total[3] += weight[k]
            total[4] = self._time

    def mean_sizes(self, ids: np.ndarray) -> np.ndarray:
        """(n, 3) the size (h, w, l) of each object of `ids` that has taken a detection: the
        weighted mean of its detections' sizes (`_add_sizes`)."""
        return np.array([self._size[int(key)][:3] / self._size[int(key)][3]
                         for key in ids.tolist()]).reshape(-1, 3)

    def _fallback(self, ltwh: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The shape of an object reported before any detection of its was (its footprint,
        1.5 m tall, standing on the ground 1.65 m below the camera, KITTI's mounting)."""
        w, l = sorted(ltwh[2:] * UNIT)
        return np.array([1.5, w, l, t[1] + 1.65, 0.0, self._time])

    def _forget(self, shown: np.ndarray) -> None:
        """Drop the shapes of objects not reported for SHAPE_MEMORY seconds."""
        now = set(int(i) for i in shown)
        for key in [k for k, s in self._shape.items()
                    if k not in now and self._time - s[5] > SHAPE_MEMORY]:
            del self._shape[key]
        for key in [k for k, e in self._evidence.items() if self._time - e[1] > SHAPE_MEMORY]:
            del self._evidence[key]
        for key in [k for k, e in self._size.items() if self._time - e[4] > SHAPE_MEMORY]:
            del self._size[key]





def detection_scores(score: np.ndarray) -> np.ndarray:
    """A detection file's scores as probabilities: kept where every score is in [0, 1], else
    read as logits (PointRCNN writes its raw logit) through the logistic function."""
    score = np.asarray(score, dtype=float)
    if len(score) == 0 or (score.min() >= 0 and score.max() <= 1):
        return score
    return 1.0 / (1.0 + np.exp(-score))


def _drawn_from_3d(det, calibration, image_size) -> np.ndarray | None:
    """(N,) bool: the detection rows whose 2D box is only their 3D box's corners projected
    (within 2 px a side; PointRCNN writes them so, clipped to [0, W - 1] x [0, H - 1]). Such a
    box says nothing the 3D box does not: the tracker's own 3D box, drawn as its kind fills it,
    takes its place (`track_kitti`). A 2D box found in the image by the detector is its own.
    None without a calibration."""
    from occtrack.io.kitti_geometry import project_boxes

    if calibration is None or image_size is None:
        return None
    corners = project_boxes(det.box3d, calibration.P2, image_size)
    with np.errstate(invalid="ignore"):
        return np.abs(corners - det.box).max(axis=1) < 2.0


def _looked_ahead(tracks: GroundTracks, frame: int, later, dt: float) -> np.ndarray:
    """(n,) the confidence of a frame's objects given the scores of the `later` frames too
    ((frame, tracks, ...) in order): each object's filtered evidence plus the backward message
    of its later score log-likelihood ratios (`lookahead_evidence`)."""
    confidence = tracks.confidence.copy()
    if not later or not len(tracks):
        return confidence
    where = [{key: j for j, key in enumerate(entry[1].ids.tolist())} for entry in later]
    for i, key in enumerate(tracks.ids.tolist()):
        llr, elapsed, last = [], [], frame
        for entry, index in zip(later, where, strict=True):
            j = index.get(key)
            if j is not None:  # (a frame where the filter did not hold it says nothing)
                llr.append(entry[1].score_llr[j])
                elapsed.append((entry[0] - last) * dt)
                last = entry[0]
        if llr:
            b, odds = lookahead_evidence(llr, elapsed), tracks.evidence[i]
            # P(real | later too) / P(real | so far), stable at any odds
            confidence[i] *= math.exp(np.logaddexp(0.0, -odds) - np.logaddexp(0.0, -odds - b))
    return np.minimum(confidence, 1.0)


def track_kitti(det, num_frames: int, config: TrackerConfig | None = None,
                poses: np.ndarray | None = None, calibration=None,
                image_size: tuple[float, float] | None = None, quiet: bool = True,
                notes: list[str] | None = None, written: npt.ArrayLike | None = None,
                lookahead: float = EVIDENCE_LOOKAHEAD,
                evidence_weight: float = SCORE_EVIDENCE_WEIGHT):
    """Track a KITTI detection table's 3D boxes (`occtrack.io.kitti.KittiTable`, frames
    0..num_frames-1, every class at once, each object keeping its own) and return the result
    as a KittiTable: the 3D box in each frame's camera coordinates, and the 2D box the
    detection's own while detected, else the 3D box projected with the calibration's P2. A
    3D box is drawn as its kind fills it (a person: the upright cylinder inscribed in it,
    `ROUND_TYPES`; anything else: its corners), and a detection's 2D box that is only its 3D
    box's corners projected (`_drawn_from_3d`, PointRCNN's) is drawn so from the tracker's 3D
    box (the detection's centre and heading, the object's mean size). A coasting box that the
    image's border cuts, or that projects nowhere in the image, is left
    out of the file: the camera sees no part of it beyond the border, so its clipped
    projection is not the box a camera would show (KITTI labels such an object truncated and
    does not score it). `poses` (F, 3, 4) the camera's path;
    None: a still camera. The score column is the confidence. `notes`, when given, gets a
    line on the boxes dropped as duplicates of another box (`GroundTracker`). `written`: the
    types whose tracks are written (None: every type); every type is tracked, as a box of
    another type can hide one of these or be the one it duplicates. `lookahead`: seconds of
    later frames whose scores weigh on each frame's confidence (`lookahead_evidence`; 0: the
    filtered confidence); the confidence floor is applied after them. `evidence_weight`:
    `GroundTracker`'s."""
    from occtrack.io.kitti import ROUND_TYPES, KittiTable
    from occtrack.io.kitti_geometry import project_boxes
    from occtrack.progress import progress

    unknown = np.flatnonzero(det.box3d[:, 3] <= -999)
    if len(unknown):
        from occtrack.errors import OcctrackError
        line = None if det.line is None else int(det.line[unknown[0]])
        raise OcctrackError("a detection without its 3D columns (x y z = -1000): --3d needs "
                            "a 3D detector's boxes (h w l x y z rotation_y)", det.path, line)
    if not (math.isfinite(lookahead) and lookahead >= 0):
        raise ValueError(f"lookahead must be a number of seconds >= 0, not {lookahead}")
    c = config or ground_config()
    tracker = GroundTracker(replace(c, report_min_confidence=0.0),  # (the floor: below)
                            evidence_weight=evidence_weight)
    ahead = round(lookahead * c.fps)
    pending: deque = deque()  # (frame, tracks, 2D boxes, written) not yet final
    scores = detection_scores(det.score)
    drawn = _drawn_from_3d(det, calibration, image_size)
    order = np.argsort(det.frame, kind="stable")
    bounds = np.searchsorted(det.frame[order], np.arange(num_frames + 1))
    rows: dict[str, list] = {k: [] for k in ("frame", "id", "type", "box", "box3d", "score")}
    for f in progress(range(num_frames), num_frames, "tracking 3D", quiet):
        sel = order[bounds[f]:bounds[f + 1]]
        tracks = tracker.update(det.box3d[sel], scores[sel], det.type[sel],
                                pose=None if poses is None else poses[f])
        box = np.full((len(tracks), 4), np.nan)
        took = tracks.detection_index >= 0
        box[took] = det.box[sel[tracks.detection_index[took]]]
        if drawn is not None and len(tracks):  # (a calibration and an image size)
            projected = project_boxes(tracks.boxes3d, calibration.P2, image_size,
                                      round_=np.isin(tracks.classes, ROUND_TYPES))
            redraw = took.copy()  # detected, its 2D box only its 3D box projected
            redraw[took] = drawn[sel[tracks.detection_index[took]]]
            redraw &= np.isfinite(projected).all(axis=1)
            box[redraw] = projected[redraw]
            width, height = image_size
            cut = ((projected[:, 0] <= 0) | (projected[:, 1] <= 0) | (projected[:, 2] >= width)
                   | (projected[:, 3] >= height))
            projected[cut] = np.nan
            box[~took] = projected[~took]
        keep = np.isfinite(box).all(axis=1)
        if written is not None:
            keep &= np.isin(tracks.classes, written)
        pending.append((f, tracks, box, keep))
        while len(pending) > ahead or (f == num_frames - 1 and pending):
            f0, tracks, box, keep = pending.popleft()
            confidence = _looked_ahead(tracks, f0, pending, tracker.tracker.filter.dt)
            keep = keep & (confidence >= c.report_min_confidence)
            rows["frame"].append(np.full(int(keep.sum()), f0))
            rows["id"].append(tracks.ids[keep])
            rows["type"].append(tracks.classes[keep])
            rows["box"].append(box[keep])
            rows["box3d"].append(tracks.boxes3d[keep])
            rows["score"].append(confidence[keep])
    if notes is not None and tracker.duplicates_dropped:
        notes.append(f"{tracker.duplicates_dropped} boxes dropped as the duplicate of a "
                     f"higher-scored box at the same place (footprints overlapping by "
                     f"{tracker.duplicate_overlap:g} of the smaller one's or more)")
    cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in rows.items()}
    n = len(cat["frame"])
    return KittiTable(frame=cat["frame"].astype(np.int64), id=cat["id"].astype(np.int64),
                      type=cat["type"].astype(np.int64), truncated=np.full(n, -1.0),
                      occluded=np.full(n, -1.0), alpha=np.full(n, -10.0),
                      box=cat["box"].reshape(n, 4), box3d=cat["box3d"].reshape(n, 7),
                      score=cat["score"], path=f"<{n} result rows>")


__all__ = ["GROUND_DEFAULTS", "GroundTracker", "GroundTracks", "check_boxes3d",
           "detection_scores", "ground_config", "ground_corners", "lookahead_evidence",
           "track_kitti"]
