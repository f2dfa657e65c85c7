"""Detector calibration: the tracker's detector model estimated from labelled sequences.

Given ground truth and a detector's output on the same frames, every detection is matched to
the ground truth of its frame (Hungarian assignment maximising the summed IoU over pairs with
IoU >= 0.5, against the pedestrians and the distractor classes together, as TrackEval's
MOTChallenge preprocessing does): a detection matched to a pedestrian (class 1, consider flag
not 0; every row of a file without a class column) is a hit, one matched to a distractor
(classes 2, 7, 8, 12: person on vehicle, static person, distractor, reflection) is set aside,
and the others are false. From that:

- detection probability P_D against the ground truth's visibility and box height, in bins and
  jointly; the stationary detectability of visible people (visibility >= `VISIBLE`: what an
  occlusion model needs, as it explains the misses behind others), that of tracked people
  (P(hit | the person was detected within the last `horizon` seconds, `HORIZON`: what
  `occlusion = none` needs, see `Calibration.settings`), and the
  lag-one memory of detection along each person's frames, which fixes the tracker's
  `detectability_ratio` (the Markov feature of `occtrack.models.markov`: for a two-state chain
  P(hit | hit) - P(hit | miss) is the memory per step, lambda = (1 - h) ** (dt / 0.5)), over
  the pairs of frames in which the person is tracked (detected within `horizon` before the
  second): the chain is the tracker's, run on the objects it holds, so a person it never
  detects or lost long ago does not count. Of every tracked person for the tracker's setting
  (`Calibration.settings`), and of tracked people in view (both frames visible) as the
  detector's own property, which a simulated detector needs (`occtrack.config.street`): on
  MOT17-04, -05 and -11 pooled 0.929 and 0.485 a frame; counting people never detected, as
  this module did before, the second was 0.911, 162 of its 216 pairs after a miss one person
  on MOT17-11, 52 px tall and in full view, missed in all 163 of its frames;
- false detections per frame against the score, and the tracker's clutter term fitted to them:
  the tracker weighs a detection z of score s against clutter with
  kappa(z) = clutter_rate / (W H w h) * s ** -clutter_score_power, and its hit term has no
  score density, so the clutter term must be the false detections' intensity over the true
  detections' score density: clutter_rate * s ** -p = lambda_F f_F(s) / (f_T(s) A), with
  lambda_F the false detections per frame, f_F and f_T the score densities of false and true
  detections and A the area in (log w, log h) over which false boxes spread (a scale-free size
  density 1 / (w h) over that area; A is taken as the 1st-99th percentile range of log width
  times that of log height of all detections). It is fitted by weighted least squares of
  log(clutter_rate) - p log s over score bins (a power p < 0 is clipped to 0);
- box-edge noise: each matched edge's error (detection minus truth) over the true box height
  (the tracker's `edge_noise` unit) and over its own axis' size (width for left / right,
  height for top / bottom), for people with visibility >= `EDGE_VISIBILITY` and edges not
  within `BORDER` px of the image border (clipped by the detector); mean (bias), standard
  deviation and a robust one (1.4826 MAD).

Confidence intervals are 95 % and honour that rows are not independent (a person's
detections go in runs; false boxes in bursts): a cluster bootstrap over people (detection,
edge noise) or over one-second blocks of frames (false detections) gives the variance, and
proportions and rates get Wilson and exact Poisson intervals at the effective sample size
n / design effect (design effect = bootstrap variance over the binomial or Poisson one, at
least 1); fitted settings get bootstrap percentile intervals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.stats import chi2, norm
from scipy.stats import t as student_t

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.spatial import iou

PEDESTRIAN = 1
DISTRACTOR_CLASSES = (2, 7, 8, 12)
MATCH_IOU = 0.5
VISIBLE = 0.75
EDGE_VISIBILITY = 0.5
BORDER = 2.0
VISIBILITY_BINS = (0.0, 0.25, 0.5, 0.75, 1.0)
HEIGHT_BINS = (0.0, 50.0, 100.0, 200.0, 400.0, math.inf)
SCORE_BINS = (0.0, 0.5, 0.9, 0.99, 0.999, 1.0)
HORIZON = 0.67
"""s: how long after a person's last detection a tracker is taken to hold them (what occtrack
reported an unseen object for before its confidence decided reporting)."""
EDGES = ("left", "top", "right", "bottom")
BOOTSTRAP = 400
Z95 = float(norm.ppf(0.975))


@dataclass(frozen=True)
class Estimate:
    """A value, its 95 % interval and the count behind it (`n`: rows; `effective`: rows over
    the design effect)."""

    value: float
    low: float
    high: float
    n: int = 0
    effective: float = float("nan")

    def covers(self, x: float) -> bool:
        return self.low <= x <= self.high

    def text(self, digits: int = 3) -> str:
        if math.isnan(self.value):
            return "-"
        return (f"{self.value:.{digits}f} [{self.low:.{digits}f}, {self.high:.{digits}f}]")


@dataclass(frozen=True)
class Labelled:
    """One sequence: its ground truth and detections, image size and frame rate, frames."""

    name: str
    gt: MotTable
    det: MotTable
    image_size: tuple[float, float]
    fps: float
    num_frames: int


@dataclass
class Calibration:
    """Everything `calibrate` measures; `settings()` gives the TrackerConfig fields."""

    sequences: list[str]
    frames: int
    targets: int
    detections: int
    hits: int
    false: int
    set_aside: int
    detection_overall: Estimate
    detectability: Estimate
    detection_tracked: Estimate  # P(hit | detected within the last `horizon` s)
    horizon: float
    # memory of detection per frame and the chain's half-second ratio: of tracked people in
    # view (the detector's own, for a simulated detector), of tracked people (the setting)
    memory_visible: Estimate
    ratio_visible: Estimate
    memory_tracked: Estimate
    ratio_tracked: Estimate
    by_visibility: list[tuple[float, float, Estimate]]
    by_height: list[tuple[float, float, Estimate]]
    joint: list[list[Estimate]]
    false_per_frame: Estimate
    by_score: list[tuple[float, float, Estimate, int]]  # (lo, hi, false per frame, hits)
    size_area: float
    clutter_rate: Estimate
    clutter_score_power: Estimate
    edge_bias: dict[str, Estimate]
    edge_std: dict[str, Estimate]  # in true box heights
    edge_std_own: dict[str, Estimate]  # in the edge's own axis size (width or height)
    edge_robust: dict[str, float]  # in true box heights
    edge_noise: Estimate  # pooled over the four edges, true box heights
    notes: list[str] = field(default_factory=list)

    def settings(self, occlusion: bool = True) -> dict:
        """The TrackerConfig fields this calibration sets. With `occlusion` (an occlusion
        model explains misses behind others) the detectability is that of visible people.
        Without, it is that of tracked people, not of every person: the tracker's P_D only
        weighs the misses of the objects it holds, and it holds a person from a detection
        until about `horizon` of misses; the people it never detected, or
        lost long ago (deep in an occlusion), are misses it never scores, and counting them
        (P_D 0.55 on MOT17-04) makes each miss nearly free, so tracks of people who left or
        went out of sight coast on as false boxes. The detectability chain's memory is that of
        tracked people for every model (`ratio_tracked`): the chain carries the runs of misses
        a model does not explain: behind others for `none`, and for an occlusion model behind
        what its box geometry does not see, which come in runs too (the memory of people in
        view, `ratio_visible`, is the detector's own, for a simulated detector)."""
        detect = self.detectability if occlusion else self.detection_tracked
        ratio = self.ratio_tracked
        out = {}
        if not math.isnan(detect.value):
            out["detectability"] = _clip(detect.value, 0.01, 0.999)
        if not math.isnan(ratio.value):
            out["detectability_ratio"] = _clip(ratio.value, 0.0, 1.0)
        if not math.isnan(self.clutter_rate.value) and self.clutter_rate.value > 0:
            out["clutter_rate"] = self.clutter_rate.value
            out["clutter_score_power"] = max(self.clutter_score_power.value, 0.0)
        if not math.isnan(self.edge_noise.value) and self.edge_noise.value > 0:
            out["edge_noise"] = self.edge_noise.value
        return out


def _clip(x: float, lo: float, hi: float) -> float:
    return float(min(max(x, lo), hi))


# ----------------------------------------------------------------------------------------------
# Matching


@dataclass(frozen=True)
class Matched:
    """Per ground-truth row: target (a pedestrian to detect) and the detection row it took
    (-1: none); per detection row: its kind, 1 hit, 0 false, -1 set aside."""

    target: np.ndarray
    gt_match: np.ndarray
    det_kind: np.ndarray


def match(gt: MotTable, det: MotTable, num_frames: int) -> Matched:
    has_class = len(gt) > 0 and bool((gt.cls >= 0).all())
    if has_class:
        target = (gt.cls == PEDESTRIAN) & (gt.score != 0)
        aside = np.isin(gt.cls, DISTRACTOR_CLASSES) | ((gt.cls == PEDESTRIAN) & (gt.score == 0))
    else:
        target = np.ones(len(gt), dtype=bool)
        aside = np.zeros(len(gt), dtype=bool)
    used = target | aside
    gt_match = np.full(len(gt), -1, dtype=np.int64)
    det_kind = np.zeros(len(det), dtype=np.int64)
    gt_rows = gt.select(np.flatnonzero(used)).frame_slices(num_frames)
    gt_index = np.flatnonzero(used)
    for g, d in zip(gt_rows, det.frame_slices(num_frames), strict=True):
        if len(g) == 0 or len(d) == 0:
            continue
        rows = gt_index[g]
        sim = iou(gt.box[rows], det.box[d])
        score = np.where(sim >= MATCH_IOU - 1e-12, sim, 0.0)
        r, c = linear_sum_assignment(-score)
        ok = score[r, c] > 0
        r, c = rows[r[ok]], d[c[ok]]
        is_target = target[r]
        gt_match[r[is_target]] = c[is_target]
        det_kind[c[is_target]] = 1
        det_kind[c[~is_target]] = -1
    return Matched(target, gt_match, det_kind)


# ----------------------------------------------------------------------------------------------
# Intervals


def _inflation(clusters: int) -> float:
    """How much wider than a large-sample interval one over `clusters` resampled clusters is
    made: the bootstrap variance times C / (C - 1) (it is biased low by (C - 1) / C) and
    Student's t with C - 1 degrees of freedom for the normal quantile."""
    if clusters < 2:
        return float("inf")
    return math.sqrt(clusters / (clusters - 1)) * float(student_t.ppf(0.975, clusters - 1)) / Z95


def _bootstrap_weights(clusters: int, rng: np.random.Generator, draws: int = BOOTSTRAP):
    """(draws, clusters) counts: how often each cluster is drawn in each resample."""
    if clusters == 0:
        return np.zeros((draws, 0))
    return rng.multinomial(clusters, np.full(clusters, 1.0 / clusters), size=draws).astype(float)


def _wilson(p: float, n_eff: float) -> tuple[float, float]:
    if n_eff <= 0:
        return 0.0, 1.0
    z2 = Z95 * Z95
    centre = (p + z2 / (2 * n_eff)) / (1 + z2 / n_eff)
    half = Z95 * math.sqrt(p * (1 - p) / n_eff + z2 / (4 * n_eff * n_eff)) / (1 + z2 / n_eff)
    return max(0.0, centre - half), min(1.0, centre + half)


def proportion(hits: np.ndarray, totals: np.ndarray, weights: np.ndarray) -> list[Estimate]:
    """Per column k of the per-cluster counts `hits` and `totals` (clusters, K): the pooled
    proportion with a Wilson interval at the effective size (cluster bootstrap `weights`)."""
    h, t = hits.sum(axis=0), totals.sum(axis=0)
    bh, bt = weights @ hits, weights @ totals
    out = []
    for k in range(hits.shape[1]):
        if t[k] == 0:
            out.append(Estimate(float("nan"), float("nan"), float("nan"), 0, 0.0))
            continue
        p = h[k] / t[k]
        ok = bt[:, k] > 0
        var = float(np.var(bh[ok, k] / bt[ok, k], ddof=1)) if ok.sum() > 1 else 0.0
        binomial = p * (1 - p) / t[k]
        deff = max(1.0, var / binomial) if binomial > 0 else 1.0
        deff *= _inflation(int((totals[:, k] > 0).sum())) ** 2
        n_eff = t[k] / deff
        lo, hi = _wilson(p, n_eff)
        out.append(Estimate(float(p), lo, hi, int(t[k]), float(n_eff)))
    return out


def rate(counts: np.ndarray, frames: float, weights: np.ndarray,
         block_frames: np.ndarray) -> list[Estimate]:
    """Per column of the per-block event counts (blocks, K): events per frame with an exact
    Poisson interval at the effective count (block bootstrap `weights`)."""
    n, out = counts.sum(axis=0), []
    bf = weights @ block_frames
    bn = weights @ counts
    for k in range(counts.shape[1]):
        r = n[k] / frames
        var = float(np.var(bn[:, k] / bf, ddof=1)) if len(bf) > 1 else 0.0
        poisson = r / frames
        deff = max(1.0, var / poisson) if poisson > 0 else 1.0
        deff *= _inflation(len(block_frames)) ** 2
        if math.isinf(deff):  # one block of frames: nothing bounds the rate above
            out.append(Estimate(float(r), 0.0, math.inf, int(n[k]), 0.0))
            continue
        eff_n, eff_frames = n[k] / deff, frames / deff
        lo = chi2.ppf(0.025, 2 * eff_n) / 2 / eff_frames if eff_n > 0 else 0.0
        hi = chi2.ppf(0.975, 2 * eff_n + 2) / 2 / eff_frames
        out.append(Estimate(float(r), float(lo), float(hi), int(n[k]), float(eff_n)))
    return out


def _percentile(value: float, draws: np.ndarray, n: int = 0, clusters: int = 0,
                bounds: tuple[float, float] = (-math.inf, math.inf)) -> Estimate:
    """The bootstrap percentile interval, widened about the estimate by `_inflation` of the
    number of resampled clusters and kept within `bounds`."""
    draws = draws[np.isfinite(draws)]
    if math.isnan(value) or len(draws) < 10:
        return Estimate(value, float("nan"), float("nan"), n)
    lo, hi = np.percentile(draws, [2.5, 97.5])
    grow = _inflation(clusters) if clusters else 1.0
    if math.isinf(grow):  # one cluster: its draws say nothing of the spread
        return Estimate(float(value), float(bounds[0]), float(bounds[1]), n)
    lo, hi = value - grow * max(value - lo, 0.0), value + grow * max(hi - value, 0.0)
    return Estimate(float(value), float(max(lo, bounds[0])), float(min(hi, bounds[1])), n)


# ----------------------------------------------------------------------------------------------
# The estimate


def _bins(values: np.ndarray, edges) -> np.ndarray:
    """Bin index of each value; the last bin is closed on the right."""
    idx = np.searchsorted(np.asarray(edges), values, side="right") - 1
    return np.clip(idx, 0, len(edges) - 2)


def calibrate(sequences: list[Labelled], seed: int = 0,
              horizon: float = HORIZON) -> Calibration:
    """Estimate the detector model from labelled sequences (see the module docstring);
    `horizon`: seconds after a person's last detection in which the tracker still holds
    them (the population of `detection_tracked`)."""
    if not sequences:
        raise OcctrackError("calibration needs at least one pair of ground truth and detections")
    rng = np.random.default_rng(seed)
    # per target row: cluster (person), visibility, height, hit; consecutive pairs; edges
    t_cluster, t_vis, t_h, t_hit, t_recent = [], [], [], [], []
    pair_cluster, pair_prev, pair_now, pair_half, pair_visible = [], [], [], [], []
    e_cluster, e_err, e_h, e_size, e_valid = [], [], [], [], []
    f_block, f_bin, f_kind, block_frames = [], [], [], []
    det_w, det_h = [], []
    frames = detections = hits = false = aside = 0
    n_clusters = n_blocks = 0
    notes = []
    for seq in sequences:
        m = match(seq.gt, seq.det, seq.num_frames)
        gt, det = seq.gt, seq.det
        frames += seq.num_frames
        detections += len(det)
        hits += int((m.det_kind == 1).sum())
        false += int((m.det_kind == 0).sum())
        aside += int((m.det_kind == -1).sum())
        det_w.append(det.box[:, 2])
        det_h.append(det.box[:, 3])

        rows = np.flatnonzero(m.target)
        ids, cluster = np.unique(gt.id[rows], return_inverse=True)
        vis = gt.visibility[rows]
        if (vis < 0).any():
            notes.append(f"{seq.name}: no visibility column; every person counted as visible")
        vis = np.where(vis < 0, 1.0, vis)
        hit = m.gt_match[rows] >= 0
        t_cluster.append(cluster + n_clusters)
        t_vis.append(vis)
        t_h.append(gt.box[rows, 3])
        t_hit.append(hit)

        # consecutive frames of one person, both visible, the person tracked (detected
        # within the horizon before the second): the memory of detection the tracker weighs
        order = np.lexsort((gt.frame[rows], cluster))
        c_o, f_o, v_o, h_o = cluster[order], gt.frame[rows][order], vis[order], hit[order]
        recent_o = _recently_detected(c_o, f_o, h_o, max(1, int(round(horizon * seq.fps))))
        recent = np.empty(len(rows), dtype=bool)
        recent[order] = recent_o
        t_recent.append(recent)
        held = (c_o[1:] == c_o[:-1]) & (f_o[1:] == f_o[:-1] + 1) & recent_o[1:]
        nxt = held & (v_o[1:] >= VISIBLE) & (v_o[:-1] >= VISIBLE)
        pair_cluster.append(c_o[1:][held] + n_clusters)
        pair_prev.append(h_o[:-1][held])
        pair_now.append(h_o[1:][held])
        pair_half.append(np.full(int(held.sum()), seq.fps / 2.0))
        pair_visible.append(nxt[held])

        # edges of matched, mostly visible people, away from the border
        sel = hit & (vis >= EDGE_VISIBILITY)
        g_rows, d_rows = rows[sel], m.gt_match[rows][sel]
        g = np.concatenate([gt.box[g_rows, :2], gt.box[g_rows, :2] + gt.box[g_rows, 2:]], 1)
        d = np.concatenate([det.box[d_rows, :2], det.box[d_rows, :2] + det.box[d_rows, 2:]],
                           1)
        W, H = seq.image_size
        limit = np.array([W, H, W, H], dtype=float)
        inside = ((np.minimum(g, d) > BORDER) & (np.maximum(g, d) < limit - BORDER))
        e_cluster.append(cluster[sel] + n_clusters)
        e_err.append(d - g)
        e_h.append(gt.box[g_rows, 3])
        e_size.append(gt.box[g_rows][:, [2, 3, 2, 3]])
        e_valid.append(inside)
        n_clusters += len(ids)

        # false detections per one-second block of frames, by score bin
        block_len = max(1, int(round(seq.fps)))
        blocks = (seq.num_frames + block_len - 1) // block_len
        f_block.append((det.frame - 1) // block_len + n_blocks)
        f_bin.append(_bins(det.score, SCORE_BINS))
        f_kind.append(m.det_kind)
        sizes = np.full(blocks, block_len, dtype=float)
        sizes[-1] = seq.num_frames - block_len * (blocks - 1)
        block_frames.append(sizes)
        n_blocks += blocks

    cat = np.concatenate
    t_cluster, t_vis, t_h, t_hit = cat(t_cluster), cat(t_vis), cat(t_h), cat(t_hit)
    t_recent = cat(t_recent)
    targets = len(t_hit)
    if targets == 0:
        raise OcctrackError("the ground truth holds no pedestrian to calibrate against "
                            "(class 1 with a consider flag of 1)")
    weights = _bootstrap_weights(n_clusters, rng)

    def per_cluster(mask_columns: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        k = len(mask_columns)
        hit_sums, totals = np.zeros((n_clusters, k)), np.zeros((n_clusters, k))
        for j, mask in enumerate(mask_columns):
            np.add.at(hit_sums[:, j], t_cluster[mask], t_hit[mask])
            np.add.at(totals[:, j], t_cluster[mask], 1.0)
        return hit_sums, totals

    vb, hb = _bins(t_vis, VISIBILITY_BINS), _bins(t_h, HEIGHT_BINS)
    nv, nh = len(VISIBILITY_BINS) - 1, len(HEIGHT_BINS) - 1
    columns = ([np.ones(targets, dtype=bool), t_vis >= VISIBLE]
               + [vb == i for i in range(nv)] + [hb == j for j in range(nh)]
               + [(vb == i) & (hb == j) for i in range(nv) for j in range(nh)]
               + [t_recent])
    est = proportion(*per_cluster(columns), weights)
    overall, visible, tracked = est[0], est[1], est[-1]
    by_vis = [(VISIBILITY_BINS[i], VISIBILITY_BINS[i + 1], est[2 + i]) for i in range(nv)]
    by_h = [(HEIGHT_BINS[j], HEIGHT_BINS[j + 1], est[2 + nv + j]) for j in range(nh)]
    joint = [[est[2 + nv + nh + i * nh + j] for j in range(nh)] for i in range(nv)]

    pairs = cat(pair_cluster), cat(pair_prev), cat(pair_now), cat(pair_half)
    seen = cat(pair_visible)
    memory, ratio = _memory(*(a[seen] for a in pairs), weights)
    memory_tracked, ratio_tracked = _memory(*pairs, weights)

    # false detections
    f_block, f_bin, f_kind = cat(f_block), cat(f_bin), cat(f_kind)
    block_frames = cat(block_frames)
    nb = len(SCORE_BINS) - 1
    fp_counts = np.zeros((n_blocks, nb + 1))
    hit_counts = np.zeros((n_blocks, nb))
    fp = f_kind == 0
    np.add.at(fp_counts, (f_block[fp], f_bin[fp]), 1.0)
    np.add.at(fp_counts[:, nb], f_block[fp], 1.0)
    np.add.at(hit_counts, (f_block[f_kind == 1], f_bin[f_kind == 1]), 1.0)
    block_weights = _bootstrap_weights(n_blocks, rng)
    rates = rate(fp_counts, frames, block_weights, block_frames)
    by_score = [(SCORE_BINS[k], SCORE_BINS[k + 1], rates[k], int(hit_counts[:, k].sum()))
                for k in range(nb)]
    all_w, all_h = cat(det_w), cat(det_h)
    size_area = _size_area(all_w, all_h)
    centres = _score_centres(f_bin, f_kind, cat([s.det.score for s in sequences]))
    clutter_rate, power = _fit_clutter(fp_counts[:, :nb], hit_counts, frames, block_frames,
                                       size_area, centres, block_weights)

    edge = _edge_noise(cat(e_cluster), cat(e_err), cat(e_h), cat(e_size), cat(e_valid),
                       n_clusters, weights)
    return Calibration(
        sequences=[s.name for s in sequences], frames=frames, targets=targets,
        detections=detections, hits=hits, false=false, set_aside=aside,
        detection_overall=overall, detectability=visible, detection_tracked=tracked,
        horizon=float(horizon), memory_visible=memory,
        ratio_visible=ratio, memory_tracked=memory_tracked, ratio_tracked=ratio_tracked,
        by_visibility=by_vis, by_height=by_h, joint=joint,
        false_per_frame=rates[nb], by_score=by_score, size_area=size_area,
        clutter_rate=clutter_rate, clutter_score_power=power, notes=notes, **edge)


def _recently_detected(cluster, frame, hit, frames: int) -> np.ndarray:
    """Per row of one person's rows sorted by (person, frame): was the person detected in one
    of the `frames` frames before this one?"""
    if len(frame) == 0:
        return np.zeros(0, dtype=bool)
    span = int(frame.max()) + 2
    # a running maximum of person * span + frame of each hit (0 for a miss) stays within the
    # person's own rows, as the rows are sorted by person and frames are >= 1
    running = np.maximum.accumulate(cluster * span + np.where(hit, frame, 0))
    last = np.concatenate([[-1], running[:-1]]) - cluster * span
    return (last >= 1) & (frame - last <= frames)


def _memory(cluster, prev, now, half_steps, weights) -> tuple[Estimate, Estimate]:
    """lambda = P(hit | hit before) - P(hit | miss before) per frame, and the tracker's
    half-second ratio h = 1 - lambda ** (frames per half second), each with a percentile
    interval over the person bootstrap."""
    n = len(prev)
    nan = Estimate(float("nan"), float("nan"), float("nan"), n)
    if n == 0 or prev.all() or not prev.any():
        return nan, nan
    k = weights.shape[1]
    sums = np.zeros((k, 5))
    for j, values in enumerate((prev & now, prev, ~prev & now, ~prev,
                                half_steps)):
        np.add.at(sums[:, j], cluster, values.astype(float))
    counts = np.zeros(k)
    np.add.at(counts, cluster, 1.0)

    def stats(s, c):
        s = np.atleast_2d(s)
        c = np.atleast_1d(c)
        with np.errstate(invalid="ignore", divide="ignore"):
            lam = s[:, 0] / s[:, 1] - s[:, 2] / s[:, 3]
            half = s[:, 4] / c
            h = 1.0 - np.clip(lam, 0.0, 1.0) ** half
        return lam, h

    lam, h = stats(sums.sum(axis=0), counts.sum())
    blam, bh = stats(weights @ sums, weights @ counts)
    used = int((counts > 0).sum())
    return (_percentile(float(lam[0]), blam, n, used, (-1.0, 1.0)),
            _percentile(float(h[0]), bh, n, used, (0.0, 1.0)))


def _size_area(widths: np.ndarray, heights: np.ndarray) -> float:
    """The area in (log w, log h) over which false boxes are taken to spread: the 1st-99th
    percentile range of log width times that of log height of all detections (at least
    0.1 x 0.1)."""
    ok = (widths > 0) & (heights > 0)
    if ok.sum() < 2:
        return 1.0
    lw, lh = np.log(widths[ok]), np.log(heights[ok])
    span = [max(float(np.diff(np.percentile(v, [1, 99]))[0]), 0.1) for v in (lw, lh)]
    return span[0] * span[1]


def _score_centres(bins, kinds, scores) -> np.ndarray:
    """A representative score per bin: the geometric mean of the scores in it (the bin's
    midpoint where it holds none)."""
    nb = len(SCORE_BINS) - 1
    out = np.empty(nb)
    for k in range(nb):
        inside = scores[(bins == k) & (kinds >= 0)]
        lo, hi = SCORE_BINS[k], SCORE_BINS[k + 1]
        out[k] = (float(np.exp(np.mean(np.log(np.maximum(inside, 1e-6))))) if len(inside)
                  else max((lo + hi) / 2, 1e-3))
    return out


def _fit_clutter(fp, hits, frames, block_frames, area, centres, weights):
    """clutter_rate and clutter_score_power fitted over score bins (module docstring), with
    percentile intervals over the block bootstrap."""
    c, p = poisson_power_fit(fp.sum(axis=0), hits.sum(axis=0), frames, area, centres)
    bc, bp = poisson_power_fit(weights @ fp, weights @ hits, weights @ block_frames, area,
                               centres)
    blocks = len(block_frames)
    return (_percentile(float(c[0]), bc, clusters=blocks, bounds=(0.0, math.inf)),
            _percentile(float(p[0]), bp, clusters=blocks, bounds=(0.0, math.inf)))


def poisson_power_fit(false_counts, hit_counts, frames, area, centres, iterations: int = 50):
    """Maximum-likelihood c and p >= 0 of false counts n_k ~ Poisson(e_k c s_k^-p) over score
    bins k, with exposure e_k = frames * area * (hits in k / all hits), for each row of the
    (draws, bins) counts at once. Bins without hits are left out (the tracker's clutter term
    is a ratio to the hits' score density, undefined there)."""
    n = np.atleast_2d(np.asarray(false_counts, dtype=float))
    h = np.atleast_2d(np.asarray(hit_counts, dtype=float))
    frames = np.atleast_1d(np.asarray(frames, dtype=float))
    used = h > 0
    share = np.where(used, h / np.maximum(h.sum(axis=1, keepdims=True), 1e-300), 0.0)
    exposure = frames[:, None] * area * share
    x = np.broadcast_to(-np.log(np.maximum(centres, 1e-12)), n.shape)
    n = np.where(used, n, 0.0)
    total_n, total_e = n.sum(axis=1), exposure.sum(axis=1)
    flat = np.divide(total_n, total_e, out=np.full(len(n), np.nan), where=total_e > 0)
    a = np.log(np.maximum(flat, 1e-300))
    p = np.zeros(len(n))
    for _ in range(iterations):
        mu = exposure * np.exp(np.clip(a[:, None] + p[:, None] * x, -700, 700))
        g0, g1 = (n - mu).sum(axis=1), ((n - mu) * x).sum(axis=1)
        h00, h01, h11 = mu.sum(axis=1), (mu * x).sum(axis=1), (mu * x * x).sum(axis=1)
        det = h00 * h11 - h01 * h01
        ok = det > 1e-12 * np.maximum(h00 * h11, 1e-300)
        da = np.where(ok, (h11 * g0 - h01 * g1) / np.where(ok, det, 1.0), 0.0)
        dp = np.where(ok, (h00 * g1 - h01 * g0) / np.where(ok, det, 1.0), 0.0)
        step = np.minimum(1.0, 5.0 / np.maximum(np.abs(dp), 1e-300))  # damped in p
        a, p = a + step * da, p + step * dp
        if np.all(np.abs(step * dp) < 1e-10):
            break
    # p < 0 would say clutter rises with the score; the tracker's term cannot: flat
    flat_fit = (p < 0) | ~np.isfinite(p)
    c = np.where(flat_fit, flat, np.exp(a))
    p = np.where(flat_fit, 0.0, p)
    c = np.where(total_n > 0, c, 0.0)
    p = np.where(total_n > 0, p, np.nan)
    return c, p


def _edge_noise(cluster, err, height, size, valid, n_clusters, weights) -> dict:
    """Per edge: bias, std (in true heights and in the axis' own size), robust std; and the
    pooled std over all four edges, in true heights."""
    rel_h = err / height[:, None]
    rel_own = err / size
    bias, std, std_own, robust = {}, {}, {}, {}

    def moments(values, mask):
        k = np.zeros((n_clusters, 3))
        for j, v in enumerate((np.ones_like(values), values, values * values)):
            np.add.at(k[:, j], cluster[mask], v[mask])
        return k

    def mean_std(sums):
        sums = np.atleast_2d(sums)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = sums[:, 1] / sums[:, 0]
            var = sums[:, 2] / sums[:, 0] - mean * mean
            sd = np.sqrt(np.maximum(var, 0.0) * sums[:, 0] / np.maximum(sums[:, 0] - 1, 1))
        return mean, sd

    pooled = np.zeros((n_clusters, 3))
    for j, name in enumerate(EDGES):
        mask = valid[:, j]
        n = int(mask.sum())
        if n < 2:
            nan = Estimate(float("nan"), float("nan"), float("nan"), n)
            bias[name] = std[name] = std_own[name] = nan
            robust[name] = float("nan")
            continue
        k = moments(rel_h[:, j], mask)
        m, s = mean_std(k.sum(axis=0))
        bm, bs = mean_std(weights @ k)
        used = int((k[:, 0] > 0).sum())
        bias[name] = _percentile(float(m[0]), bm, n, used)
        std[name] = _percentile(float(s[0]), bs, n, used, (0.0, math.inf))
        ko = moments(rel_own[:, j], mask)
        _, so = mean_std(ko.sum(axis=0))
        _, bso = mean_std(weights @ ko)
        std_own[name] = _percentile(float(so[0]), bso, n, used, (0.0, math.inf))
        v = rel_h[mask, j]
        robust[name] = float(1.4826 * np.median(np.abs(v - np.median(v))))
        # pooled: each edge's deviation from its own bias (the tracker has no bias term, but
        # a bias is a fault of the boxes' definition, reported apart)
        centred = rel_h[:, j] - m[0]
        pooled += moments(centred, mask)
    n_all = int(pooled[:, 0].sum())
    if n_all < 2:
        noise = Estimate(float("nan"), float("nan"), float("nan"), n_all)
    else:
        _, s = mean_std(pooled.sum(axis=0))
        _, bs = mean_std(weights @ pooled)
        noise = _percentile(float(s[0]), bs, n_all, int((pooled[:, 0] > 0).sum()),
                            (0.0, math.inf))
    return {"edge_bias": bias, "edge_std": std, "edge_std_own": std_own, "edge_robust": robust,
            "edge_noise": noise}


# ----------------------------------------------------------------------------------------------
# Text


def _range(lo: float, hi: float, unit: str = "") -> str:
    if math.isinf(hi):
        return f">= {lo:g}{unit}"
    return f"{lo:g}-{hi:g}{unit}"


def report_lines(cal: Calibration) -> list[str]:
    """The measurements as text, one finding a line, 95 % intervals in brackets."""
    lines = [f"sequences: {', '.join(cal.sequences)}; {cal.frames} frames, {cal.targets} "
             f"pedestrian boxes, {cal.detections} detections: {cal.hits} hits, {cal.false} "
             f"false, {cal.set_aside} on distractors (set aside); match IoU >= {MATCH_IOU}",
             "",
             f"detection probability, all pedestrians: {cal.detection_overall.text()}",
             f"  visible (visibility >= {VISIBLE}): {cal.detectability.text()}",
             f"  tracked (detected within the last {cal.horizon:g} s): "
             f"{cal.detection_tracked.text()}",
             f"  memory per frame P(hit|hit) - P(hit|miss), visible and tracked: "
             f"{cal.memory_visible.text()}; half-second ratio "
             f"{cal.ratio_visible.text()}",
             f"  memory per frame, tracked: {cal.memory_tracked.text()}; half-second ratio "
             f"{cal.ratio_tracked.text()}",
             "  by visibility:"]
    for lo, hi, e in cal.by_visibility:
        lines.append(f"    {_range(lo, hi):<12}{e.text():<26}n {e.n:>7}  effective "
                     f"{e.effective:>8.0f}")
    lines.append("  by box height (px):")
    for lo, hi, e in cal.by_height:
        lines.append(f"    {_range(lo, hi):<12}{e.text():<26}n {e.n:>7}  effective "
                     f"{e.effective:>8.0f}")
    lines.append("  by visibility (rows) and height (columns), value (n):")
    lines.append("    " + " " * 12 + "".join(f"{_range(lo, hi):>16}" for lo, hi in
                                              zip(HEIGHT_BINS[:-1], HEIGHT_BINS[1:],
                                                  strict=True)))
    for (lo, hi, _), row in zip(cal.by_visibility, cal.joint, strict=True):
        cells = "".join(f"{'-' if e.n == 0 else f'{e.value:.3f} ({e.n})':>16}" for e in row)
        lines.append(f"    {_range(lo, hi):<12}{cells}")
    lines += ["", f"false detections per frame: {cal.false_per_frame.text()}",
              "  by score (false per frame; hits in the bin):"]
    for lo, hi, e, hits in cal.by_score:
        lines.append(f"    {_range(lo, hi):<12}{e.text(4):<30}n {e.n:>6}  hits {hits:>7}")
    lines += [f"  tracker's clutter term: clutter_rate {cal.clutter_rate.text(4)} and "
              f"clutter_score_power {cal.clutter_score_power.text(2)}",
              f"  (false boxes spread over {cal.size_area:.2f} in log width x log height: the "
              f"1st-99th percentile ranges of the detections)",
              "", f"box-edge noise, matched people with visibility >= {EDGE_VISIBILITY}, edges "
              f"off the border: std in true box heights (own axis size), bias, robust std"]
    for name in EDGES:
        lines.append(f"    {name:<8}std {cal.edge_std[name].text():<24}"
                     f"({cal.edge_std_own[name].text()})  bias {cal.edge_bias[name].text():<26}"
                     f"robust {cal.edge_robust[name]:.3f}   n {cal.edge_std[name].n}")
    lines.append(f"  pooled about each edge's bias: edge_noise {cal.edge_noise.text(4)}")
    lines += [f"note: {note}" for note in cal.notes]
    return lines


def _number(value: float) -> str:
    return f"{value:.4g}" if value != 0 else "0.0"


def to_toml(cal: Calibration, occlusion: bool = True, command: str = "") -> str:
    """A TrackerConfig file (loads with `occtrack track --config`): the settings this
    calibration sets, each with its interval in a comment, and the whole report as comments."""
    settings = cal.settings(occlusion)
    source = {"detectability": cal.detectability if occlusion else cal.detection_tracked,
              "detectability_ratio": cal.ratio_tracked,
              "clutter_rate": cal.clutter_rate,
              "clutter_score_power": cal.clutter_score_power, "edge_noise": cal.edge_noise}
    meaning = {
        "detectability": ("P_D of visible people (visibility >= 0.75), for occlusion models"
                          if occlusion else f"P_D of tracked pedestrians (detected within "
                          f"the last {cal.horizon:g} s), for occlusion = none"),
        "detectability_ratio": "half-second ratio of the detectability chain, tracked people",
        "clutter_rate": "kappa W H w h at score 1: false boxes per frame per unit of log w x "
                        "log h, over the hits' score density",
        "clutter_score_power": "clutter term ~ score ** -power",
        "edge_noise": "std of a box edge, in box heights",
    }
    lines = ["# occtrack detector calibration (occtrack calibrate)"]
    if command:
        lines.append(f"# {command}")
    lines += ["# Only TrackerConfig fields below; load with: occtrack track --config FILE.",
              "# Each setting: its 95 % interval and meaning in the comment above it.", ""]
    for name, value in settings.items():
        e = source[name]
        lines.append(f"# {meaning[name]}; estimate {_number(e.value)}, 95 % interval "
                     f"[{_number(e.low)}, {_number(e.high)}]")
        if name == "detectability" and value != e.value:
            lines.append("# (clipped to [0.01, 0.999]: a certain detection leaves no room for "
                         "a miss)")
        lines.append(f"{name} = {_number(value)}")
        lines.append("")
    left_out = [n for n in source if n not in settings]
    if left_out:
        lines.append(f"# not set (no estimate in these data; the defaults hold): "
                     f"{', '.join(left_out)}")
        lines.append("")
    lines.append("# The measurements:")
    lines += [f"#   {line}" if line else "#" for line in report_lines(cal)]
    return "\n".join(lines) + "\n"
