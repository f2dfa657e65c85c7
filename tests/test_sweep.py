"""`occtrack sweep`: the spec, the table, reruns, the LocalCluster's equality with a
sequential run, and the report of a failed task."""

from __future__ import annotations

import importlib.util
import json

import pytest

from occtrack.cli import main
from occtrack.errors import OcctrackError
from occtrack.experiments import sweep
from sequences import write_sequence

pytest.importorskip("pyarrow", reason="the sweep's table needs `pip install occtrack[sweep]`")

LENGTH = 30


def make_sequence(folder, name: str, seed: int = 4) -> None:
    """A small synthetic MOTChallenge sequence folder (gt with class 1, visibility 1)."""
    write_sequence(folder, name, people=4, frames=LENGTH, length=LENGTH, seed=seed)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep-data")
    make_sequence(root / "SYN-A", "SYN-A", seed=4)
    make_sequence(root / "SYN-B", "SYN-B", seed=5)
    return root


MOT_SPEC = """\
trackers = ["none", "measurement-wise"]
[work]
kind = "mot"
sequences = ["{root}"]
[grid]
edge_noise = [0.05, 0.08]
"""

HIGHWAY_SPEC = """\
trackers = ["measurement-wise", "object-wise-expval"]
seeds = 2
[work]
kind = "highway"
steps = 15
sensors = ["measurement-wise"]
[base]
particles = 128
undetected_particles = 64
birth_particles = 64
[grid]
detection_probability = [0.95, 0.99]
"""


def write(path, text: str):
    path.write_text(text)
    return path


def without_timing(table):
    return table.drop(columns=[c for c in sweep.TIMING if c in table.columns])


def test_spec_plans_every_cell_with_typed_settings(data, tmp_path):
    spec = sweep.load_spec(write(tmp_path / "s.toml", MOT_SPEC.format(root=data)))
    cells = sweep.plan(spec)
    assert len(cells) == 2 * 2 * 2  # sequences x trackers x points, one seed
    assert [c.work for c in cells[:4]] == ["SYN-A"] * 4
    assert {c.values["edge_noise"] for c in cells} == {0.05, 0.08}
    assert len({c.key for c in cells}) == len(cells)
    # an integer where a float is expected is the same setting, so the same cell
    same = sweep.load_spec(write(tmp_path / "t.toml", MOT_SPEC.format(root=data).replace(
        "0.05, 0.08", "0.05, 0.08")))
    assert [c.key for c in sweep.plan(same)] == [c.key for c in cells]


def test_random_search_is_seeded_and_crossed_with_the_grid(tmp_path):
    text = HIGHWAY_SPEC + """
[random]
samples = 3
seed = 7
kernel_bandwidth = {uniform = [0.3, 0.6]}
particles = {choice = [128, 192]}
"""
    spec = sweep.load_spec(write(tmp_path / "r.toml", text))
    again = sweep.load_spec(write(tmp_path / "r2.toml", text))
    assert spec.points == again.points and len(spec.points) == 2 * 3
    assert all(0.3 <= p["kernel_bandwidth"] <= 0.6 for p in spec.points)
    assert {p["particles"] for p in spec.points} <= {128, 192}


@pytest.mark.parametrize("text, message", [
    ("[work]\nkind = 'video'\n", "kind must be one of"),
    ("[work]\nkind = 'highway'\n[grid]\nparticle = [1, 2]\n", "unknown highway setting"),
    ("[work]\nkind = 'highway'\n[grid]\nparticles = []\n", "non-empty list"),
    ("[work]\nkind = 'highway'\n[grid]\nsurvival = [0.9, 1.5]\n", "survival"),
    ("[work]\nkind = 'highway'\nseeds = 2\n", "seeds belongs at the top of the spec"),
    ("[work]\nkind = 'highway'\nstep = 2\n", "[work] key 'step'"),
    ("[work]\nkind = 'highway'\n[random]\nsamples = 2\nsurvival = {normal = [0, 1]}\n",
     "must be one of"),
    ("[work]\nkind = 'mot'\nsequences = ['{root}']\n[grid]\nedge_noise = [-1.0]\n",
     "edge_noise must be a positive number"),
    ("[work]\nkind = 'mot'\nsequences = ['{root}']\n[grid]\nocclusion = ['none']\n",
     "chosen by trackers"),
    ("seeds = [1, 2]\n[work]\nkind = 'mot'\nsequences = ['{root}']\n",
     "seeds only matter with simulated detections"),
    ("trackers = ['deepsort']\n[work]\nkind = 'mot'\nsequences = ['{root}']\n",
     "unknown name 'deepsort'"),
])
def test_bad_specs_are_refused_before_any_task(data, tmp_path, text, message):
    path = write(tmp_path / "bad.toml", text.replace("{root}", str(data)))
    with pytest.raises(OcctrackError, match=message.replace("[", r"\[")) as err:
        sweep.load_spec(path)
    assert str(path) in str(err.value)


def test_sequential_table_and_rerun_skip(tmp_path):
    pytest.importorskip("pandas")
    spec_path = write(tmp_path / "hw.toml", HIGHWAY_SPEC)
    out = tmp_path / "hw.parquet"
    spec = sweep.load_spec(spec_path)
    first = sweep.sweep(spec, out)
    assert first.ran == 8 and first.skipped == 0 and not first.failures
    table = first.table
    assert list(table["cell"]) == [c.key for c in first.cells]  # plan order
    assert {"setting.particles", "setting.detection_probability", "gospa", "gospa_per_car",
            "seconds", "task_seconds", "seed", "tracker", "work"} <= set(table.columns)
    assert (table["steps"] == 15).all() and (table["task_seconds"] >= table["seconds"]).all()
    assert json.loads(table["settings"][0])["particles"] == 128

    again = sweep.sweep(spec, out)
    assert again.ran == 0 and again.skipped == 8
    if sweep.dask_available():  # nothing to run: the cluster is never started (it once
        engine = sweep.DaskEngine(workers=1)  # was asked for tasks it did not have)
        assert sweep.sweep(spec, out, engine).skipped == 8 and not engine.started
    # a larger grid runs only its new cells and keeps the old rows
    bigger = sweep.load_spec(write(tmp_path / "hw.toml", HIGHWAY_SPEC.replace(
        "[0.95, 0.99]", "[0.95, 0.99, 0.9]")))
    grown = sweep.sweep(bigger, out)
    assert grown.ran == 4 and grown.skipped == 8 and len(grown.table) == 12
    import pandas as pd

    stored = pd.read_parquet(out)
    assert list(stored["cell"]) == [c.key for c in grown.cells]
    kept = stored.set_index("cell").loc[list(table["cell"])].reset_index()
    pd.testing.assert_frame_equal(without_timing(kept)[without_timing(table).columns],
                                  without_timing(table))
    summary = sweep.summarise(grown.table, grown.cells)
    assert "mean +- standard error over 2 seeds" in summary and "GOSPA/step" in summary


@pytest.fixture(scope="module")
def cluster():
    pytest.importorskip("distributed", reason="the Dask engine needs `occtrack[sweep]`")
    with sweep.DaskEngine(workers=2) as engine:
        yield engine


@pytest.mark.parametrize("which", ["mot", "highway"])
def test_local_cluster_gives_the_sequential_table(cluster, data, tmp_path, which):
    """Same spec, same seeds: the LocalCluster's table equals the sequential one in every
    column but the timings, row for row, whatever order the tasks finished in."""
    text = MOT_SPEC.format(root=data) if which == "mot" else HIGHWAY_SPEC
    if which == "mot":  # simulated detections, so that the seeds matter
        text = text.replace("kind = \"mot\"", "kind = \"mot\"\ndetections = \"simulated\"")
        text = "seeds = [0, 1]\n" + text
    spec = sweep.load_spec(write(tmp_path / "s.toml", text))
    one = sweep.sweep(spec, tmp_path / "sequential.parquet")
    two = sweep.sweep(spec, tmp_path / "cluster.parquet", cluster)
    assert one.ran == two.ran == len(one.cells) == (16 if which == "mot" else 8)
    assert not one.failures and not two.failures
    import pandas as pd

    a = pd.read_parquet(tmp_path / "sequential.parquet")
    b = pd.read_parquet(tmp_path / "cluster.parquet")
    pd.testing.assert_frame_equal(without_timing(a), without_timing(b), check_exact=True)
    assert len(set(b["seed"])) == 2


def test_failed_task_is_reported_with_its_settings_and_the_others_finish(cluster, data,
                                                                          tmp_path, capsys):
    root = tmp_path / "seqs"
    root.mkdir()
    for name in ("SYN-A", "SYN-B"):
        (root / name).symlink_to(data / name, target_is_directory=True)
    broken = root / "SYN-C"
    make_sequence(broken, "SYN-C")
    det = broken / "det" / "det.txt"
    det.write_text(det.read_text() + "3,-1,10,10,-5,20,0.9,-1,-1\n")  # a negative width
    spec = sweep.load_spec(write(tmp_path / "s.toml", MOT_SPEC.format(root=root)))
    outcome = sweep.sweep(spec, tmp_path / "t.parquet", cluster)
    assert outcome.ran == 8 and len(outcome.failures) == 4
    assert {f.cell.work for f in outcome.failures} == {"SYN-C"}
    assert set(outcome.table["work"]) == {"SYN-A", "SYN-B"}
    report = sweep.format_failures(outcome.failures)
    assert "SYN-C / none / seed 0 / edge_noise=0.05" in report
    assert f"{det}:" in report and "negative box size" in report

    # the command: the failures on stderr, the others' summary on stdout, exit status 1;
    # a rerun runs only the failed cells again
    code = main(["sweep", str(tmp_path / "s.toml"), "-o", str(tmp_path / "t.parquet"),
                 "--sequential"])
    captured = capsys.readouterr()
    assert code == 1
    assert "4 task(s) failed" in captured.err and "edge_noise=0.08" in captured.err
    assert "8 cells: 0 run, 8 already in" not in captured.out
    assert "12 cells: 0 run, 8 already in" in captured.out


def test_command_prints_summary_and_dry_run(data, tmp_path, capsys):
    spec = write(tmp_path / "s.toml", MOT_SPEC.format(root=data))
    assert main(["sweep", str(spec), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert out.count("todo  ") == 8 and "8 cells, 0 in" in out
    assert main(["sweep", str(spec), "--sequential", "--quiet"]) == 0
    assert (tmp_path / "s.parquet").is_file()
    assert main(["sweep", str(spec), "--sequential"]) == 0
    out = capsys.readouterr().out
    assert "8 cells: 0 run, 8 already in" in out
    assert "mean over the 2 sequences" in out and "HOTA" in out
    assert "p1   edge_noise=0.08" in out
    assert main(["sweep", str(spec), "--dry-run"]) == 0
    assert capsys.readouterr().out.count("done  ") == 8


@pytest.mark.parametrize("argv", [["sweep", "--help"], ["calibrate", "--help"]])
def test_help_loads_no_heavy_module(argv):
    import subprocess
    import sys

    heavy = ("numpy", "scipy", "pandas", "pyarrow", "dask", "distributed", "occtrack.tracker")
    code = (f"import sys\nfrom occtrack.cli import main\ntry:\n    main({argv!r})\n"
            f"except SystemExit:\n    pass\n"
            f"print('loaded:', *sorted(m for m in {heavy!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.rstrip().splitlines()[-1] == "loaded:"


def test_scheduler_address_sends_the_same_tasks(cluster, tmp_path):
    """--scheduler: a client of a running cluster (here the LocalCluster's own scheduler,
    reached by its tcp:// address) gives the same table again."""
    spec = sweep.load_spec(write(tmp_path / "s.toml", HIGHWAY_SPEC))
    one = sweep.sweep(spec, tmp_path / "sequential.parquet")
    address = cluster._cluster.scheduler_address
    assert address.startswith("tcp://127.0.0.1:")
    remote = sweep.DaskEngine(scheduler=address)
    two = sweep.sweep(spec, tmp_path / "remote.parquet", remote)
    assert not remote.started  # the command's own client is closed, the cluster is not
    assert "Dask scheduler tcp://" in two.engine and "(2 workers)" in two.engine
    import pandas as pd

    pd.testing.assert_frame_equal(without_timing(one.table), without_timing(two.table))
    with pytest.raises(OcctrackError, match="cannot reach the Dask scheduler"):
        with sweep.DaskEngine(scheduler="tcp://127.0.0.1:9", timeout=1.0):
            pass


def test_example_specs_parse():
    from pathlib import Path

    folder = Path(__file__).resolve().parents[1] / "docs" / "sweeps"
    spec = sweep.load_spec(folder / "highway.toml")
    assert len(sweep.plan(spec)) == 72
    assert len(sweep.plan(sweep.load_spec(folder / "lidar.toml"))) == 36
    # the MOT17 example names the data beside the checkout, relative to the spec
    if (folder / "../../../shared/data/mot17/MOT17-04-FRCNN").resolve().is_dir():
        spec = sweep.load_spec(folder / "mot17.toml")
        assert len(sweep.plan(spec)) == 12 * len(spec.sequences)
        if importlib.util.find_spec("optuna") is not None:
            spec = sweep.load_spec(folder / "search.toml")
            assert spec.search.trials == 24 and spec.search.metric == "hota"


def test_reproduce_table3_on_dask_gives_the_same_table(capsys):
    pytest.importorskip("distributed", reason="the Dask engine needs `occtrack[sweep]`")
    args = ["reproduce", "table3", "--steps", "8", "--seeds", "2", "--json", "--quiet"]
    assert main(args + ["--jobs", "1"]) == 0  # in this process
    plain = json.loads(capsys.readouterr().out)
    assert main(args) == 0  # the default: a LocalCluster of 2 workers
    on_dask = json.loads(capsys.readouterr().out)
    for sensor, row in plain.items():
        for tracker, cell in row.items():
            assert on_dask[sensor][tracker]["mean"] == cell["mean"]
            assert on_dask[sensor][tracker]["stderr"] == cell["stderr"]


SEARCH_SPEC = """\
trackers = ["measurement-wise", "object-wise-expval"]
seeds = 2
[work]
kind = "highway"
steps = 10
sensors = ["measurement-wise"]
[base]
particles = 64
undetected_particles = 32
birth_particles = 32
[search]
kind = "optuna"
trials = {trials}
batch = 2
metric = "gospa"
direction = "minimize"
seed = 3
detection_probability = {{uniform = [0.9, 0.99]}}
kernel_bandwidth = {{log_uniform = [0.3, 0.7]}}
"""


def test_optuna_search_is_seeded_streams_into_the_table_and_resumes(cluster, tmp_path):
    """A tiny Optuna study per tracker: the cells of its trials are rows of the table, each
    trial's value is the mean GOSPA over its seeds, the best trial is the lowest; the same
    spec gives the same trials and table on a LocalCluster; a rerun with more trials replays
    the first ones from the table and runs only the new ones."""
    pytest.importorskip("optuna", reason="[search] needs `pip install occtrack[sweep]`")
    spec = sweep.load_spec(write(tmp_path / "s.toml", SEARCH_SPEC.format(trials=3)))
    assert spec.points == () and spec.search.trials == 3
    one = sweep.sweep(spec, tmp_path / "one.parquet")
    assert not one.failures
    assert len(one.cells) == 2 * 3 * 2 and one.ran == len({c.key for c in one.cells})
    table = one.table
    assert set(table["tracker"]) == {"measurement-wise", "object-wise-expval"}
    drawn = table["setting.detection_probability"]
    assert ((drawn >= 0.9) & (drawn <= 0.99)).all() and (table["setting.particles"] == 64).all()
    for tracker in ("measurement-wise", "object-wise-expval"):
        rows = table[table["tracker"] == tracker]
        means = rows.groupby("settings")["gospa"].mean()
        best = next(n for n in one.notes if n.startswith(tracker))
        assert f"best gospa {means.min():.4f}" in best and "of 3, minimize" in best

    two = sweep.sweep(spec, tmp_path / "two.parquet", cluster)
    assert two.notes == one.notes
    import pandas as pd

    pd.testing.assert_frame_equal(without_timing(pd.read_parquet(tmp_path / "one.parquet")),
                                  without_timing(pd.read_parquet(tmp_path / "two.parquet")),
                                  check_exact=True)
    more = sweep.load_spec(write(tmp_path / "s.toml", SEARCH_SPEC.format(trials=5)))
    grown = sweep.sweep(more, tmp_path / "one.parquet")
    assert grown.skipped >= len(one.cells) and grown.ran <= 2 * 2 * 2
    assert {c.key for c in one.cells} <= {c.key for c in grown.cells}


@pytest.mark.parametrize(("extra", "message"), [
    ("[grid]\nparticles = [64, 128]\n", "[search] replaces [grid] and [random]"),
    ("", None)])
def test_search_spec_is_checked_before_any_task(tmp_path, extra, message):
    pytest.importorskip("optuna", reason="[search] needs `pip install occtrack[sweep]`")
    text = SEARCH_SPEC.format(trials=2) + extra
    if message is None:  # a setting out of its range at one end of the search
        text, message = text.replace("[0.9, 0.99]", "[0.9, 1.5]"), "detection_probability"
    with pytest.raises(OcctrackError, match=message.replace("[", r"\[")):
        sweep.load_spec(write(tmp_path / "s.toml", text))
    for bad, says in (('metric = "gospa"', 'metric = "hota"'),
                      ('direction = "minimize"', 'direction = "down"'),
                      ("trials = 2", "trials = 0")):
        with pytest.raises(OcctrackError, match=says.split(" ")[0]):
            sweep.load_spec(write(tmp_path / "b.toml",
                                  SEARCH_SPEC.format(trials=2).replace(bad, says)))


LIDAR_SPEC = """\
seeds = [0, 1]
[work]
kind = "lidar"
ranges = [10.0, 20.0]
samples = 20000
[grid]
p_d = [0.7, 0.9]
"""


def test_lidar_cells_check_the_derived_beam_likelihood(tmp_path):
    """kind lidar: each cell puts the derived L(z | x) beside seeded simulated beams; the
    derivation holds (within a few standard errors) for every range, P_D and seed, L is
    high at the object, about 1 - P_D just past it, and the table is seeded."""
    spec = sweep.load_spec(write(tmp_path / "l.toml", LIDAR_SPEC))
    cells = sweep.plan(spec)
    assert len(cells) == 2 * 1 * 2 * 2 and {c.work for c in cells} == {"x=10m", "x=20m"}
    one = sweep.sweep(spec, tmp_path / "one.parquet")
    assert one.ran == 8 and not one.failures
    table = one.table
    assert (table["max_z"] < 4.5).all()
    assert (table["l_hit"] > 1).all()
    assert table["l_none"].tolist() == pytest.approx(1 - table["setting.p_d"])
    assert ((table["l_passed"] - table["l_none"]).abs() < 0.01).all()
    assert ((table["l_hidden"] - 1).abs() < 0.01).all()
    again = sweep.sweep(spec, tmp_path / "two.parquet")
    import pandas as pd

    pd.testing.assert_frame_equal(without_timing(pd.read_parquet(tmp_path / "one.parquet")),
                                  without_timing(again.table), check_exact=True)
    assert "max |z|" in sweep.summarise(table, one.cells)
    for bad, says in (("ranges = [10.0, 20.0]", "ranges = [60.0]"),
                      ("p_d = [0.7, 0.9]", "p_d = [1.5]"),
                      ("p_d = [0.7, 0.9]", "speed = [1.0]")):
        with pytest.raises(OcctrackError, match=r"max_range|p_d|unknown lidar setting"):
            sweep.load_spec(write(tmp_path / "b.toml", LIDAR_SPEC.replace(bad, says)))


class _Unreachable:
    """An engine whose scheduler cannot be reached (what DaskEngine raises then)."""

    started = False

    def __enter__(self):
        raise OcctrackError("cannot reach the Dask scheduler at tcp://127.0.0.1:1")

    def __exit__(self, *exc):
        return False


def test_an_engine_that_never_starts_leaves_no_table(tmp_path):
    """Issue 38: a sweep whose scheduler cannot be reached wrote a 0-column Parquet file,
    which the same command then refused once the scheduler ran; now nothing is left, and
    the rerun works."""
    pytest.importorskip("pandas")
    spec = sweep.load_spec(write(tmp_path / "hw.toml", HIGHWAY_SPEC))
    out = tmp_path / "hw.parquet"
    with pytest.raises(OcctrackError, match="cannot reach the Dask scheduler"):
        sweep.sweep(spec, out, _Unreachable())
    assert not out.exists() and not list(tmp_path.glob(".*partial*"))
    assert sweep.sweep(spec, out).ran == 8
