"""The demo street's settings (`occtrack demo`): how its people move and how its detector sees
them. Every number is a measurement on MOT17 (the command that gives it is named beside it)
or, where MOT17 cannot give it, a property of the scene said as such. None was chosen for how
the trackers score on the street."""

from __future__ import annotations

from dataclasses import dataclass

# The detector: `occtrack calibrate` on the three MOT17 sequences with ground truth, FRCNN
# public detections (2787 frames, 63910 pedestrian boxes, 35661 matched detections, 525
# false):
#   occtrack calibrate MOT17-04-FRCNN/gt/gt.txt MOT17-04-FRCNN/det/det.txt \
#       MOT17-05-FRCNN/gt/gt.txt MOT17-05-FRCNN/det/det.txt \
#       MOT17-11-FRCNN/gt/gt.txt MOT17-11-FRCNN/det/det.txt -o detector.toml


@dataclass(frozen=True)
class StreetDetector:
    """A detector as `occtrack calibrate` measures one (`occtrack.models.calibration`).

    visibility_bins, detect_by_visibility: P(detected) of a person whose visible share lies in
        each bin ("detection probability by visibility"); the measured values already hold the
        detector's non-maximum suppression, so none is applied on top.
    memory: P(hit | hit last frame) - P(hit | miss last frame) ("memory per frame", measured
        on visible people the tracker holds): misses come in runs, as a real detector's do
        (of two frames on average, as MOT17's misses of people in view). Applied while a
        person stays in the top visibility bin; elsewhere each frame is drawn afresh.
    edge_std, edge_bias: each edge's error (left, top, right, bottom), in true box heights
        ("box-edge noise": std and bias).
    score_bins, hit_scores: the scores of detected people, share per score bin (the "hits"
        counts of the false-detection table).
    false_per_bin: false detections per frame in each score bin ("by score").
    """

    visibility_bins: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
    detect_by_visibility: tuple[float, ...] = (0.007, 0.028, 0.706, 0.992)
    memory: float = 0.485
    edge_std: tuple[float, ...] = (0.012, 0.016, 0.012, 0.019)
    edge_bias: tuple[float, ...] = (0.001, 0.0, 0.011, 0.010)
    score_bins: tuple[float, ...] = (0.0, 0.5, 0.9, 0.99, 0.999, 1.0)
    hit_scores: tuple[float, ...] = (881.0, 574.0, 976.0, 1595.0, 31635.0)
    false_per_bin: tuple[float, ...] = (0.1170, 0.0452, 0.0226, 0.0032, 0.0004)

    @property
    def false_per_frame(self) -> float:
        return float(sum(self.false_per_bin))


# How people move: the ground truth of MOT17-04 (the one sequence of the three with a still
# camera, so image motion is the people's own), measured by
#   python benchmarks/walker_statistics.py $OCCTRACK_DATA/MOT17-04-FRCNN/gt/gt.txt
# (pedestrians tracked for at least 2 s; speed of the feet smoothed over 1 s, in box heights a
# second; walking above 0.12 h/s, standing below 0.05, hysteresis between).


@dataclass(frozen=True)
class StreetMotion:
    """walking_speed, speed_spread: median and log-std of a walker's speed, box heights / s
        (quartiles 0.16 and 0.28 h/s; log-std = ln(q3 / q1) / 1.349).
    stop_rate: stops per second of walking; stop_mean: mean length of a stop, s (stops longer
        than the 35 s sequence are cut, so this is low, if anything).
    turn_back: share of stops after which the person walks back the way they came.
    standing: share of people who stand the whole time.
    drift: the vertical speed's std, as a share of the walking speed (on a street people walk
        along it; a scene choice: MOT17-04 is a square seen from above)."""

    walking_speed: float = 0.21
    speed_spread: float = 0.40
    stop_rate: float = 0.064
    stop_mean: float = 4.6
    turn_back: float = 0.56
    standing: float = 0.13
    drift: float = 0.1
