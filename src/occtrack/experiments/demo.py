"""`occtrack demo`'s experiment: the street tracked under each occlusion model, scored in the
units a user cares about.

- MOTA, IDF1, ID switches: motmetrics against every person in the image (hidden ones
  included: a box kept on a hidden person is right), a match needs IoU >= 0.5.
- kept through full occlusions, k / n: a full occlusion is a spell of at least
  `MIN_SPELL` seconds in which a person, inside the image, is more than half hidden by nearer
  people (the detector measured on MOT17 sees such a person at most 3 % of the time), with
  the person seen (less than half hidden) in the frames before and after. It is kept when the
  track matched to the person in the last frame before the spell (looking back at most
  `LOOK` seconds) is the one matched first after it (looking on at most `LOOK` seconds);
  per frame reported boxes and people are matched one to one at IoU >= 0.5 (the most pairs).
- false boxes: reported boxes that the same matching leaves without a person.
- ECE: the expected calibration error of `Tracks.confidence` over the reported boxes, a box
  right when matched (`occtrack.metrics.reliability`, as `occtrack eval --calibration`).
- steps / s: frames tracked per second, the time inside `Tracker.step` only, after a warm-up
  run over the same frames on a tracker of the same settings (caches and allocations warm
  by then; the kernels arrive compiled with the install): the steady state, measured as
  benchmarks/bench_tracker.py measures it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.metrics.gospa import iou
from occtrack.metrics.reliability import RIGHT_IOU, reliability_table
from occtrack.scenarios.street import Street, StreetScene, street_scene
from occtrack.tracker import OCCLUSION_NAMES, Tracker, TrackerConfig, TrackResult

HIDDEN = 0.5
"""A person is hidden when nearer people cover more than this share of their box."""
MIN_SPELL = 0.5
"""s: the shortest full occlusion counted (a detector misses visible people for a third of a
second at a time: MOT17's P(hit | miss) = 0.09 a frame)."""
LOOK = 1.0
"""s: how far before and after a spell the person's track is looked for."""


@dataclass(frozen=True)
class Spell:
    person: int
    first: int  # first hidden frame
    last: int  # last hidden frame


def full_occlusions(scene: StreetScene) -> list[Spell]:
    """The scene's full occlusions: spells of at least `MIN_SPELL` s in which a person wholly
    inside the image is more than `HIDDEN` covered, seen before and after."""
    t = scene.truth
    hidden = (scene.hidden_by_others > HIDDEN) & (scene.in_image > 0.999)
    seen = scene.hidden_by_others <= HIDDEN
    spells = []
    min_frames = int(np.ceil(MIN_SPELL * scene.fps))
    for person in np.unique(t.id):
        rows = np.flatnonzero(t.id == person)
        rows = rows[np.argsort(t.frame[rows], kind="stable")]
        frames = t.frame[rows]
        state = np.where(hidden[rows], 1, np.where(seen[rows], 0, -1))
        k = 0
        while k < len(rows):
            if state[k] != 1:
                k += 1
                continue
            j = k
            while j + 1 < len(rows) and state[j + 1] == 1 and frames[j + 1] == frames[j] + 1:
                j += 1
            before_ok = k > 0 and state[k - 1] == 0 and frames[k - 1] == frames[k] - 1
            after_ok = j + 1 < len(rows) and state[j + 1] == 0 and frames[j + 1] == frames[j] + 1
            if before_ok and after_ok and j - k + 1 >= min_frames:
                spells.append(Spell(int(person), int(frames[k]), int(frames[j])))
            k = j + 1
    return spells


def match_frames(scene: StreetScene, result: TrackResult) -> tuple[dict, np.ndarray]:
    """Per frame the one-to-one matching at IoU >= 0.5 (the most pairs): {(frame, person):
    track id}, and for each result row whether it was matched."""
    truth = scene.truth
    matched: dict[tuple[int, int], int] = {}
    right = np.zeros(len(result.frame), bool)
    t_rows = truth.frame_slices(scene.frames)
    r_rows = _slices(result.frame, scene.frames)
    for f, (t, r) in enumerate(zip(t_rows, r_rows, strict=True), start=1):
        if not len(t) or not len(r):
            continue
        good = iou(truth.box[t], result.box[r]) >= RIGHT_IOU - 1e-12
        if not good.any():
            continue
        a, b = linear_sum_assignment(good, maximize=True)
        ok = good[a, b]
        for i, j in zip(a[ok], b[ok], strict=True):
            matched[(f, int(truth.id[t[i]]))] = int(result.id[r[j]])
        right[r[b[ok]]] = True
    return matched, right


def through(spell: Spell, matched: dict, fps: float) -> tuple[int | None, int | None]:
    """The frames, before and after the spell (at most `LOOK` s away), where the person was
    last and first matched to a track (None: not within `LOOK`)."""
    look = int(round(LOOK * fps))
    before = next((f for f in range(spell.first - 1, spell.first - 1 - look, -1)
                   if (f, spell.person) in matched), None)
    after = next((f for f in range(spell.last + 1, spell.last + 1 + look)
                  if (f, spell.person) in matched), None)
    return before, after


def kept(spells: list[Spell], matched: dict, fps: float) -> list[bool]:
    """For each spell, whether one track covers the person before and after it."""
    out = []
    for s in spells:
        before, after = through(s, matched, fps)
        out.append(before is not None and after is not None
                   and matched[(before, s.person)] == matched[(after, s.person)])
    return out


def clear_scores(scene: StreetScene, result: TrackResult) -> dict:
    """MOTA, IDF1 and ID switches (motmetrics, IoU >= 0.5)."""
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=True)
    truth = scene.truth
    for t, r in zip(truth.frame_slices(scene.frames), _slices(result.frame, scene.frames),
                    strict=True):
        distance = 1.0 - iou(truth.box[t], result.box[r])
        acc.update(truth.id[t], result.id[r], np.where(distance <= 0.5, distance, np.nan))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        summary = mm.metrics.create().compute(
            acc, metrics=["mota", "idf1", "num_switches"], name="demo").iloc[0]
    return {"mota": float(summary["mota"]), "idf1": float(summary["idf1"]),
            "id_switches": int(summary["num_switches"])}


def _slices(frames: np.ndarray, n: int) -> list[np.ndarray]:
    order = np.argsort(frames, kind="stable")
    bounds = np.searchsorted(frames[order], np.arange(1, n + 2))
    return [order[bounds[f]:bounds[f + 1]] for f in range(n)]


def score(scene: StreetScene, result: TrackResult, spells: list[Spell],
          matching: tuple[dict, np.ndarray] | None = None) -> dict:
    """The demo's scores of one run (see the module's docstring); `matching`: the run's
    `match_frames`, when already made."""
    matched, right = matching or match_frames(scene, result)
    confidence = np.clip(result.confidence, 0.0, 1.0)
    return {**clear_scores(scene, result), "kept": sum(kept(spells, matched, scene.fps)),
            "occlusions": len(spells), "false_boxes": int((~right).sum()),
            "boxes": len(right), "ece": reliability_table(confidence, right).ece,
            "tracks": result.num_tracks}


def track(scene: StreetScene, occlusion: str, quiet: bool = True,
          settings: dict | None = None) -> tuple[TrackResult, float]:
    """The run under one occlusion model and its steady-state steps per second; `settings`:
    TrackerConfig fields on top of the defaults (for experiments; the demo has none)."""
    config = TrackerConfig(**{**(settings or {}), "occlusion": occlusion,
                              "image_size": scene.image_size, "fps": scene.fps})
    Tracker(config).run(scene.detections, scene.frames)  # the warm-up
    result = Tracker(config).run(scene.detections, scene.frames, quiet, occlusion)
    return result, result.frames / max(result.seconds_tracking, 1e-9)


def detector_figures(scene: StreetScene) -> dict:
    """Recall and precision of the detections against the people (IoU >= 0.5, one to one)."""
    matched = 0
    for t, d in zip(scene.truth.frame_slices(scene.frames),
                    scene.detections.frame_slices(scene.frames), strict=True):
        if len(t) and len(d):
            good = iou(scene.truth.box[t], scene.detections.box[d]) >= RIGHT_IOU - 1e-12
            a, b = linear_sum_assignment(good, maximize=True)
            matched += int(good[a, b].sum())
    return {"recall": matched / max(len(scene.truth), 1),
            "precision": matched / max(len(scene.detections), 1),
            "false_per_frame": (len(scene.detections) - matched) / scene.frames}


def run_demo(street: Street | None = None, seed: int = 0, quiet: bool = True,
             models: tuple[str, ...] = OCCLUSION_NAMES, settings: dict | None = None) -> dict:
    """The scene (default `Street()`), each model's result and scores, and the detector's
    figures; `settings` as in `track`."""
    scene = street_scene(street or Street(), seed)
    spells = full_occlusions(scene)
    results, scores, matches = {}, {}, {}
    for name in models:
        results[name], speed = track(scene, name, quiet, settings)
        matches[name] = match_frames(scene, results[name])
        scores[name] = {**score(scene, results[name], spells, matches[name]),
                        "steps_per_second": speed}
    return {"scene": scene, "spells": spells, "results": results, "scores": scores,
            "matches": {k: v[0] for k, v in matches.items()},
            "detector": detector_figures(scene)}


def telling_spell(out: dict, model: str = "object-wise",
                  baseline: str = "none") -> tuple[Spell, int, int] | None:
    """A full occlusion to draw, with the frames before and after it where `model`'s track
    covers the person: the longest that `model` keeps and `baseline` does not, else the
    longest `model` keeps, else the longest; None when the scene has none."""
    spells = out["spells"]
    if not spells:
        return None
    fps = out["scene"].fps
    mine = kept(spells, out["matches"][model], fps)
    theirs = kept(spells, out["matches"][baseline], fps) if baseline in out["matches"] \
        else [False] * len(spells)
    length = [s.last - s.first for s in spells]
    best = max(range(len(spells)), key=lambda i: (mine[i] and not theirs[i], mine[i],
                                                  length[i], -i))
    spell = spells[best]
    before, after = through(spell, out["matches"][model], fps)
    return spell, before or spell.first - 1, after or spell.last + 1
