"""The simulated detector's settings (the `[detector]` table of `occtrack
simulate-detections --config`): every field, its type and its range, checked when built."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from occtrack.errors import OcctrackError

NMS_ORDERS = ("score", "bottom")


@dataclass(frozen=True)
class DetectorConfig:
    """Parameters of the simulated detector. Logits are log-odds of the score; boxes in pixels.

    bias: logit of a fully visible person of height >= `height_ref` with average difficulty.
    visibility_weight: logit lost from full visibility to none (w_v).
    height_ref, height_weight: persons shorter than `height_ref` lose `height_weight` logit per
        e-fold of height (w_h).
    person_std: std of the per-person difficulty d_i, fixed over the sequence (sigma_d).
    noise_std, score_memory: std and correlation time (frames) of the per-frame logit noise.
    edge_noise_x, edge_noise_y: edge noise std as a fraction of the box width / height.
    false_positive_rate: expected false candidates per frame (Poisson), before thresholds.
    false_positive_logit, false_positive_logit_std: mean and std of their logits.
    false_positive_height: smallest and largest false box height (log-uniform).
    aspect: width / height of false boxes.
    candidate_threshold: candidates scoring below it never enter NMS.
    nms_iou: NMS suppresses a candidate whose IoU with a kept detection exceeds it.
    nms_order: "score" (Faster-RCNN) or "bottom" (nearest the camera first).
    score_threshold: detections scoring below it are not reported.
    min_size: clipped boxes narrower or shorter than this many pixels are dropped.
    person_classes: ground-truth classes the detector sees as persons; rows of a file without
        a class column count as persons, and a missing visibility counts as 1.
    """

    bias: float = 3.7
    visibility_weight: float = 7.0
    height_ref: float = 100.0
    height_weight: float = 2.0
    person_std: float = 1.0
    noise_std: float = 1.0
    score_memory: float = 8.0
    edge_noise_x: float = 0.05
    edge_noise_y: float = 0.04
    false_positive_rate: float = 1.3
    false_positive_logit: float = -1.0
    false_positive_logit_std: float = 1.5
    false_positive_height: tuple[float, float] = (50.0, 300.0)
    aspect: float = 0.41
    candidate_threshold: float = 0.05
    nms_iou: float = 0.5
    nms_order: str = "score"
    score_threshold: float = 0.5
    min_size: float = 2.0
    person_classes: tuple[int, ...] = (1, 2, 7, 8, 12)

    def __post_init__(self) -> None:
        checks = [
            (self.visibility_weight >= 0 and self.height_weight >= 0,
             "visibility_weight and height_weight must be >= 0"),
            (self.height_ref > 0, "height_ref must be > 0"),
            (self.person_std >= 0 and self.noise_std >= 0, "person_std, noise_std must be >= 0"),
            (self.score_memory >= 0, "score_memory must be >= 0"),
            (self.edge_noise_x >= 0 and self.edge_noise_y >= 0, "edge noise must be >= 0"),
            (self.false_positive_rate >= 0, "false_positive_rate must be >= 0"),
            (self.false_positive_logit_std >= 0, "false_positive_logit_std must be >= 0"),
            (len(self.false_positive_height) == 2
             and 0 < self.false_positive_height[0] <= self.false_positive_height[1],
             "false_positive_height must be (low, high) with 0 < low <= high"),
            (self.aspect > 0, "aspect must be > 0"),
            (0 <= self.candidate_threshold <= 1 and 0 <= self.score_threshold <= 1,
             "thresholds must lie in [0, 1]"),
            (0 < self.nms_iou <= 1, "nms_iou must lie in (0, 1]"),
            (self.nms_order in NMS_ORDERS, f"nms_order must be one of {NMS_ORDERS}"),
            (self.min_size >= 0, "min_size must be >= 0"),
        ]
        for ok, message in checks:
            if not ok:
                raise OcctrackError(f"detector config: {message}")

    @classmethod
    def from_dict(cls, values: dict, path: str | None = None) -> DetectorConfig:
        """A config from a mapping (a TOML table), rejecting unknown keys."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise OcctrackError(f"unknown detector setting(s) {', '.join(unknown)}; known: "
                                f"{', '.join(sorted(known))}", path)
        defaults = cls()
        clean = {}
        for key, value in values.items():
            default = getattr(defaults, key)
            if isinstance(default, tuple):
                items = value if isinstance(value, list | tuple) else [value]
                kind = type(default[0])
                ok = all(_is_number(v, kind) for v in items)
                clean[key] = tuple(kind(v) for v in items) if ok else None
            elif isinstance(default, str):
                ok = isinstance(value, str)
                clean[key] = value
            else:
                ok = _is_number(value, type(default))
                clean[key] = type(default)(value) if ok else None
            if not ok:
                raise OcctrackError(f"detector setting {key} = {value!r}: expected "
                                    f"{type(default).__name__} like {default!r}", path)
        try:
            return cls(**clean)
        except OcctrackError as err:
            raise OcctrackError(err.message, path) from None

    def to_dict(self) -> dict:
        return asdict(self)


def _is_number(value, kind: type) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return False
    return kind is float or float(value).is_integer()
