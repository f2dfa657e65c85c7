"""Issue 38, kinds 4 and 5: an output that is a FIFO or a device is written into, never renamed
over (as root, `-o /dev/null --force` replaced the system's /dev/null with a regular file); a
missing input is "no such file", not what could not be looked up beside it."""

from __future__ import annotations

import os
import stat
import threading

import pytest

from occtrack.cli import main


@pytest.fixture
def det(tmp_path):
    path = tmp_path / "det.txt"
    path.write_text("".join(f"{f},-1,{100 + 2 * f},100,40,100,0.9\n" for f in range(1, 31)))
    return path


TRACK = ("--image-size", "640x480", "--fps", "30", "--quiet")


@pytest.mark.parametrize("force", [False, True])
def test_a_fifo_output_is_written_into_and_stays_a_fifo(det, tmp_path, force):
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_text()))
    reader.start()
    argv = ["track", str(det), "-o", str(fifo), *TRACK] + (["--force"] if force else [])
    assert main(argv) == 0
    reader.join(timeout=30)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    reference = tmp_path / "r.txt"
    assert main(["track", str(det), "-o", str(reference), *TRACK]) == 0
    assert got == [reference.read_text()] and got[0]
    assert not list(tmp_path.glob(".*.partial*"))


@pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")
def test_a_device_output_is_written_into_and_stays_a_device(det, tmp_path):
    """A null device made here (the same as /dev/null: major 1, minor 3), so that a failure
    could only ever replace this one."""
    null = tmp_path / "null"
    os.mknod(null, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    assert main(["track", str(det), "-o", str(null), *TRACK, "--force"]) == 0
    assert main(["track", str(det), "-o", str(null), *TRACK]) == 0
    assert stat.S_ISCHR(os.stat(null).st_mode)
    assert not list(tmp_path.glob(".*.partial*"))


@pytest.mark.parametrize("argv", [
    ["track", "{missing}", "-o", "{out}"],
    ["calibrate", "{missing}", "{det}", "-o", "{out}"],
    ["calibrate", "{det}", "{missing}", "-o", "{out}"],
])
def test_a_missing_input_is_no_such_file(argv, det, tmp_path, capsys):
    missing = tmp_path / "nowhere.txt"
    values = {"missing": str(missing), "det": str(det), "out": str(tmp_path / "o.toml")}
    assert main([a.format(**values) for a in argv]) == 1
    err = capsys.readouterr().err
    assert err.strip().endswith(f"{missing}: no such file") and err.count("\n") == 1


def _without_eval_extra(argv: list[str]):
    """`occtrack ARGV` in a fresh interpreter where motmetrics and TrackEval cannot be
    imported (as on the core install)."""
    import subprocess
    import sys

    code = ("import sys; sys.modules['motmetrics'] = None; sys.modules['trackeval'] = None\n"
            "from occtrack.cli import main\n"
            f"sys.exit(main({argv!r}))")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)


@pytest.mark.parametrize("argv, status", [
    (["reproduce", "--help"], 0),
    (["reproduce", "table2", "--help"], 0),
    (["reproduce", "table2", "--seed", "2"], 1),
])
def test_reproduce_without_the_eval_extra_names_it(argv, status):
    done = _without_eval_extra(argv)
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr
    if argv[1:2] == ["table2"]:
        said = done.stdout if status == 0 else done.stderr
        assert ('occtrack reproduce table2 needs motmetrics, from the optional \'eval\' extra: '
                'install it with pip install "occtrack[eval]"') in said
    else:
        assert "table2" in done.stdout
