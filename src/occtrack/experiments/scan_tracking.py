"""The lidar scan tracker on the simulated walkway (`occtrack.scenarios.lidar`): GOSPA per scan,
identity kept through full occlusions, scans a second; one row per (seed, occlusion model).

- GOSPA (`occtrack.metrics.gospa`): Euclidean distance between true and reported centres,
  c = 1 m, p = 1, alpha = 2, per scan, averaged over the scans; people only (vehicles none
  by default).
- Kept through a full occlusion: a spell of full occlusion runs while the person is not seen
  (fewer than `SEEN_BEAMS` beams return from it) and holds at least one scan where no beam
  reaches it (`full_occlusions` with `seen`): a one-beam glimpse, which no tracker can tell
  from a clutter return, does not end it. For each spell shorter than `max_spell` s with the
  person in the scene on both sides (seen the scan before and the scan after), the person is
  matched to a track at the scan just before the spell and at the first scan after it (per
  scan, `match`: the assignment that minimises the summed distance over the pairs closer than
  `cutoff` m, scipy's linear_sum_assignment); kept when both matches exist and name the same
  track. Spells at the start or the end of the scene or of the person's walk (entering or
  leaving while hidden) are left out; those whose person was matched to no track going in
  count as not kept (`entered`: those matched going in); the spells of 1 to 2 s also on their own (a
  spell's duration is from its first to its last unseen scan, so a one-scan spell lasts 0 s).
  `strict_spells` / `strict_kept`: the same count over the spells of the scene's flag alone
  (every fully occluded run, so a glimpse splits a spell in two).
- HOTA on positions (`occtrack.metrics.hota_points`): TrackEval's HOTA with the similarity
  max(0, 1 - d / `cutoff`) in place of IoU (alpha 0.5: within half a metre), with DetA and AssA.
- ECE of the tracks' confidence (`occtrack.metrics.reliability`, 10 bins): a reported track
  is right when matched (as above) to a person within one radius of its centre, the event its
  confidence is the probability of.
- Identity switches: a person matched (as above, every scan) to another track than the one
  it was last matched to.
- Scans a second: `update` calls timed with time.perf_counter (each scan is simulated before
  its call, outside the timing, and let go after it: memory holds the scores, not the scans).
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from occtrack.config.lidar import LidarSceneConfig
from occtrack.config.scan import ScanTrackerConfig
from occtrack.errors import OcctrackError
from occtrack.metrics.gospa import gospa
from occtrack.metrics.hota_points import PointTracks
from occtrack.metrics.reliability import reliability_table
from occtrack.progress import progress
from occtrack.scenarios.lidar import full_occlusions, simulate_scene
from occtrack.scenarios.lidar.scene import Occlusions
from occtrack.tracker.scan import ScanTracker

SEEN_BEAMS = 2  # a person is seen in a scan when two beams return from it: one alone looks
# like a clutter return (5 a scan by default), and a disc needs two points to be fitted


@dataclass(frozen=True)
class ScanRun:
    seed: int
    occlusion: str
    scans: int
    gospa: float  # mean per scan
    localisation: float
    missed: float
    false: float
    spells: int  # full occlusions shorter than max_spell inside the scene
    entered: int  # of them, with the person tracked going in
    kept: int  # of those, the same track after
    long_entered: int  # of `entered`, the spells of a second or more
    long_kept: int
    scans_per_second: float
    likelihood: str = "derived"
    switches: int = 0  # identity switches: a person matched to another track than last time
    strict_spells: int = 0  # the spells of the scene's flag alone (a glimpse ends them)
    strict_kept: int = 0
    hota: float = 0.0  # HOTA on positions (`metrics.hota_points`, threshold `cutoff`)
    deta: float = 0.0
    assa: float = 0.0
    ece: float = 0.0  # of the confidence: right = matched within one radius


def match(truth: np.ndarray, estimates: np.ndarray, cutoff: float) -> tuple[np.ndarray, ...]:
    """(truth rows, estimate rows) of the pairs closer than `cutoff` in the assignment that
    minimises the summed min(distance, cutoff)."""
    if len(truth) == 0 or len(estimates) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    d = np.hypot(*(truth[:, None, :] - estimates[None, :, :]).transpose(2, 0, 1))
    rows, cols = linear_sum_assignment(np.minimum(d, cutoff))
    ok = d[rows, cols] < cutoff
    return rows[ok], cols[ok]


def tracker_config(scene: LidarSceneConfig, occlusion: str, likelihood: str = "derived",
                   tracker: ScanTrackerConfig | None = None) -> ScanTrackerConfig:
    """The tracker's settings for a scene: its sensor (P_D, noise, clutter, range) and the
    people's radius are the scene's, as the paper's trackers knew their simulations'."""
    return (tracker or ScanTrackerConfig()).replace(
        occlusion=occlusion, likelihood=likelihood, p_d=scene.p_d, range_noise=scene.range_noise,
        clutter_per_scan=scene.clutter_per_scan, max_range=scene.max_range,
        radius=scene.person_radius)


@dataclass(frozen=True)
class OcclusionPicture:
    """One scan of a scene for a picture: the sensor (x, y), the returns' points (R, 2), the
    people's centres (K, 2), ids and which are fully occluded, the radius, and per occlusion
    model the tracks' positions (n, 2), ids and hidden flags."""

    time: float
    sensor: np.ndarray
    returns: np.ndarray
    people: np.ndarray
    people_ids: np.ndarray
    occluded: np.ndarray
    radius: float
    tracks: dict


SETTLE = 10.0  # s: the scans before it are not picked (the trackers are still starting)


def check_pickable(scans: int, scene: LidarSceneConfig | None = None) -> None:
    """Refuse, before the run, a run too short for a picture: none of its scans after `SETTLE`."""
    rate = (scene or LidarSceneConfig()).rate
    if (scans - 1) / rate < SETTLE:
        raise OcctrackError(f"a picture is picked after the first {SETTLE:g} s of the scene: "
                            f"give more than {SETTLE * rate:g} scans")


def _picture(s, scene: LidarSceneConfig, out: dict) -> OcclusionPicture:
    person = s.objects.shapes.disc
    returns = np.isfinite(s.range) & (s.range < scene.max_range)
    bearing = s.pose[2] + s.angle[returns]
    return OcclusionPicture(
        s.time, s.pose[:2].copy(),
        s.pose[:2] + s.range[returns, None] * np.column_stack([np.cos(bearing),
                                                                np.sin(bearing)]),
        s.objects.shapes.centre[person], s.objects.id[person], s.occluded[person],
        scene.person_radius, {m: (o.positions, o.ids, o.occluded) for m, o in out.items()})


def occlusion_scans(seed: int = 0, scans: int = 600, models=("measurement-wise", "none"),
                    scene: LidarSceneConfig | None = None, quiet: bool = True,
                    length: int = 1) -> tuple[list[OcclusionPicture], int]:
    """The `length` consecutive scans (`around`) centred on the one picked, as pictures, and
    the picked one's index among them; a tracker per model on the same scans. Picked: after
    the first `SETTLE` s, the scan where the most fully occluded people are held by a track
    (its centre within two radii of theirs) under the first model and by none under the second
    (ties: the earliest). The scans are simulated one at a time and at most 3 `length`
    pictures are held, so memory does not grow with `scans`. A progress bar unless `quiet`."""
    scene = scene or LidarSceneConfig()
    check_pickable(scans, scene)
    trackers = {m: ScanTracker(tracker_config(scene, m), beams=scene.beams, rate=scene.rate)
                for m in models}
    window = PickWindow(length)
    best_key = (-1, 0)
    for i, s in enumerate(progress(simulate_scene(scene, scans, seed), scans, "lidar picture",
                                   quiet)):
        out = {m: tr.update(s.range, s.pose[2] + s.angle, s.time, s.pose[:2])
               for m, tr in trackers.items()}
        key = (-1, 0)
        if s.time >= SETTLE:
            person = s.objects.shapes.disc
            hidden = s.objects.shapes.centre[person & s.occluded]
            held = [np.hypot(*(hidden[:, None] - out[m].positions[None]).transpose(2, 0, 1))
                    .min(axis=1, initial=np.inf) < scene.person_radius * 2 for m in models]
            key = (int((held[0] & ~held[1]).sum()), -i)
        picked = key > best_key
        best_key = max(key, best_key)
        window.add(lambda s=s, out=out: _picture(s, scene, out), picked)
    return window.result()


def occlusion_picture(seed: int = 0, scans: int = 600, models=("measurement-wise", "none"),
                      scene: LidarSceneConfig | None = None) -> OcclusionPicture:
    """The scan `occlusion_scans` picks."""
    pictures, best = occlusion_scans(seed, scans, models, scene)
    return pictures[best]


def _start(index: int, length: int, n: int) -> int:
    return min(max(index - length // 2, 0), max(n - length, 0))


def around(pictures: list, index: int, length: int) -> list:
    """`length` consecutive pictures (fewer if there are not so many) centred on `index`,
    shifted to stay within the run."""
    start = _start(index, length, len(pictures))
    return pictures[start:start + length]


class PickWindow:
    """What `around(items, picked, length)` gives, kept while a stream goes by: the items before
    the latest pick (at most `length`), the pick and the items after it (at most `length` - 1),
    never the whole stream. An item comes as a function that makes it, called only if kept."""

    def __init__(self, length: int) -> None:
        self.length = length
        self.recent: deque = deque(maxlen=length)  # the items before the current one
        self.kept: list = []  # before the pick, the pick, after it
        self.index = -1  # the pick's place in `kept`; -1: nothing picked yet

    def add(self, make, picked: bool) -> None:
        if picked:
            self.kept = [*self.recent, make()]
            self.index = len(self.kept) - 1
            self.recent.append(self.kept[-1])
            return
        need = self.index >= 0 and len(self.kept) - self.index < self.length
        item = make() if need or self.length > 1 else None
        if need:
            self.kept.append(item)
        if self.length > 1:
            self.recent.append(item)

    def result(self) -> tuple[list, int]:
        """The window (`around`'s) and the pick's index in it."""
        start = _start(self.index, self.length, len(self.kept))
        return self.kept[start:start + self.length], self.index - start


def count_bridged(spells: Occlusions, assigned: dict, present: set, index: dict, rate: float,
                  max_spell: float) -> tuple[int, int, int, int, int]:
    """(spells, entered, kept, long_entered, long_kept) over the `spells` shorter than
    `max_spell` s with the person in the scene (`present`: (scan, id)) the scan before and the
    scan after; `assigned` (scan, id) -> the track matched, `index` round(time * rate) -> scan."""
    n = entered = kept = long_entered = long_kept = 0
    for pid, first, last in zip(spells.id.tolist(), spells.first, spells.last, strict=True):
        before = index.get(round(first * rate) - 1)
        after = index.get(round(last * rate) + 1)
        if (last - first >= max_spell or (before, pid) not in present
                or (after, pid) not in present):
            continue
        n += 1
        going_in = assigned.get((before, pid))
        if going_in is None:
            continue
        entered += 1
        same = assigned.get((after, pid)) == going_in
        kept += same
        if last - first >= 1.0:
            long_entered += 1
            long_kept += same
    return n, entered, kept, long_entered, long_kept


def run_scene(seed: int, occlusion: str, scans: int = 600,
              scene: LidarSceneConfig | None = None, tracker: ScanTrackerConfig | None = None,
              cutoff: float = 1.0, max_spell: float = 2.0,
              likelihood: str = "derived") -> ScanRun:
    scene = scene or LidarSceneConfig()
    config = tracker_config(scene, occlusion, likelihood, tracker)
    tr = ScanTracker(config, beams=scene.beams, rate=scene.rate)
    total = np.zeros(4)
    assigned: dict[tuple[int, int], int] = {}  # (scan, truth id) -> track id
    elapsed = 0.0
    last_track: dict[int, int] = {}  # truth id -> the track it was last matched to
    switches = 0
    times, ids, occluded, seen = [], [], [], []
    present: set[tuple[int, int]] = set()  # (scan, truth id) of the people in the scene
    points = PointTracks()
    confidence, right = [], []
    index: dict[int, int] = {}  # scan number at the scene's rate -> scan index
    for i, s in enumerate(simulate_scene(scene, scans, seed)):  # one scan in memory at a time
        index[round(s.time * scene.rate)] = i
        start = time.perf_counter()
        out = tr.update(s.range, s.pose[2] + s.angle, s.time, s.pose[:2])
        elapsed += time.perf_counter() - start
        person = s.objects.shapes.disc
        truth = s.objects.shapes.centre[person]
        g = gospa(truth, out.positions, "euclidean", c=cutoff, p=1.0)
        total += [g.total, g.localisation, g.missed, g.false]
        rows, cols = match(truth, out.positions, cutoff)
        tid = s.objects.id[person]
        for r, c in zip(rows, cols, strict=True):
            assigned[(i, int(tid[r]))] = int(out.ids[c])
            before = last_track.get(int(tid[r]))
            switches += before is not None and before != int(out.ids[c])
            last_track[int(tid[r])] = int(out.ids[c])
        present.update((i, int(p)) for p in tid)
        points.add(tid, truth, out.ids, out.positions)
        near = np.zeros(len(out), bool)
        near[match(truth, out.positions, scene.person_radius)[1]] = True
        confidence.append(out.confidence)
        right.append(near)
        times.append(np.full(len(tid), s.time))
        ids.append(tid)
        occluded.append(s.occluded[person])
        seen.append(s.visible[person] >= SEEN_BEAMS)
    rows_ = [np.concatenate(x) for x in (times, ids, occluded)]

    n, entered, kept, long_entered, long_kept = count_bridged(
        full_occlusions(*rows_, scene.period, seen=np.concatenate(seen)), assigned, present,
        index, scene.rate, max_spell)
    strict, _, strict_kept, _, _ = count_bridged(
        full_occlusions(*rows_, scene.period), assigned, present, index, scene.rate, max_spell)
    mean = total / max(len(index), 1)
    h = points.score(cutoff)
    ece = reliability_table(np.concatenate(confidence), np.concatenate(right)).ece
    return ScanRun(seed, occlusion, len(index), *mean, n, entered, kept, long_entered,
                   long_kept, len(index) / max(elapsed, 1e-9), likelihood, int(switches),
                   strict_spells=strict, strict_kept=strict_kept, hota=h.hota, deta=h.deta,
                   assa=h.assa, ece=ece)


def table(runs: list[ScanRun]) -> str:
    lines = ["| seed | occlusion | scans | GOSPA / scan (m) | loc. | missed | false | "
             "full occlusions < 2 s | tracked going in | kept | of them 1-2 s: kept | HOTA | ECE | "
             "scans/s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        lines.append(f"| {r.seed} | {r.occlusion} | {r.scans} | {r.gospa:.3f} | "
                     f"{r.localisation:.3f} | {r.missed:.3f} | {r.false:.3f} | {r.spells} | "
                     f"{r.entered} | {r.kept} | {r.long_kept}/{r.long_entered} | "
                     f"{r.hota:.3f} | {r.ece:.3f} | {r.scans_per_second:.0f} |")
    return "\n".join(lines)
