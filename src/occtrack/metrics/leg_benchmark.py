"""The leg-tracker benchmark's scoring: CLEAR MOT of people tracked with a 2-D laser.

The benchmark (Leigh, Pineau, Olmedo and Zhang, "Person Tracking and Following with 2D Laser
Scanners", ICRA 2015; recordings and scorer in the repository angusleigh/leg_tracker_benchmarks)
holds ROS bags of a laser at leg height with hand-clicked positions of the people, and scores a
tracker with CLEAR MOT (Bernardin and Stiefelhagen 2008) as its `clear_mot/scripts/clear_mot.py`
does. Its rules, followed here (the script was read; this is a separate implementation):

- Scans. The annotations are stamped with the bag's record times, and each annotated position
  is scored against the tracks of the last scan recorded at or before it (the script scores
  the messages that arrive between one scan and the next against the first of the two). Here
  a scan is a time of the tracks file (or of `scan_time`, see below).
- Distance. Euclidean distance in the plane; a pair matches only when it is closer than the
  threshold, 0.75 m (strictly).
- Matches persist. A (track, person) pair matched on an earlier scan is kept first, whenever
  both are on this scan and still closer than the threshold. The memory is one-to-one and long:
  a pair is forgotten only when its track or its person is matched to someone else, not when
  either is missing for a while.
- The rest is assigned by least total distance (the Hungarian method;
  `scipy.optimize.linear_sum_assignment`) over the unmatched tracks and people, with their
  plain distances, every track or every person getting a partner; only then are the pairs at
  or beyond the threshold dropped. So the threshold gates after the assignment, not before it:
  an assignment that is cheapest in total may pair a track with a far person and lose a pair
  that gating first would have kept (tests/test_leg_benchmark.py has such a case). motmetrics
  and occtrack.metrics.clear gate first.
- ID switches, counted per match against the memory: a track that was last matched to another
  person is a switch; so is a track new to the memory matched to a person who was last matched
  to another track. A switch is not also a valid match: valid + ID switches + misses = the
  annotated positions, as in the paper's Table III ("valid matches"), whereas CLEAR MOT's usual
  "matches" include the switches.
- MOTP: the mean distance of every match, switches included (metres; lower is better).
- MOTA = 1 - (misses + ID switches + false positives) / annotated positions. On
  person_following_outdoor_1 the benchmark ignores false positives (only the followed person
  is annotated, so other people's tracks would count as false), i.e. `mota_without_fp`.

Where this differs from the script, on purpose or for want of its information:
- False positives are counted on annotated scans only (tracks there that match nobody), and
  `false_positives_all_scans` counts them on every scan as the script does (tracks file rows
  minus matches). The benchmark's published MOTA for the recordings that use FPs counts them
  on every scan.
- Annotated positions earlier than every scan are misses here (`early`); the script drops the
  messages before its first scan.
- Several annotated positions of one person assigned to the same scan: the last (in time, then
  file order) is kept, the earlier are dropped and counted (`duplicates`).
- A tracks file has rows only for scans with a reported object, so a scan where the tracker
  reported nothing is not a time of the file, and an annotation made then would be scored
  against the scan before it. Giving every scan's time (`scan_time`; `occtrack eval-scans
  --scans`) makes those scans empty, as in the script, which sees every scan. Scan times are
  matched to the tracks' to the microsecond (the tracks file's precision).

Why written here: no library applies this benchmark's rules. motmetrics' accumulator (the `eval`
extra) gates before assigning, counts a switch only from the person's side and counts switches
among the matches, so its numbers are not the benchmark's; ours is a short loop over the
annotated scans with scipy's assignment, and keeps the core free of motmetrics and pandas.
The published numbers on person_following_outdoor_1 (valid / ID switches / misses, MOTP):
leg_tracker "Joint Leg" 6,073 / 21 / 104, 0.09 m; "Individual Leg" 5,348 / 121 / 819, 0.11 m;
ROS leg_detector 4,835 / 1,721 / 1,172, 0.09 m.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

THRESHOLD = 0.75
"""The benchmark's match threshold, metres."""


@dataclass(frozen=True)
class LegScores:
    """The benchmark's counts and ratios for one tracks file. Ratios are NaN where their
    denominator is zero."""

    threshold: float  # m, a match is closer than this
    scans: int  # annotated scans scored (scans with at least one annotated position)
    all_scans: int  # scans: the tracks file's times (and the scan times given)
    truth: int  # annotated positions scored: valid + id_switches + misses
    early: int  # of them, before every scan (misses)
    duplicates: int  # annotated positions dropped: a later one of the same id on the same scan
    valid: int  # matches that are not ID switches (the paper's "valid matches")
    id_switches: int
    misses: int
    false_positives: int  # tracks that match nobody, on annotated scans
    false_positives_all_scans: int  # tracks that match nobody, on every scan
    track_rows: int  # reported objects over all scans
    motp: float  # mean distance of all matches (valid and switches), m
    mota: float  # 1 - (misses + id_switches + false_positives) / truth
    mota_without_fp: float  # 1 - (misses + id_switches) / truth (the benchmark's here)
    tracks_per_scan: float  # track_rows / all_scans
    false_tracks_per_scan: float  # false_positives / scans

    def as_dict(self) -> dict:
        """The fields, NaN as None (JSON has no NaN)."""
        return {k: (None if isinstance(v, float) and v != v else v)
                for k, v in asdict(self).items()}


def _ratio(a: float, b: float) -> float:
    return a / b if b else float("nan")


def _column(values, name: str, dtype, width: int | None = None) -> np.ndarray:
    a = np.asarray(values, dtype=dtype)
    if width is None:
        a = a.reshape(-1)
    else:
        if a.size == 0:
            a = a.reshape(0, width)
        if a.ndim != 2 or a.shape[1] != width:
            raise ValueError(f"{name} must be ({width},) a row, got shape {a.shape}")
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        raise ValueError(f"{name} holds a NaN or infinite value")
    return a


def _rows_per_scan(scan: np.ndarray, n_scans: int) -> np.ndarray:
    """Row offsets of each scan's rows in rows sorted by scan: scan s holds
    start[s]:start[s + 1]."""
    return np.searchsorted(scan, np.arange(n_scans + 1)).astype(np.int64)


def score(truth_time, truth_id, truth_xy, track_time, track_id, track_xy,
          threshold: float = THRESHOLD, scan_time=None) -> LegScores:
    """Score tracks against annotated positions by the benchmark's rules (module docstring).

    truth_time (N,) s, truth_id (N,) and truth_xy (N, 2) m: the annotated positions;
    track_time (M,), track_id (M,) and track_xy (M, 2): the reported objects, one row an object
    a scan, the scan being its time (an id appears at most once a scan); both in one frame and
    in any order. scan_time: every scan's time when some scans may have no reported object
    (they are added, empty; default: the tracks' times only). ValueError on a shape, a NaN or
    a repeated track id within a scan.
    """
    threshold = float(threshold)
    if not (np.isfinite(threshold) and threshold > 0):
        raise ValueError(f"threshold must be a positive number of metres, got {threshold}")
    g_time = _column(truth_time, "truth_time", float)
    g_id = _column(truth_id, "truth_id", np.int64)
    g_xy = _column(truth_xy, "truth_xy", float, 2)
    e_time = _column(track_time, "track_time", float)
    e_id = _column(track_id, "track_id", np.int64)
    e_xy = _column(track_xy, "track_xy", float, 2)
    if not len(g_time) == len(g_id) == len(g_xy):
        raise ValueError("truth_time, truth_id and truth_xy need one entry a position")
    if not len(e_time) == len(e_id) == len(e_xy):
        raise ValueError("track_time, track_id and track_xy need one entry a reported object")

    # Scans: the tracks' times, with the given scan times matched to them to the microsecond.
    times = e_time
    if scan_time is not None:
        times = np.round(np.r_[e_time, _column(scan_time, "scan_time", float)], 6)
        e_time = np.round(e_time, 6)
    scans = np.unique(times)
    e_scan = np.searchsorted(scans, e_time)
    order = np.lexsort((e_id, e_scan))
    e_scan, e_id, e_xy = e_scan[order], e_id[order], e_xy[order]
    twice = np.flatnonzero((np.diff(e_scan) == 0) & (np.diff(e_id) == 0))
    if len(twice):
        k = twice[0]
        raise ValueError(f"track id {e_id[k]} appears twice in the scan at time "
                         f"{scans[e_scan[k]]:.6f}")
    e_start = _rows_per_scan(e_scan, len(scans))

    # Each annotated position to the last scan at or before it; the last of an id a scan kept.
    g_scan = np.searchsorted(scans, g_time, side="right") - 1
    early = int(np.sum(g_scan < 0))
    placed = np.flatnonzero(g_scan >= 0)
    order = placed[np.lexsort((placed, g_time[placed], g_id[placed], g_scan[placed]))]
    last = np.r_[(np.diff(g_scan[order]) != 0) | (np.diff(g_id[order]) != 0),
                 np.ones(min(len(order), 1), bool)]
    duplicates = int(np.sum(~last))
    keep = order[last]
    keep = keep[np.lexsort((g_id[keep], g_scan[keep]))]
    g_scan, g_id, g_xy = g_scan[keep], g_id[keep], g_xy[keep]
    annotated = np.unique(g_scan)
    g_start = np.searchsorted(g_scan, annotated)
    g_stop = np.searchsorted(g_scan, annotated, side="right")

    memory: dict[int, int] = {}  # track id -> the person it was last matched to
    valid = switches = misses = false_positives = matched = 0
    distance_sum = 0.0
    for s, g0, g1 in zip(annotated.tolist(), g_start.tolist(), g_stop.tolist(), strict=True):
        people, p_xy = g_id[g0:g1].tolist(), g_xy[g0:g1]
        tracks, t_xy = e_id[e_start[s]:e_start[s + 1]].tolist(), e_xy[e_start[s]:e_start[s + 1]]
        d = np.hypot(*(t_xy[:, None, :] - p_xy[None, :, :]).transpose(2, 0, 1))
        row = {t: i for i, t in enumerate(tracks)}
        col = {p: j for j, p in enumerate(people)}
        pairs: list[tuple[int, int]] = []  # (track row, person column)
        for t, p in memory.items():  # 1. last scan's matches that still hold
            i, j = row.get(t), col.get(p)
            if i is not None and j is not None and d[i, j] < threshold:
                pairs.append((i, j))
        kept_i, kept_j = {i for i, _ in pairs}, {j for _, j in pairs}
        free_i = [i for i in range(len(tracks)) if i not in kept_i]
        free_j = [j for j in range(len(people)) if j not in kept_j]
        if free_i and free_j:  # 2. the rest by least total distance, then gated
            sub = d[np.ix_(free_i, free_j)]
            a, b = linear_sum_assignment(sub)
            pairs += [(free_i[x], free_j[y]) for x, y in zip(a.tolist(), b.tolist(), strict=True)
                      if sub[x, y] < threshold]
        last_match = set(memory.values())
        for i, j in pairs:  # 3. valid or switch, against the memory before this scan
            t, p = tracks[i], people[j]
            if t in memory:
                switched = memory[t] != p
            else:
                switched = p in last_match
            switches += switched
            valid += not switched
            distance_sum += float(d[i, j])
        matched += len(pairs)
        misses += len(people) - len(pairs)
        false_positives += len(tracks) - len(pairs)
        if pairs:  # 4. the new matches replace what they contradict
            new = {tracks[i]: people[j] for i, j in pairs}
            taken = set(new.values())
            memory = {t: p for t, p in memory.items() if t not in new and p not in taken}
            memory.update(new)

    misses += early
    truth = len(keep) + early
    return LegScores(
        threshold=threshold, scans=len(annotated), all_scans=len(scans), truth=truth,
        early=early, duplicates=duplicates, valid=valid, id_switches=switches, misses=misses,
        false_positives=false_positives, false_positives_all_scans=len(e_id) - matched,
        track_rows=len(e_id), motp=_ratio(distance_sum, matched),
        mota=1.0 - _ratio(misses + switches + false_positives, truth),
        mota_without_fp=1.0 - _ratio(misses + switches, truth),
        tracks_per_scan=_ratio(len(e_id), len(scans)),
        false_tracks_per_scan=_ratio(false_positives, len(annotated)))


def _percent(x: float) -> str:
    return "-" if x != x else f"{100 * x:.1f}%"


def _metres(x: float) -> str:
    return "-" if x != x else f"{x:.3f}"


def _per_scan(x: float) -> str:
    return "-" if x != x else f"{x:.2f}"


COLUMNS = ("valid", "ID sw", "misses", "FP", "MOTP m", "MOTA", "MOTA-FP", "tracks/scan",
           "FP/scan")


def table(scores: LegScores | Mapping[str, LegScores], name: str = "tracks") -> str:
    """The scores as text, one row a result (a mapping name -> LegScores, or one LegScores
    called `name`), the paper's Table III columns first: valid matches, ID switches, misses,
    then false positives on annotated scans, MOTP (m), MOTA with and without (MOTA-FP) false
    positives, reported objects a scan (all scans) and false positives an annotated scan."""
    results = {name: scores} if isinstance(scores, LegScores) else dict(scores)
    rows = [[key, f"{s.valid:,}", f"{s.id_switches:,}", f"{s.misses:,}",
             f"{s.false_positives:,}", _metres(s.motp), _percent(s.mota),
             _percent(s.mota_without_fp), _per_scan(s.tracks_per_scan),
             _per_scan(s.false_tracks_per_scan)] for key, s in results.items()]
    head = ["", *COLUMNS]
    widths = [max(len(r[k]) for r in [head, *rows]) for k in range(len(head))]
    lines = ["  ".join([r[0].ljust(widths[0])] + [c.rjust(w) for c, w in
                                                  zip(r[1:], widths[1:], strict=True)])
             for r in [head, *rows]]
    thresholds = sorted({s.threshold for s in results.values()})
    lines.append(f"CLEAR MOT, a match closer than {', '.join(f'{t:g}' for t in thresholds)} m;"
                 f" MOTA-FP: false positives ignored (the benchmark's on "
                 f"person_following_outdoor_1)")
    return "\n".join(lines)


def summary(scores: LegScores) -> str:
    """One line: what was scored and the headline numbers."""
    s = scores
    early = f" ({s.early:,} before the first scan)" if s.early else ""
    dropped = f", {s.duplicates:,} repeated positions dropped" if s.duplicates else ""
    return (f"{s.truth:,} annotated positions{early} on {s.scans:,} of {s.all_scans:,} scans"
            f"{dropped}: {s.valid:,} valid, {s.id_switches:,} ID switches, {s.misses:,} misses,"
            f" MOTP {_metres(s.motp)} m, MOTA {_percent(s.mota_without_fp)} without false "
            f"positives ({s.false_positives:,} of them: MOTA {_percent(s.mota)})")
