"""The lidar scene (`occtrack simulate lidar`): its ray casting and occlusion flags against an
independent per-beam, per-object check written with plain floats, its sensor model, its
reproducibility byte for byte, and its files read back (and refused when malformed)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.config.lidar import LidarSceneConfig
from occtrack.errors import OcctrackError
from occtrack.io.scans import read_poses, read_scans, read_truth
from occtrack.scenarios.lidar import full_occlusions, simulate_beams, simulate_scene
from occtrack.scenarios.lidar.files import write_scene
from occtrack.scenarios.lidar.raycast import Shapes, beam_counts, cast
from occtrack.scenarios.lidar.scene import beam_angles, measure

SMALL = LidarSceneConfig(beams=90, people=6, vehicles=2)


# -- an independent ray caster: one beam, one object, plain floats --------------------------------

def _disc_range(o, u, c, r):
    """Solve |o + t u - c|^2 = r^2 for t (u a unit vector): the quadratic's smaller root."""
    px, py = o[0] - c[0], o[1] - c[1]
    b = px * u[0] + py * u[1]
    disc = b * b - (px * px + py * py - r * r)
    if disc < 0:
        return math.inf
    t1, t2 = -b - math.sqrt(disc), -b + math.sqrt(disc)
    return math.inf if t2 < 0 else max(t1, 0.0)


def _corners(c, heading, length, width):
    e1 = (math.cos(heading), math.sin(heading))
    e2 = (-e1[1], e1[0])
    return [(c[0] + a * length / 2 * e1[0] + b * width / 2 * e2[0],
             c[1] + a * length / 2 * e1[1] + b * width / 2 * e2[1])
            for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1))]


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def _rect_range(o, u, c, heading, length, width):
    """0 if o is inside the rectangle, else the nearest crossing of the ray with its 4 edges."""
    corners = _corners(c, heading, length, width)
    edges = [(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    sides = [_cross((q[0] - p[0], q[1] - p[1]), (o[0] - p[0], o[1] - p[1])) for p, q in edges]
    if all(s >= 0 for s in sides) or all(s <= 0 for s in sides):
        return 0.0
    best = math.inf
    for p, q in edges:
        e = (q[0] - p[0], q[1] - p[1])
        w = (p[0] - o[0], p[1] - o[1])
        den = _cross(u, e)
        if den == 0:
            continue
        t, s = _cross(w, e) / den, _cross(w, u) / den
        if t >= 0 and 0 <= s <= 1:
            best = min(best, t)
    return best


def slow_cast(origin, angles, shapes: Shapes) -> np.ndarray:
    out = np.full((len(angles), len(shapes)), np.inf)
    for b, a in enumerate(angles.tolist()):
        u = (math.cos(a), math.sin(a))
        for k in range(len(shapes)):
            c = shapes.centre[k].tolist()
            if shapes.disc[k]:
                out[b, k] = _disc_range(origin, u, c, shapes.length[k] / 2)
            else:
                out[b, k] = _rect_range(origin, u, c, float(shapes.heading[k]),
                                        float(shapes.length[k]), float(shapes.width[k]))
    return out


def slow_counts(dist, max_range):
    """Per object: beams reaching it alone, beams whose nearest object it is (loops)."""
    beams, objects = dist.shape
    clear, visible = [0] * objects, [0] * objects
    for b in range(beams):
        best, first = max_range, None
        for k in range(objects):
            if dist[b, k] < max_range:
                clear[k] += 1
                if dist[b, k] < best:
                    best, first = dist[b, k], k
        if first is not None:
            visible[first] += 1
    return np.array(clear), np.array(visible)


def random_shapes(rng, n):
    disc = rng.random(n) < 0.5
    length = np.where(disc, rng.uniform(0.2, 1.5, n), rng.uniform(0.5, 5, n))
    width = np.where(disc, length, rng.uniform(0.3, 2.5, n))
    return Shapes(rng.uniform(-12, 12, (n, 2)), rng.uniform(-np.pi, np.pi, n), length, width,
                  disc)


@pytest.mark.parametrize("seed", range(6))
def test_vectorised_ranges_equal_a_per_beam_per_object_check(seed):
    rng = np.random.default_rng(seed)
    shapes = random_shapes(rng, 12)
    origin = rng.uniform(-3, 3, 2)
    angles = rng.uniform(-np.pi, np.pi, 400)
    fast, slow = cast(origin, angles, shapes), slow_cast(origin.tolist(), angles, shapes)
    assert np.array_equal(np.isinf(fast), np.isinf(slow))
    hit = np.isfinite(slow)
    assert hit.sum() > 100 and np.isinf(slow).sum() > 100  # both cases are exercised
    np.testing.assert_allclose(fast[hit], slow[hit], rtol=0, atol=1e-9)


def test_a_sensor_inside_a_shape_sees_it_at_zero_and_shapes_behind_are_missed():
    shapes = Shapes(np.array([[0.1, 0.0], [0.0, 0.2], [-3.0, 0.0], [3.0, 0.0]]),
                    np.array([0.0, 0.7, 0.0, 0.0]), np.array([1.0, 2.0, 1.0, 1.0]),
                    np.array([1.0, 1.0, 1.0, 1.0]), np.array([True, False, True, False]))
    dist = cast(np.zeros(2), np.array([0.0]), shapes)
    assert dist[0, 0] == 0 and dist[0, 1] == 0  # inside both
    assert dist[0, 2] == np.inf  # behind the beam
    assert dist[0, 3] == pytest.approx(2.5)  # the rectangle's near face


@pytest.mark.parametrize("seed", range(4))
def test_beam_counts_and_full_occlusion_equal_the_loop_check(seed):
    rng = np.random.default_rng(100 + seed)
    shapes = random_shapes(rng, 25)
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    dist = slow_cast([0.0, 0.0], angles, shapes)
    clear, visible = beam_counts(cast(np.zeros(2), angles, shapes), 10.0)
    slow_clear, slow_visible = slow_counts(dist, 10.0)
    assert np.array_equal(clear, slow_clear) and np.array_equal(visible, slow_visible)
    occluded = (clear > 0) & (visible == 0)
    # the flag means: some beam would reach it, and on every such beam something is nearer
    for k in np.flatnonzero(occluded):
        reach = dist[:, k] < 10.0
        others = np.delete(dist[reach], k, axis=1)
        assert reach.any() and np.all(others.min(axis=1) < dist[reach, k])


def test_the_scenes_flags_equal_the_loop_check_people_and_vehicles():
    config = dataclasses.replace(SMALL, beams=180, people=12, vehicles=2, max_range=25.0)
    flagged = 0
    for scan in simulate_scene(config, 40, seed=3):
        shapes = scan.objects.shapes
        dist = slow_cast(scan.pose[:2].tolist(), scan.pose[2] + scan.angle, shapes)
        clear, visible = slow_counts(dist, config.max_range)
        assert np.array_equal(scan.clear, clear) and np.array_equal(scan.visible, visible)
        flagged += int(scan.occluded.sum())
    assert flagged > 0


def test_a_disc_behind_a_nearer_one_is_fully_occluded_and_seen_once_it_steps_aside():
    angles = beam_angles(LidarSceneConfig())
    for far, hidden in (((6.0, 0.0), True), ((6.0, 1.0), False), ((25.0, 0.0), False)):
        shapes = Shapes(np.array([[2.0, 0.0], far]), np.zeros(2), np.full(2, 0.5),
                        np.full(2, 0.5), np.ones(2, bool))
        clear, visible = beam_counts(cast(np.zeros(2), angles, shapes), 20.0)
        assert ((clear[1] > 0) & (visible[1] == 0)) == hidden
        assert visible[0] == clear[0] > 0  # the near one is never hidden
    # beyond max range it is neither seen nor occluded: no beam would reach it
    assert clear[1] == 0


# -- the sensor ----------------------------------------------------------------------------------

def test_a_perfect_sensor_reports_the_first_surface_and_inf_beyond_range():
    config = LidarSceneConfig(p_d=1.0, range_noise=0.0, clutter_per_scan=0.0, max_range=5.0)
    dist = np.array([[3.0, 1.0], [np.inf, 4.0], [6.0, np.inf], [np.inf, np.inf]])
    z = measure(dist, config, np.random.default_rng(0))
    assert z.tolist() == [1.0, 4.0, np.inf, np.inf]


@pytest.mark.parametrize("sensor, far_share", [("object-wise", 0.0), ("measurement-wise", 0.25)])
def test_a_miss_blocks_the_beam_object_wise_and_lets_it_through_measurement_wise(sensor,
                                                                                 far_share):
    """Two objects on every beam at 2 and 5 m, P_D = 0.5: measurement-wise, the far one is
    reported when the near one misses and it does not (1/4)."""
    config = LidarSceneConfig(p_d=0.5, range_noise=0.01, clutter_per_scan=0.0, sensor=sensor)
    n = 20_000
    z = measure(np.tile([2.0, 5.0], (n, 1)), config, np.random.default_rng(1))
    near, far = np.abs(z - 2) < 0.1, np.abs(z - 5) < 0.1
    assert abs(near.mean() - 0.5) < 0.02 and abs(far.mean() - far_share) < 0.02
    assert np.all(near | far | np.isinf(z))


@pytest.mark.parametrize("sensor", ["object-wise", "measurement-wise"])
def test_an_empty_scene_reports_clutter_only(sensor):
    config = LidarSceneConfig(people=0, sensor=sensor, clutter_per_scan=3.0)
    scans = list(simulate_scene(config, 20, seed=0))
    returns = sum(int(np.isfinite(s.range).sum()) for s in scans)
    assert all(len(s.objects) == 0 for s in scans) and 0 < returns < 150


def test_clutter_returns_come_at_the_configured_rate_and_hide_what_is_behind():
    config = LidarSceneConfig(p_d=1.0, range_noise=0.0, clutter_per_scan=40.0, max_range=20.0)
    rng = np.random.default_rng(2)
    dist = np.full((720, 1), 19.0)
    short = [np.count_nonzero(measure(dist, config, rng) < 19.0) for _ in range(300)]
    # a clutter return lands before 19 m with probability 19/20 (two on a beam: rarely)
    assert abs(np.mean(short) - 40 * 19 / 20) < 1.0


# -- the world -----------------------------------------------------------------------------------

def test_people_keep_their_lanes_apart_and_walk_at_their_speed():
    config = LidarSceneConfig(people=10, stop_probability=0.5)
    scans = list(simulate_scene(config, 300, seed=4))
    for scan in scans:
        y = np.sort(scan.objects.shapes.centre[:, 1])
        assert np.all(np.diff(y) >= config.lane_spacing - 1e-9)
        assert np.all(np.abs(scan.objects.shapes.centre[:, 0]) <= config.half_length + 0.25)
    for a, b in zip(scans, scans[1:], strict=False):
        same = a.objects.id == b.objects.id
        step = (b.objects.shapes.centre - a.objects.shapes.centre)[same, 0]
        speed = np.abs(a.objects.velocity[same, 0])
        assert np.all(np.abs(step) <= config.max_speed * config.period + 1e-9)
        moving = (speed > 0) & (np.abs(b.objects.velocity[same, 0]) > 0)
        # walking on both scans: moved by v dt, unless it stopped and set off in between
        assert np.mean(np.abs(np.abs(step[moving]) - speed[moving] * config.period) < 1e-9) > 0.99


def test_full_occlusion_spells_from_truth_rows():
    time = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.0, 0.1, 0.2, 0.4, 0.5])
    ids = np.array([1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2])
    occ = np.array([0, 1, 1, 1, 0, 1, 1, 1, 1, 1, 1], bool)
    order = np.random.default_rng(0).permutation(len(time))  # any row order
    spells = full_occlusions(time[order], ids[order], occ[order], period=0.1)
    got = sorted(zip(spells.id.tolist(), spells.first.tolist(), spells.last.tolist(),
                     strict=True))
    # id 2 is missing at 0.3: two spells, not one
    assert got == [(1, 0.1, 0.3), (1, 0.5, 0.5), (2, 0.0, 0.2), (2, 0.4, 0.5)]
    assert spells.longer_than(0.15) == 2


def test_a_glimpse_too_small_to_be_seen_does_not_end_a_spell():
    # one object, scans 0.0 .. 0.9: seen, hidden, a one-beam glimpse, hidden, seen, then a
    # run unseen without a fully occluded scan (far away, say), then seen
    time = np.round(np.arange(10) * 0.1, 1)
    ids = np.ones(10, np.int64)
    occ = np.array([0, 1, 0, 1, 1, 0, 0, 0, 0, 0], bool)
    seen = np.array([1, 0, 0, 0, 0, 1, 0, 0, 1, 1], bool)
    order = np.random.default_rng(1).permutation(10)
    bare = full_occlusions(time[order], ids[order], occ[order], period=0.1)
    assert sorted(zip(bare.first.tolist(), bare.last.tolist(), strict=True)) == [
        (0.1, 0.1), (0.3, 0.4)]
    merged = full_occlusions(time[order], ids[order], occ[order], period=0.1,
                             seen=seen[order])
    assert (merged.id.tolist(), merged.first.tolist(), merged.last.tolist()) == (
        [1], [0.1], [0.4])


def test_the_default_scene_has_over_50_full_occlusions_longer_than_a_second():
    config = LidarSceneConfig()
    t, i, o = [], [], []
    for scan in simulate_scene(config, 1800, seed=0):
        t.append(np.full(len(scan.objects), scan.time))
        i.append(scan.objects.id)
        o.append(scan.occluded)
    spells = full_occlusions(np.concatenate(t), np.concatenate(i), np.concatenate(o),
                             config.period)
    assert spells.longer_than(1.0) >= 50


# -- files ---------------------------------------------------------------------------------------

def _bytes(folder):
    return [(folder / n).read_bytes() for n in ("scans.csv", "truth.csv", "sensor.csv")]


def test_one_seed_gives_the_same_bytes_and_another_seed_other_bytes(tmp_path):
    config = dataclasses.replace(SMALL, sensor_vx=0.3, sensor_yaw_rate=0.1)
    for name, seed in (("a", 5), ("b", 5), ("c", 6)):
        write_scene(tmp_path / name, config, 30, seed)
    a, b, c = (_bytes(tmp_path / n) for n in "abc")
    assert a == b
    assert all(x != y for x, y in zip(a, c, strict=True))


def test_a_longer_scene_begins_as_the_shorter_one(tmp_path):
    write_scene(tmp_path / "short", SMALL, 20, 1)
    write_scene(tmp_path / "long", SMALL, 45, 1)
    for short, long in zip(_bytes(tmp_path / "short"), _bytes(tmp_path / "long"), strict=True):
        assert long.startswith(short)


def test_files_read_back_as_simulated(tmp_path):
    config = dataclasses.replace(SMALL, sensor_vx=0.2)
    done = write_scene(tmp_path, config, 25, 9)
    scans = read_scans(tmp_path / "scans.csv")
    truth = read_truth(tmp_path / "truth.csv")
    times, poses = read_poses(tmp_path / "sensor.csv")
    sims = list(simulate_scene(config, 25, 9))
    assert len(scans) == len(sims) == done.scans == 25 and scans.settings["seed"] == "9"
    rows = 0
    for (t, angle, rng), sim, pose in zip(scans, sims, poses, strict=True):
        assert t == pytest.approx(sim.time) and pose == pytest.approx(sim.pose, abs=1e-4)
        np.testing.assert_allclose(angle, sim.angle, atol=1e-6)
        assert np.array_equal(np.isinf(rng), np.isinf(sim.range))
        np.testing.assert_allclose(rng[np.isfinite(rng)], sim.range[np.isfinite(rng)],
                                   atol=1e-4)
        k = slice(rows, rows + len(sim.objects))
        rows += len(sim.objects)
        assert np.array_equal(truth.id[k], sim.objects.id)
        np.testing.assert_allclose(truth.centre[k], sim.objects.shapes.centre, atol=1e-4)
        assert np.array_equal(truth.occluded[k], sim.occluded)
        assert np.array_equal(truth.disc[k], sim.objects.shapes.disc)
    assert rows == len(truth) and np.array_equal(times, scans.time)
    # no-return beams are written as inf, as a LaserScan reports them
    assert ",inf\n" in (tmp_path / "scans.csv").read_text()


GOOD = "# a comment sensor=x\ntime,angle,range\n0.0,0.1,2.5\n0.0,0.2,inf\n0.1,0.1,2.4\n"


@pytest.mark.parametrize("text, line, problem", [
    (GOOD + "0.1,0.2\n", 6, "expected 3 columns (time, angle, range), found 2"),
    (GOOD + "0.1,abc,2\n", 6, "angle is not a number: 'abc'"),
    (GOOD + "0.1,0.2,nan\n", 6, "range is nan; write inf for a beam with no return"),
    (GOOD + "0.1,0.2,-0.5\n", 6, "range -0.5 is negative"),
    (GOOD + "0.05,0.2,1\n", 6, "time 0.05 is earlier than the row before (0.1)"),
    (GOOD + "nan,0.2,1\n", 6, "time is nan; it must be a finite number"),
    (GOOD + "0.2,inf,1\n", 6, "angle is inf; it must be a finite number"),
])
def test_a_bad_scan_row_names_the_file_line_and_problem(tmp_path, text, line, problem):
    path = tmp_path / "scans.csv"
    path.write_text(text)
    with pytest.raises(OcctrackError) as err:
        read_scans(path)
    assert str(err.value).startswith(f"{path}:{line}: {problem}")


def test_a_good_scan_file_groups_rows_by_time(tmp_path):
    path = tmp_path / "scans.csv"
    path.write_text(GOOD)
    scans = read_scans(path)
    assert scans.time.tolist() == [0.0, 0.1] and scans.settings == {"sensor": "x"}
    assert scans[0][1].tolist() == [2.5, np.inf] and scans[1][0].tolist() == [0.1]


def test_a_bad_truth_row_names_the_file_line_and_problem(tmp_path):
    path = tmp_path / "truth.csv"
    row = "0.0,3,{},1,2,0,0,0.5,0.5,0,4,{},0\n"
    path.write_text(row.format("disc", 4) + row.format("square", 4))
    with pytest.raises(OcctrackError, match=r"truth.csv:2: shape 'square' is not one of"):
        read_truth(path)
    path.write_text(row.format("disc", 4) + row.format("disc", 2.5))
    with pytest.raises(OcctrackError, match=r"truth.csv:2: visible_beams 2.5 is not a whole"):
        read_truth(path)


def test_a_missing_scan_file_is_named(tmp_path):
    with pytest.raises(OcctrackError, match="no such file"):
        read_scans(tmp_path / "none.csv")


# -- the command ---------------------------------------------------------------------------------

def test_the_command_writes_refuses_to_overwrite_and_forces(tmp_path, capsys):
    out = tmp_path / "scene"
    argv = ["simulate", "lidar", "-o", str(out), "--scans", "12", "--beams", "120",
            "--people", "4", "--quiet"]
    assert main(argv) == 0
    summary = capsys.readouterr().out
    assert summary.count("\n") == 1 and "12 scans of 120 beams, 4 people" in summary
    scans = read_scans(out / "scans.csv")
    assert len(scans) == 12 and len(scans.angle) == 12 * 120
    before = _bytes(out)
    assert main([*argv, "--seed", "1"]) == 1
    assert "exists already; pass --force" in capsys.readouterr().err
    assert _bytes(out) == before
    assert main([*argv, "--seed", "1", "--force"]) == 0
    assert _bytes(out) != before


def test_the_command_refuses_bad_settings_in_one_line(tmp_path, capsys):
    assert main(["simulate", "lidar", "-o", str(tmp_path), "--fov", "400", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "fov_deg must be a number in (0, 360]" in err
    assert not (tmp_path / "scans.csv").exists()
    (tmp_path / "a-file").write_text("")
    assert main(["simulate", "lidar", "-o", str(tmp_path / "a-file"), "--quiet"]) == 1
    assert "a-file: is a file; give a folder" in capsys.readouterr().err


def test_the_command_has_help(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", "lidar", "--help"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    assert "scans.csv" in text and "--force" in text and "inf: no return" in text


def test_the_single_beam_check_still_imports_from_the_old_place():
    from occtrack.models.beam import BeamModel

    z = simulate_beams(None, BeamModel(clutter_rate=1e-9), 10, np.random.default_rng(0))
    assert np.all(z == 50.0)
