"""The leg-tracker benchmark's scoring (occtrack.metrics.leg_benchmark), its readers and
`occtrack eval-scans` (issue 41, item 5): hand-built cases with exact counts, a brute-force
scorer on small random cases, the readers' errors, the command end to end and the real
recording's ground truth scored against itself."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.io.scans import read_people, read_tracks, write_tracks
from occtrack.metrics.leg_benchmark import LegScores, score, summary, table

TRACKS_HEADER = "time,id,x,y,vx,vy,existence,confidence,occluded"


def run(truth, tracks, **kw) -> LegScores:
    """Score lists of (time, id, x, y) rows."""
    g = np.array(truth, float).reshape(-1, 4)
    e = np.array(tracks, float).reshape(-1, 4)
    return score(g[:, 0], g[:, 1].astype(int), g[:, 2:], e[:, 0], e[:, 1].astype(int),
                 e[:, 2:], **kw)


def counts(s: LegScores) -> tuple[int, int, int, int]:
    return s.valid, s.id_switches, s.misses, s.false_positives


# -- hand-built cases ----------------------------------------------------------------------------

def test_a_perfect_track_has_no_switch_no_miss_and_its_offset_as_motp():
    scans = np.arange(10) / 10
    truth = [(t + 0.05, 7, 0.3 * t, 1.0) for t in scans]
    tracks = [(t, 3, 0.3 * t + 0.1, 1.0) for t in scans]
    s = run(truth, tracks)
    assert counts(s) == (10, 0, 0, 0)
    assert (s.scans, s.all_scans, s.truth, s.early, s.duplicates) == (10, 10, 10, 0, 0)
    assert s.motp == pytest.approx(0.1, abs=1e-12)
    assert s.mota == s.mota_without_fp == 1.0
    assert s.tracks_per_scan == 1.0 and s.false_tracks_per_scan == 0.0


def test_a_new_track_taking_over_a_person_is_exactly_one_switch():
    truth = [(t + 0.01, 1, 0.0, 0.0) for t in range(8)]
    tracks = [(t, 10 if t < 4 else 11, 0.05, 0.0) for t in range(8)]
    s = run(truth, tracks)
    assert counts(s) == (7, 1, 0, 0)
    assert s.motp == pytest.approx(0.05)  # switches are matches: in MOTP too
    assert s.mota == pytest.approx(1 - 1 / 8)


def test_two_tracks_exchanging_people_are_two_switches():
    truth = [(t + 0.01, p, 0.0, 2.0 * p) for t in range(6) for p in (1, 2)]
    tracks = [(t, i, 0.0, 2.0 * (p if t < 3 else 3 - p)) for t in range(6)
              for i, p in ((10, 1), (20, 2))]
    s = run(truth, tracks)
    assert counts(s) == (10, 2, 0, 0)


def test_a_track_moving_to_a_person_never_matched_is_a_switch():
    """The benchmark's track-side rule: track 10 leaves person 1 for person 2, whom no track
    had matched (CLEAR MOT's person-side rule alone would see no switch)."""
    truth = [(t + 0.01, 1, 0.0, 0.0) for t in range(3)] + [(3.01, 2, 0.0, 5.0)]
    tracks = [(t, 10, 0.0, 0.0) for t in range(3)] + [(3, 10, 0.0, 5.0)]
    assert counts(run(truth, tracks)) == (3, 1, 0, 0)


def test_each_handover_through_an_absence_is_a_switch():
    """A match is remembered while its track is away; a person's new track is a switch, and
    so is the old one coming back."""
    truth = [(t + 0.01, 1, 0.0, 0.0) for t in range(3)]
    tracks = [(0, 1, 0.0, 0.0), (1, 2, 0.1, 0.0), (2, 1, 0.0, 0.0)]
    assert counts(run(truth, tracks)) == (1, 2, 0, 0)


def test_last_scans_match_is_kept_over_a_closer_newcomer():
    truth = [(0.01, 1, 0.0, 0.0), (1.01, 1, 0.0, 0.0)]
    tracks = [(0, 1, 0.1, 0.0), (1, 1, 0.5, 0.0), (1, 2, 0.0, 0.0)]
    s = run(truth, tracks)
    assert counts(s) == (2, 0, 0, 1)
    assert s.motp == pytest.approx(0.3)
    assert s.false_tracks_per_scan == 0.5 and s.tracks_per_scan == 1.5


@pytest.mark.parametrize("gap", [0.75, 0.76])
def test_a_track_at_or_beyond_the_threshold_is_a_miss_and_a_false_positive(gap):
    s = run([(0.0, 1, 0.0, 0.0)], [(0.0, 5, gap, 0.0)])
    assert counts(s) == (0, 0, 1, 1)
    assert math.isnan(s.motp) and s.mota == -1.0 and s.mota_without_fp == 0.0
    assert counts(run([(0.0, 1, 0.0, 0.0)], [(0.0, 5, gap, 0.0)], threshold=0.8)) == (
        1, 0, 0, 0)


def test_a_position_is_scored_against_the_last_scan_at_or_before_it():
    tracks = [(0.0, 1, 0.0, 0.0), (0.1, 1, 1.0, 0.0), (0.2, 1, 2.0, 0.0)]
    # just before scan 0.1: scan 0.0; at 0.1 exactly: scan 0.1; after the last: the last
    truth = [(0.0999, 4, 0.0, 0.0), (0.1, 4, 1.0, 0.0), (7.0, 4, 2.0, 0.0)]
    s = run(truth, tracks)
    assert counts(s) == (3, 0, 0, 0) and s.motp == 0.0
    s = run([(0.0999, 4, 1.0, 0.0)], tracks)  # where scan 0.1 has it: too early for that
    assert counts(s) == (0, 0, 1, 1)


def test_a_position_before_every_scan_is_a_miss():
    s = run([(-0.01, 4, 0.0, 0.0), (0.05, 4, 0.0, 0.0)], [(0.0, 1, 0.0, 0.0)])
    assert counts(s) == (1, 0, 1, 0)
    assert (s.early, s.truth, s.scans) == (1, 2, 1)
    s = run([(0.0, 4, 0.0, 0.0)], [])
    assert (s.early, s.misses, s.all_scans, s.scans) == (1, 1, 0, 0)
    assert math.isnan(s.tracks_per_scan) and math.isnan(s.false_tracks_per_scan)


def test_scan_times_make_a_scan_with_no_reported_object_count():
    tracks = [(0.0, 1, 0.0, 0.0), (0.2, 1, 0.0, 0.0)]
    truth = [(0.15, 4, 0.0, 0.0)]
    assert counts(run(truth, tracks)) == (1, 0, 0, 0)  # scored against scan 0.0
    s = run(truth, tracks, scan_time=[0.0, 0.1, 0.2 + 1e-9])
    assert counts(s) == (0, 0, 1, 0) and s.all_scans == 3 and s.tracks_per_scan == 2 / 3


def test_the_assignment_minimises_the_total_distance_not_greedy():
    """Greedy takes the closest pair (track 1, person B: 0.4 m) and leaves track 2 1.6 m from
    person A; least total distance pairs both."""
    truth = [(0.0, 1, 0.0, 0.0), (0.0, 2, 1.0, 0.0)]
    tracks = [(0.0, 1, 0.6, 0.0), (0.0, 2, 1.6, 0.0)]
    s = run(truth, tracks)
    assert counts(s) == (2, 0, 0, 0) and s.motp == pytest.approx(0.6)


def test_the_threshold_gates_after_the_assignment():
    """The benchmark's rule: track 1 on person B, track 2 0.7 m from B and 1 m from A; pairing
    (1, A) and (2, B) would match both (0.7 m each, 1.4 in all), but (1, B) and (2, A) costs
    1.0 in all, so it is chosen and (2, A) dropped."""
    x = 1.0 / 1.4
    y = math.sqrt(1.0 - x**2)
    truth = [(0.0, 1, 0.0, 0.0), (0.0, 2, 0.7, 0.0)]
    tracks = [(0.0, 1, 0.7, 0.0), (0.0, 2, x, y)]
    assert math.hypot(x - 0.7, y) == pytest.approx(0.7) and math.hypot(x, y) == pytest.approx(1)
    assert counts(run(truth, tracks)) == (1, 0, 1, 1)


def test_of_two_positions_of_a_person_on_one_scan_the_last_is_kept():
    truth = [(0.02, 1, 0.0, 0.0), (0.05, 1, 3.0, 0.0), (0.03, 2, 9.0, 9.0)]
    s = run(truth, [(0.0, 8, 0.0, 0.0)])
    assert (s.duplicates, s.truth) == (1, 2)
    assert counts(s) == (0, 0, 2, 1)
    # the same time: the later row of the file
    s = run([(0.02, 1, 3.0, 0.0), (0.02, 1, 0.0, 0.0)], [(0.0, 8, 0.0, 0.0)])
    assert counts(s) == (1, 0, 0, 0) and s.duplicates == 1


def test_rows_in_any_order_give_the_same_scores():
    rng = np.random.default_rng(3)
    for _ in range(50):
        truth, tracks = random_case(rng)
        g, e = np.array(truth).reshape(-1, 4), np.array(tracks).reshape(-1, 4)
        mixed = run(g[rng.permutation(len(g))], e[rng.permutation(len(e))]).as_dict()
        expected = run(truth, tracks).as_dict()
        assert mixed.pop("motp") == pytest.approx(expected.pop("motp"), abs=1e-12)
        assert mixed == expected


def test_bad_arrays_are_refused():
    with pytest.raises(ValueError, match="track id 3 appears twice in the scan at time 0.5"):
        run([(0.5, 1, 0.0, 0.0)], [(0.5, 3, 0.0, 0.0), (0.5, 3, 1.0, 0.0)])
    with pytest.raises(ValueError, match="truth_xy holds a NaN"):
        run([(0.5, 1, np.nan, 0.0)], [])
    with pytest.raises(ValueError, match="threshold"):
        run([], [], threshold=0.0)
    with pytest.raises(ValueError, match="one entry a position"):
        score([0.0, 1.0], [1], [[0, 0]], [], [], [])


def test_no_truth_gives_undefined_ratios_and_json_null():
    s = run([], [(0.0, 1, 0.0, 0.0)])
    assert (s.truth, s.scans, s.false_positives, s.false_positives_all_scans) == (0, 0, 0, 1)
    assert math.isnan(s.mota) and math.isnan(s.motp)
    d = s.as_dict()
    assert d["mota"] is None and d["motp"] is None and d["track_rows"] == 1
    json.dumps(d, allow_nan=False)
    assert "-" in table(s).splitlines()[1].split()


def test_the_table_has_a_row_a_result_and_the_summary_the_counts():
    perfect = run([(0.0, 1, 0.0, 0.0)], [(0.0, 1, 0.1, 0.0)])
    missed = run([(0.0, 1, 0.0, 0.0), (-1.0, 1, 0.0, 0.0)], [(0.0, 1, 2.0, 0.0)])
    lines = table({"perfect": perfect, "missed": missed}).splitlines()
    assert lines[0].split() == ["valid", "ID", "sw", "misses", "FP", "MOTP", "m", "MOTA",
                                "MOTA-FP", "tracks/scan", "FP/scan"]
    assert lines[1].split() == ["perfect", "1", "0", "0", "0", "0.100", "100.0%", "100.0%",
                                "1.00", "0.00"]
    assert lines[2].split() == ["missed", "0", "0", "2", "1", "-", "-50.0%", "0.0%", "1.00",
                                "1.00"]
    assert "0.75 m" in lines[3]
    assert summary(missed).startswith("2 annotated positions (1 before the first scan) on 1 "
                                      "of 1 scans: 0 valid, 0 ID switches, 2 misses")


# -- against a brute-force scorer ----------------------------------------------------------------

def random_case(rng):
    """A few scans (some with no reported object), positions in a 1.5 m square so that
    distances fall on both sides of 0.75 m, ids from small pools (so switches happen), truth
    rows at any time (some before the first scan, some repeated on a scan)."""
    n_scans = int(rng.integers(1, 7))
    tracks = []
    for s in range(n_scans):
        for i in rng.choice(5, size=int(rng.integers(0, 4)), replace=False):
            tracks.append((float(s), int(i), *rng.uniform(0, 1.5, 2)))
    truth = []
    for _ in range(int(rng.integers(0, 12))):
        truth.append((float(rng.uniform(-0.5, n_scans)), int(rng.integers(0, 4)),
                      *rng.uniform(0, 1.5, 2)))
    return truth, tracks


def brute_force(truth, tracks, threshold=0.75):
    """The benchmark's rules, literally, with every assignment of each scan enumerated."""
    scan_times = sorted({t for t, *_ in tracks})
    people: dict[float, dict[int, tuple]] = {}
    early = duplicates = 0
    for t, i, x, y in truth:  # file order
        before = [s for s in scan_times if s <= t]
        if not before:
            early += 1
            continue
        on = people.setdefault(before[-1], {})
        if i in on:
            duplicates += 1
            if on[i][0] > t:
                continue
        on[i] = (t, x, y)
    memory: dict[int, int] = {}
    valid = switches = misses = fps = matched = 0
    dist_sum = 0.0
    for s in sorted(people):
        gt = {i: (x, y) for i, (_, x, y) in people[s].items()}
        est = {i: (x, y) for t, i, x, y in tracks if t == s}

        def dist(e, g, est=est, gt=gt):
            return math.dist(est[e], gt[g])

        match = {e: g for e, g in memory.items()
                 if e in est and g in gt and dist(e, g) < threshold}
        free_e = [e for e in est if e not in match]
        free_g = [g for g in gt if g not in match.values()]
        best, best_cost = [], math.inf
        if len(free_e) <= len(free_g):
            options = ([*zip(free_e, p, strict=True)]
                       for p in itertools.permutations(free_g, len(free_e)))
        else:
            options = ([*zip(p, free_g, strict=True)]
                       for p in itertools.permutations(free_e, len(free_g)))
        for pairs in options:
            cost = sum(dist(e, g) for e, g in pairs)
            if cost < best_cost:
                best, best_cost = pairs, cost
        match.update((e, g) for e, g in best if dist(e, g) < threshold)
        for e, g in match.items():
            if e in memory:
                switch = memory[e] != g
            else:
                switch = g in memory.values()
            switches += switch
            valid += not switch
            dist_sum += dist(e, g)
        matched += len(match)
        misses += len(gt) - len(match)
        fps += len(est) - len(match)
        memory = {e: g for e, g in memory.items() if e not in match and g not in match.values()}
        memory.update(match)
    truth_count = early + sum(len(p) for p in people.values())
    return dict(valid=valid, id_switches=switches, misses=misses + early,
                false_positives=fps, early=early, duplicates=duplicates, truth=truth_count,
                scans=len(people), false_positives_all_scans=len(tracks) - matched,
                motp=dist_sum / matched if matched else math.nan)


def test_the_scores_are_the_brute_force_scorers_on_random_cases():
    rng = np.random.default_rng(20150526)
    seen = dict.fromkeys(("valid", "id_switches", "misses", "false_positives", "early",
                          "duplicates"), 0)
    for _ in range(400):
        truth, tracks = random_case(rng)
        got = run(truth, tracks)
        expected = brute_force(truth, tracks)
        motp = expected.pop("motp")
        assert {k: getattr(got, k) for k in expected} == expected, (truth, tracks)
        assert got.motp == pytest.approx(motp, nan_ok=True, abs=1e-12)
        assert got.valid + got.id_switches + got.misses == got.truth
        for k in seen:
            seen[k] += expected[k]
    assert all(v > 20 for v in seen.values()), seen  # every rule was exercised


# -- the readers ---------------------------------------------------------------------------------

def test_read_people_reads_the_benchmarks_file(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("bag_time,id,x,y,z\n1400160093.128572,2,1.184665,0.209292,-0.000206\n"
                    "1400160093.228771,2,1.126581,0.295069,0.255722\n")
    people = read_people(path)
    assert len(people) == 2 and people.id.tolist() == [2, 2]
    assert people.time[0] == 1400160093.128572 and people.position.shape == (2, 2)
    assert people.position[1].tolist() == [1.126581, 0.295069] and people.z[0] == -0.000206


@pytest.mark.parametrize(("text", "problem"), [
    ("bag_time,id,x,y,z\n1.0,2,0.5,0.5,0\n1.1,2,0.5,0.5\n",
     ":3: expected 5 columns (bag_time, id, x, y, z), found 4: '1.1,2,0.5,0.5'"),
    ("bag_time,id,x,y,z\n1.0,2,0.5,0.5,0\n\n1.1,2,nan,0.5,0\n",
     ":4: x is nan; it must be a finite number"),
    ("bag_time,id,x,y,z\n1.0,2,0.5,0.5,0\n0.9,2,0.5,0.5,0\n",
     ":3: bag_time 0.9 is earlier than the row before (1.0): rows must be in time order"),
    ("bag_time,id,x,y,z\n1.0,two,0.5,0.5,0\n", ":2: id is not a number: 'two'"),
    ("bag_time,id,x,y,z\n1.0,2.5,0.5,0.5,0\n", ":2: id 2.5 is not a whole number >= 0"),
])
def test_read_people_names_the_file_and_line_of_a_bad_row(tmp_path, text, problem):
    path = tmp_path / "gt.csv"
    path.write_text(text)
    with pytest.raises(OcctrackError) as err:
        read_people(path)
    assert str(err.value) == f"{path}{problem}"


def test_read_tracks_reads_back_what_write_tracks_wrote(tmp_path):
    path = tmp_path / "tracks.csv"
    path.write_text(f"{TRACKS_HEADER}\n0.100000,3,1.0000,2.0000,0.1000,0.0000,0.900000,"
                    f"0.800000,0\n0.100000,5,-1.0000,2.5000,0.0000,-0.2000,0.500000,0.100000,"
                    f"1\n0.200000,3,1.0100,2.0000,0.1000,0.0000,0.910000,0.810000,0\n")
    tracks = read_tracks(path)
    assert len(tracks) == 3 and tracks.id.tolist() == [3, 5, 3]
    assert tracks.position[1].tolist() == [-1.0, 2.5] and tracks.occluded.tolist() == [
        False, True, False]
    again = tmp_path / "again.csv"
    write_tracks(again, tracks)
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.parametrize(("rows", "problem"), [
    ("0.1,3,1,2,0,0,0.9,0.8,0\n0.1,3,1,2,0,0,0.9,0.8\n",
     ":3: expected 9 columns (time, id, x, y, vx, vy, existence, confidence, occluded), "
     "found 8: '0.1,3,1,2,0,0,0.9,0.8'"),
    ("0.1,3,1,2,0,0,0.9,0.8,0\n0.2,4,nan,2,0,0,0.9,0.8,0\n",
     ":3: x is nan; it must be a finite number"),
    ("0.2,3,1,2,0,0,0.9,0.8,0\n0.1,4,1,2,0,0,0.9,0.8,0\n",
     ":3: time 0.1 is earlier than the row before (0.2): rows must be in time order"),
    ("0.1,3,1,2,0,0,0.9,0.8,0\n0.1,4,1,2,0,0,0.9,0.8,0\n0.1,3,5,2,0,0,0.9,0.8,0\n",
     ":4: id 3 appears twice at time 0.1: a tracks file reports an object once a scan"),
    ("0.1,3,1,2,0,0,1.5,0.8,0\n", ":2: existence 1.5 is not in [0, 1]"),
    ("0.1,3,1,2,0,0,0.9,0.8,2\n", ":2: occluded must be 0 or 1"),
])
def test_read_tracks_names_the_file_and_line_of_a_bad_row(tmp_path, rows, problem):
    path = tmp_path / "tracks.csv"
    path.write_text(f"{TRACKS_HEADER}\n{rows}")
    with pytest.raises(OcctrackError) as err:
        read_tracks(path)
    assert str(err.value) == f"{path}{problem}"


# -- occtrack eval-scans -------------------------------------------------------------------------

@pytest.fixture
def files(tmp_path):
    """A person walking for 20 scans, tracked by track 3 then (from scan 12) track 4, with a
    false track on every scan and no report at all on scan 15."""
    gt = tmp_path / "gt.csv"
    gt.write_text("bag_time,id,x,y,z\n" + "".join(
        f"{100 + s / 10 + 0.03:.6f},2,{0.1 * s:.6f},1.000000,0.0\n" for s in range(20)))
    rows = []
    for s in range(20):
        if s == 15:
            continue
        t = f"{100 + s / 10:.6f}"
        rows.append(f"{t},{3 if s < 12 else 4},{0.1 * s + 0.05:.4f},1.0000,0,0,0.9,0.9,0\n")
        rows.append(f"{t},9,5.0000,5.0000,0,0,0.5,0.5,0\n")
    tracks = tmp_path / "tracks.csv"
    tracks.write_text(f"{TRACKS_HEADER}\n" + "".join(rows))
    return gt, tracks


def test_eval_scans_prints_the_table_and_a_summary(files, capsys):
    gt, tracks = files
    assert main(["eval-scans", str(gt), str(tracks)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert lines[0].split()[:4] == ["valid", "ID", "sw", "misses"]
    # scan 15, with no row, is no scan: its position lands on scan 14 and, later, displaces
    # scan 14's own; it is 0.05 m from scan 14's track
    assert lines[1].split()[:6] == [str(tracks), "18", "1", "0", "19", "0.050"]
    assert lines[-1].startswith("19 annotated positions on 19 of 19 scans, 1 repeated "
                                "positions dropped: 18 valid, 1 ID switches, 0 misses")
    assert "1 gaps longer than 1.5 scan periods" in err and "--scans" in err


def test_eval_scans_with_the_scan_file_counts_the_empty_scan(files, tmp_path, capsys):
    gt, tracks = files
    scans = tmp_path / "scans.csv"
    scans.write_text("time,angle,range\n" + "".join(
        f"{100 + s / 10:.6f},0.0,inf\n" for s in range(20)))
    out = tmp_path / "scores.json"
    assert main(["eval-scans", str(gt), str(tracks), "--scans", str(scans), "--json",
                 str(out), "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    report = json.loads(out.read_text())
    assert report["gt"] == str(gt) and report["tracks"] == str(tracks)
    assert (report["valid"], report["id_switches"], report["misses"]) == (18, 1, 1)
    assert (report["all_scans"], report["scans"], report["false_positives"]) == (20, 20, 19)
    assert report["mota_without_fp"] == pytest.approx(0.9)
    assert report["tracks_per_scan"] == pytest.approx(38 / 20)

    scans.write_text("time,angle,range\n100.000000,0.0,inf\n")  # not the tracks' scan file
    assert main(["eval-scans", str(gt), str(tracks), "--scans", str(scans)]) == 1
    assert "is no scan's time in" in capsys.readouterr().err


def test_eval_scans_json_is_written_whole_and_never_over_a_file_without_force(files, tmp_path,
                                                                              capsys):
    gt, tracks = files
    out = tmp_path / "scores.json"
    out.write_text("keep me\n")
    assert main(["eval-scans", str(gt), str(tracks), "--json", str(out)]) == 1
    err = capsys.readouterr().err
    assert err == f"occtrack eval-scans: error: {out}: exists already; pass --force to " \
                  f"overwrite it\n"
    assert out.read_text() == "keep me\n"
    assert main(["eval-scans", str(gt), str(tracks), "--json", str(out), "--force",
                 "--threshold", "0.01"]) == 0
    report = json.loads(out.read_text())
    assert report["threshold"] == 0.01 and report["valid"] == 0 and report["motp"] is None
    assert main(["eval-scans", str(gt), str(tracks), "--json", str(gt)]) == 1
    assert "is also an input" in capsys.readouterr().err


def test_eval_scans_json_dash_prints_only_json(files, capsys):
    gt, tracks = files
    assert main(["eval-scans", str(gt), str(tracks), "--json", "-"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["valid"] == 18
    assert "18 valid" in err


def test_eval_scans_bad_input_is_one_line_naming_file_and_line(files, capsys):
    gt, tracks = files
    gt.write_text("bag_time,id,x,y,z\n1.0,2,0.5,0.5,0\n1.1,2,0.5,nan,0\n")
    assert main(["eval-scans", str(gt), str(tracks)]) == 1
    assert capsys.readouterr().err == (f"occtrack eval-scans: error: {gt}:3: y is nan; it "
                                       f"must be a finite number\n")
    with pytest.raises(SystemExit) as stop:
        main(["eval-scans", str(gt), str(tracks), "--threshold", "-1"])
    assert stop.value.code == 2
    assert "must be a positive number of metres" in capsys.readouterr().err


def test_eval_scans_warns_of_positions_before_the_first_scan(tmp_path, capsys):
    gt = tmp_path / "gt.csv"
    gt.write_text("bag_time,id,x,y,z\n0.5,1,0,0,0\n1.5,1,0,0,0\n")
    tracks = tmp_path / "tracks.csv"
    tracks.write_text(f"{TRACKS_HEADER}\n1.0,7,0,0,0,0,1,1,0\n")
    assert main(["eval-scans", str(gt), str(tracks)]) == 0
    out, err = capsys.readouterr()
    assert "1 positions come before the first scan (1.000000) and count as misses" in err
    assert "(1 before the first scan)" in out


def test_eval_scans_help_names_its_options(capsys):
    with pytest.raises(SystemExit):
        main(["eval-scans", "--help"])
    text = capsys.readouterr().out
    for option in ("--threshold", "--json", "--force", "--quiet", "--scans", "GT", "TRACKS"):
        assert option in text


# -- the real recording --------------------------------------------------------------------------

def test_the_recordings_ground_truth_scored_against_itself_is_perfect(laser_recording,
                                                                      tmp_path, capsys):
    """Each annotated position as a track 1 us earlier: each lands on its own "scan"."""
    recording = laser_recording / "ground_truth_people_tracks.csv"
    people = read_people(recording)
    assert len(people) == 6179
    tracks = tmp_path / "tracks.csv"
    tracks.write_text(f"{TRACKS_HEADER}\n" + "".join(
        f"{t - 1e-6:.6f},{i},{x:.6f},{y:.6f},0,0,1,1,0\n"
        for t, i, (x, y) in zip(people.time, people.id, people.position, strict=True)))
    out = tmp_path / "scores.json"
    assert main(["eval-scans", str(recording), str(tracks), "--json", str(out), "--quiet"]) == 0
    capsys.readouterr()
    report = json.loads(out.read_text())
    assert (report["valid"], report["id_switches"], report["misses"]) == (6179, 0, 0)
    assert (report["truth"], report["scans"], report["false_positives"]) == (6179, 6179, 0)
    assert report["motp"] == 0.0 and report["mota"] == 1.0
    s = score(people.time, people.id, people.position, people.time - 1e-6, people.id,
              people.position)
    assert counts(s) == (6179, 0, 0, 0) and s.motp == 0.0
