"""The command line: one line and a documented exit status for every failure, outputs that
never overwrite inputs, and help that loads none of the heavy libraries."""

from __future__ import annotations

import errno
import importlib
import subprocess
import sys

import pytest

from occtrack._compat import tomllib
from occtrack.cli import COMMANDS, main

DET = "1,-1,10,10,30,90,0.9\n2,-1,12,10,30,90,0.8\n3,-1,14,10,30,90,0.85\n"
GT = "1,1,10,10,30,90,1,1,1\n2,1,12,10,30,90,1,1,1\n"


@pytest.fixture
def det(tmp_path):
    path = tmp_path / "det.txt"
    path.write_text(DET)
    return path


def track(det, *args):
    return main(["track", str(det), "--image-size", "640x480", "--fps", "30", "--quiet", *args])


def one_error_line(capsys, start: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith(start) and err.count("\n") == 1 and "Traceback" not in err
    return err


def test_help_documents_the_exit_status(capsys):
    for argv in (["--help"], ["track", "--help"]):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        assert exit_.value.code == 0
        text = capsys.readouterr().out
        for line in ("1    bad input", "2    usage", "130  interrupted", "--debug"):
            assert line in text


def test_usage_errors_exit_2(det, capsys):
    with pytest.raises(SystemExit) as exit_:
        track(det, "-o", "r.txt", "--score-range", "5,1")
    assert exit_.value.code == 2 and "LO < HI" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["no-such-command"])
    assert exit_.value.code == 2


def test_output_that_is_an_input_is_refused_before_reading(det, tmp_path, capsys):
    assert track(det, "-o", str(det), "--force") == 1
    err = one_error_line(capsys, f"occtrack track: error: {det}: is also an input")
    assert det.read_text() == DET and "another file" in err
    config = tmp_path / "tracker.toml"
    config.write_text('occlusion = "none"\n')
    assert track(det, "--config", str(config), "-o", str(config), "--force") == 1
    one_error_line(capsys, f"occtrack track: error: {config}: is also an input")
    assert config.read_text() == 'occlusion = "none"\n'
    gt = tmp_path / "gt.txt"
    gt.write_text(GT)
    assert main(["simulate-detections", str(gt), "-o", str(gt), "--force"]) == 1
    one_error_line(capsys, f"occtrack simulate-detections: error: {gt}: is also an input")
    assert gt.read_text() == GT


def test_dash_writes_the_result_to_stdout(det, capsys):
    assert main(["track", str(det), "--image-size", "640x480", "--fps", "30", "-o", "-"]) == 0
    out, err = capsys.readouterr()
    rows = out.splitlines()
    assert rows and all(row.count(",") == 9 for row in rows)
    assert "frames per second" in err


def test_simulated_detections_to_stdout(tmp_path, capsys):
    gt = tmp_path / "gt.txt"
    gt.write_text(GT)
    assert main(["simulate-detections", str(gt), "-o", "-", "--seed", "1"]) == 0
    out, err = capsys.readouterr()
    assert all(row.count(",") == 9 for row in out.splitlines()) and "seed 1" in err


def test_bad_rows_name_file_line_and_the_way_out(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n2,-1,10,10,30,90,57\n")
    out = tmp_path / "r.txt"
    assert track(det, "-o", str(out)) == 1
    err = one_error_line(capsys, f"occtrack track: error: {det}:2: score 57 is outside [0, 1]")
    assert "--score-range LO,HI" in err and "--lenient" in err and not out.exists()
    assert track(det, "-o", str(out), "--score-range", "0,100") == 0
    assert track(det, "-o", str(out), "--force", "--lenient") == 0
    assert capsys.readouterr().err == (f"occtrack track: warning: {det}: clipped 1 scores to "
                                       f"[0, 1] (first at line 2)\n")


def test_stray_frame_number_is_an_error_not_a_loop(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n1000000000,-1,10,10,30,90,0.9\n")
    assert track(det, "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {det}:2: frame 1000000000 follows frame 1")
    assert track(det, "-o", str(tmp_path / "r.txt"), "--max-gap-frames", "5") == 1


def test_eval_bounds_empty_frames_when_the_length_is_unknown(tmp_path, capsys):
    gt = tmp_path / "gt.txt"
    gt.write_text(GT)
    result = tmp_path / "result.txt"
    result.write_text("1,1,10,10,30,90,1\n1000000000,1,10,10,30,90,1\n")
    assert main(["eval", str(gt), str(result)]) == 1
    one_error_line(capsys, f"occtrack eval: error: {result}:2: frame 1000000000 follows frame 1")


def test_integer_columns_are_parsed_as_integers(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n2.5,-1,10,10,30,90,0.9\n")
    assert track(det, "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {det}:2: frame 2.5 is not a whole number")


def test_os_errors_are_one_line_naming_the_file(det, tmp_path, capsys, monkeypatch):
    assert track(tmp_path, "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {tmp_path}: is a directory")

    track_module = importlib.import_module("occtrack.cli.track")

    def denied(args):
        raise PermissionError(errno.EACCES, "Permission denied", "locked/det.txt")

    monkeypatch.setattr(track_module, "run", denied)
    assert track(det, "-o", "r.txt") == 1
    err = one_error_line(capsys, "occtrack track: error: locked/det.txt: permission denied; ")
    assert "check the permissions" in err

    def full(args):
        raise OSError(errno.ENOSPC, "No space left on device", "r.txt")

    monkeypatch.setattr(track_module, "run", full)
    assert track(det, "-o", "r.txt") == 1
    assert "r.txt: no space left on device; free some space" in one_error_line(capsys, "occ")


def test_disk_full_midway_keeps_the_old_result(det, tmp_path, capsys, monkeypatch):
    from occtrack.io import atomic

    out = tmp_path / "r.txt"
    out.write_text("old result\n")

    class Full:
        def __init__(self, fh):
            self.fh = fh

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

    monkeypatch.setattr(atomic, "open", lambda *a, **k: Full(open(*a, **k)), raising=False)
    assert track(det, "-o", str(out), "--force") == 1
    one_error_line(capsys, f"occtrack track: error: {out}: no space left on device")
    assert out.read_text() == "old result\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["det.txt", "r.txt"]


def test_bad_toml_and_non_utf8_settings(det, tmp_path, capsys):
    config = tmp_path / "bad.toml"
    config.write_bytes(b"occlusion = \xff\xfe\n")
    assert track(det, "--config", str(config), "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {config}: not valid TOML")
    config.write_text("occlusion = [\n")
    assert track(det, "--config", str(config), "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {config}: not valid TOML")
    config.write_text("frame_step = 2.5\n")
    assert track(det, "--config", str(config), "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: {config}: frame_step must be an integer")


@pytest.mark.parametrize("failure,status,message", [
    (KeyboardInterrupt(), 130, "occtrack track: interrupted"),
    (MemoryError(), 1, "occtrack track: error: out of memory; the largest input is "),
    (UnicodeDecodeError("utf-8", b"\xff", 0, 1, "invalid start byte"), 1,
     "occtrack track: error: an input is not UTF-8 text"),
    (tomllib.TOMLDecodeError("Expected '='"), 1,
     "occtrack track: error: a settings file is not valid TOML: Expected '='"),
    (ZeroDivisionError("division by zero"), 1,
     "occtrack track: error: internal error: ZeroDivisionError: division by zero; this is a "
     "bug"),
])
def test_every_failure_has_one_line_and_a_status(det, capsys, monkeypatch, failure, status,
                                                 message):
    def fail(args):
        raise failure

    monkeypatch.setattr(importlib.import_module("occtrack.cli.track"), "run", fail)
    assert track(det, "-o", "r.txt", "--config", "cfg.toml") == status
    one_error_line(capsys, message)
    with pytest.raises(type(failure)):
        main(["--debug", "track", str(det), "--image-size", "640x480", "--fps", "30",
              "-o", "r.txt"])


def test_out_of_memory_names_the_largest_input_and_the_settings(det, capsys, monkeypatch,
                                                                 tmp_path):
    """Issue 38, kind 3: running out of memory names what the user gave that could cause it,
    never settings that were not given."""
    def fail(args):
        raise MemoryError

    monkeypatch.setattr(importlib.import_module("occtrack.cli.track"), "run", fail)
    config = tmp_path / "cfg.toml"
    config.write_text("occlusion = 'none'\n")
    size = det.stat().st_size
    assert track(det, "-o", str(tmp_path / "r.txt")) == 1
    one_error_line(capsys, f"occtrack track: error: out of memory; the largest input is {det} "
                           f"({size / 1e6:.0f} MB): split it; or give the run more memory")
    assert track(det, "-o", str(tmp_path / "r.txt"), "--config", str(config)) == 1
    one_error_line(capsys, f"occtrack track: error: out of memory; the largest input is {det} "
                           f"({size / 1e6:.0f} MB): split it; or lower the sizes set in {config} "
                           f"(capacity, max_labels, particles, ...); or give the run more memory")


def test_occlusion_names_match_the_tracker():
    from occtrack.cli.track import OCCLUSION_NAMES
    from occtrack.tracker import OCCLUSION_NAMES as TRACKER_NAMES

    assert OCCLUSION_NAMES == TRACKER_NAMES


HEAVY = ("numpy", "scipy", "numba", "matplotlib", "trackeval", "motmetrics", "pandas", "tqdm",
         "occtrack.tracker")

PROBE = """
import sys
from occtrack.cli import main
try:
    main({argv!r})
except SystemExit:
    pass
print("loaded:", *sorted(m for m in {heavy!r} if m in sys.modules))
"""


def loaded_after(argv: list[str]) -> str:
    code = PROBE.format(argv=argv, heavy=HEAVY) if argv else (
        f"import sys, occtrack; print('loaded:', *(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    return done.stdout.rstrip().splitlines()[-1]


@pytest.mark.parametrize("argv", [
    [], ["--help"], ["track", "--help"], ["eval", "--help"], ["demo", "--help"],
    ["simulate-detections", "--help"], ["foursquare", "--help"], ["lidar", "--help"],
    ["render", "--help"], ["track-scans", "--help"],
])
def test_help_and_import_load_no_heavy_module(argv):
    """Every subcommand module is imported to list it, so each must import only light modules
    at its top (the rule in occtrack.cli's docstring); these commands' options need none."""
    assert loaded_after(argv) == "loaded:"


def test_every_subcommand_module_is_light_at_import():
    code = ("import importlib, sys\n"
            f"for name in {COMMANDS!r}:\n"
            "    importlib.import_module('occtrack.cli.' + name)\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == ""
