"""Real faults, not patched ones: a run interrupted by SIGINT while its output is being written,
an output folder one cannot write in, a disk that fills up. Each must end in one line on stderr
and the documented exit status, and leave the old output (or none) and no temporary file.

Each command runs as a user runs it, `python -m occtrack ...` in a subprocess. The faults are
made deterministic: the interrupted run is held mid-write by a FIFO among its input pictures
(it blocks reading the next frame with its output open), the read-only folder is a real one,
the full disk a real 64 KiB tmpfs. tests/test_atomic.py and tests/test_cli_errors.py patch the
same faults in-process, where every code path is reached whatever the machine allows."""

from __future__ import annotations

import ctypes
import errno
import os
import shutil
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from conftest import in_ci

W, H = 320, 240
FRAMES, PEOPLE = 200, 8
TRACK = ("--image-size", "1280x480", "--fps", "30", "--quiet")
CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH = 1, 2
PR_CAPBSET_DROP = 24


def occtrack(*argv, timeout: float = 300, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "occtrack", *map(str, argv)],
                          capture_output=True, text=True, timeout=timeout, **kwargs)


def one_line(stderr: str, start: str) -> str:
    assert stderr.startswith(start), stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr, stderr
    return stderr


def partial_files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial" in p.name)


@pytest.fixture(scope="module")
def detections(tmp_path_factory) -> Path:
    """8 people walking for 200 frames: a result file of about 75 KB."""
    path = tmp_path_factory.mktemp("det") / "det.txt"
    path.write_text("".join(f"{f},-1,{50 + 70 * i + 0.5 * f:.1f},{100 + 10 * i},30,90,0.9\n"
                            for f in range(1, FRAMES + 1) for i in range(PEOPLE)))
    return path


# --- mounts (we may be root; CI is) ----------------------------------------------------------

def _cannot_mount() -> str | None:
    """Why this process cannot mount a file system, or None if it can."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return "mounting needs root"
    if shutil.which("mount") is None or shutil.which("umount") is None:
        return "no mount command"
    return None


@contextmanager
def mounted(where: Path, *args: str):
    """`mount ARGS WHERE` for the block; skips, saying why, where mounting is impossible."""
    reason = _cannot_mount()
    if reason is None:
        done = subprocess.run(["mount", *args, str(where)], capture_output=True, text=True)
        if done.returncode != 0:
            reason = f"mount {' '.join(args)} failed: {done.stderr.strip()}"
    if reason is not None:
        pytest.skip(f"{reason}; the patched version of this fault in tests/test_atomic.py and "
                    f"tests/test_cli_errors.py still runs")
    try:
        yield where
    finally:
        if subprocess.run(["umount", str(where)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(where)], capture_output=True)


# --- a full disk -----------------------------------------------------------------------------

@pytest.mark.parametrize("old", [True, False], ids=["old-file", "no-file"])
def test_a_full_disk_leaves_the_old_result_and_no_partial_file(detections, tmp_path, old):
    roomy = tmp_path / "roomy.txt"
    assert occtrack("track", detections, *TRACK, "-o", roomy).returncode == 0
    assert roomy.stat().st_size > 64 * 1024  # the result does not fit on the small disk
    disk = tmp_path / "disk"
    disk.mkdir()
    with mounted(disk, "-t", "tmpfs", "-o", "size=64k", "tmpfs"):
        out = disk / "result.txt"
        if old:
            out.write_text("the old, complete result\n")
        run = occtrack("track", detections, *TRACK, "-o", out, "--force")
        assert run.returncode == 1
        one_line(run.stderr, f"occtrack track: error: {out}: no space left on device; "
                             f"free some space or write to another disk")
        assert sorted(p.name for p in disk.iterdir()) == (["result.txt"] if old else [])
        if old:
            assert out.read_text() == "the old, complete result\n"


# --- a folder one cannot write in ------------------------------------------------------------

def _without_dac_capabilities() -> None:
    """In the child, before exec: drop the capabilities that let root read and write any
    file (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH), so that permissions bind it as they bind
    any user (what root needs to run Python, it owns)."""
    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH):
        if libc.prctl(PR_CAPBSET_DROP, capability, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), f"prctl(PR_CAPBSET_DROP, {capability}) failed")


def unsupported(reason: str) -> None:
    """Skip; but fail in CI, which runs as root where these mechanisms work."""
    if in_ci():
        pytest.fail(f"{reason}; CI must test this fault", pytrace=False)
    pytest.skip(reason)


def as_a_user() -> dict:
    """subprocess arguments under which permissions (chmod) bind: none for a user; for root,
    a child without the DAC capabilities (chmod does not stop root otherwise)."""
    if os.geteuid() != 0:
        return {}
    if sys.platform != "linux":
        unsupported("running as root, which chmod does not stop, and dropping its "
                    "capabilities needs Linux")
    return {"preexec_fn": _without_dac_capabilities}


def read_only_by_permissions(folder: Path) -> dict:
    folder.chmod(0o555)
    extra = as_a_user()
    probe = subprocess.run([sys.executable, "-c", f"open({str(folder / 'probe')!r}, 'w')"],
                           capture_output=True, text=True, **extra)
    if probe.returncode == 0:
        (folder / "probe").unlink()
        unsupported(f"chmod 0555 does not stop writes here (uid {os.geteuid()}, and "
                    f"dropping CAP_DAC_OVERRIDE did not help)")
    assert "PermissionError" in probe.stderr or "Operation not permitted" in probe.stderr
    return extra


@pytest.fixture
def folder_with_old_result(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "result.txt").write_text("the old, complete result\n")
    yield folder
    folder.chmod(0o755)


def check_refused(detections, folder: Path, extra: dict, message: str) -> None:
    old = folder / "result.txt"
    run = occtrack("track", detections, *TRACK, "-o", old, "--force", **extra)
    assert run.returncode == 1
    one_line(run.stderr, f"occtrack track: error: {old}: {message}")
    new = folder / "new.txt"
    run = occtrack("track", detections, *TRACK, "-o", new, **extra)
    assert run.returncode == 1
    one_line(run.stderr, f"occtrack track: error: {new}: {message}")
    assert sorted(p.name for p in folder.iterdir()) == ["result.txt"]
    assert old.read_text() == "the old, complete result\n"


def test_a_folder_without_write_permission(detections, folder_with_old_result):
    extra = read_only_by_permissions(folder_with_old_result)
    check_refused(detections, folder_with_old_result, extra,
                  "permission denied; check the permissions of the file and its folder")


def test_a_read_only_disk(detections, folder_with_old_result, tmp_path):
    view = tmp_path / "view"
    view.mkdir()
    with mounted(view, "--bind", str(folder_with_old_result)):
        remount = subprocess.run(["mount", "-o", "remount,bind,ro", str(view)],
                                 capture_output=True, text=True)
        if remount.returncode != 0:
            pytest.skip(f"cannot make a bind mount read-only: {remount.stderr.strip()}")
        check_refused(detections, view, {}, "read-only file system; write to a writable folder")


def test_an_input_without_read_permission(detections, tmp_path):
    det = tmp_path / "det.txt"
    shutil.copy(detections, det)
    det.chmod(0o000)
    extra = as_a_user()
    out = tmp_path / "result.txt"
    run = occtrack("track", det, *TRACK, "-o", out, **extra)
    if run.returncode == 0 and os.geteuid() == 0:
        unsupported("running as root, and dropping CAP_DAC_READ_SEARCH did not stop the read")
    assert run.returncode == 1
    one_line(run.stderr, f"occtrack track: error: {det}: permission denied; check the "
                         f"permissions of the file and its folder")
    assert not out.exists() and partial_files(tmp_path) == []


def test_the_check_comes_before_the_work(detections, folder_with_old_result, tmp_path):
    """A folder one cannot write in stops the run before the tracking, not hours later: the
    refusal does not read the detections (here a FIFO nobody writes to, which would block)."""
    extra = read_only_by_permissions(folder_with_old_result)
    fifo = tmp_path / "det.txt"
    os.mkfifo(fifo)
    run = occtrack("track", fifo, *TRACK, "-o", folder_with_old_result / "new.txt",
                   timeout=60, **extra)
    assert run.returncode == 1 and "permission denied" in run.stderr


# --- Ctrl-C while the output is being written ------------------------------------------------

def pictures_with_a_fifo(folder: Path, frames: int, blocked: int) -> Path:
    """Frames 1..frames as PNG pictures of a walking person, with a FIFO in place of picture
    `blocked`: a reader blocks there until someone writes to it. Returns the detection file."""
    iio = pytest.importorskip("imageio.v3", reason='needs pip install "occtrack[viz]"')
    import numpy as np

    images = folder / "img1"
    images.mkdir(parents=True)
    rows = []
    for k in range(1, frames + 1):
        left = 40 + 4 * k
        if k == blocked:
            os.mkfifo(images / f"{k:06d}.png")
        else:
            image = np.full((H, W, 3), 130, np.uint8)
            image[60:150, left:left + 30] = 40
            iio.imwrite(images / f"{k:06d}.png", image)
        rows.append(f"{k},-1,{left},60,30,90,0.95\n")
    (folder / "det.txt").write_text("".join(rows))
    return folder / "det.txt"


def open_when_read(fifo: Path, process: subprocess.Popen, seconds: float = 120.0) -> int:
    """Wait until `process` opens `fifo` to read it, and return our writing end, which we
    hold open without writing: the reader stays blocked. Returns once the reader sleeps in
    its read: a SIGINT that came earlier, between its open and its read, would only be marked
    by Python's handler (which runs between bytecodes) and the read would block for good."""
    deadline = time.monotonic() + seconds
    while True:
        try:
            fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            break
        except OSError as err:
            assert err.errno == errno.ENXIO, err  # no reader yet
        if process.poll() is not None:
            out, err = process.communicate()
            pytest.fail(f"the run ended (status {process.returncode}) before reading the FIFO:"
                        f"\n{out}{err}")
        assert time.monotonic() < deadline, "the run never reached the FIFO"
        time.sleep(0.01)
    while not sleeping(process.pid):
        assert time.monotonic() < deadline, "the run never blocked in its read"
        time.sleep(0.001)
    return fd


def sleeping(pid: int) -> bool:
    """Whether the main thread of `pid` sleeps (waits in a system call); without /proc (not
    Linux), True after a pause long enough for the reader to reach its read."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        time.sleep(0.5)
        return True
    return stat.rsplit(")", 1)[1].split()[0] == "S"


ENDINGS = {"SIGINT": (130, "interrupted"), "SIGTERM": (143, "terminated (SIGTERM)"),
           "SIGHUP": (129, "terminated (SIGHUP)")}


@pytest.mark.parametrize("sig", list(ENDINGS))
@pytest.mark.parametrize("old", [True, False], ids=["old-file", "no-file"])
def test_a_signal_mid_write_leaves_the_old_file_or_none(tmp_path, old, sig):
    """Ctrl-C, SIGTERM (a scheduler's or `kill`'s) and SIGHUP (the terminal closed) each end
    the run with its own status, and none leaves the hidden temporary file behind."""
    pytest.importorskip("PIL", reason='needs pip install "occtrack[viz]"')
    pytest.importorskip("av", reason='needs pip install "occtrack[viz]"')
    det = pictures_with_a_fifo(tmp_path / "SEQ", frames=8, blocked=5)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = out_dir / "tracks.mp4"
    if old:
        out.write_bytes(b"the old, complete video")
    # Ctrl-C as a terminal gives it: a suite started in the background of a non-interactive
    # shell has SIGINT ignored, a child would inherit that, and Python would install no
    # KeyboardInterrupt for it. A handled signal is reset to its default in the child.
    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        process = subprocess.Popen(
            [sys.executable, "-m", "occtrack", "render", str(det), "--images",
             str(tmp_path / "SEQ" / "img1"), "--fps", "10", "-o", str(out), "--force",
             "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    finally:
        signal.signal(signal.SIGINT, handler)
    fd = open_when_read(tmp_path / "SEQ" / "img1" / "000005.png", process)
    try:
        # Frames 1-4 are in the video writer, whose temporary file is open beside the output.
        assert len(partial_files(out_dir)) == 1
        process.send_signal(getattr(signal, sig))
        stdout, stderr = process.communicate(timeout=60)
    finally:
        os.close(fd)
        if process.poll() is None:
            process.kill()
    status, said = ENDINGS[sig]
    assert process.returncode == status and stdout == ""
    one_line(stderr, f"occtrack render: {said}; output files are left as they were")
    assert partial_files(out_dir) == []
    if old:
        assert sorted(p.name for p in out_dir.iterdir()) == ["tracks.mp4"]
        assert out.read_bytes() == b"the old, complete video"
    else:
        assert list(out_dir.iterdir()) == []


def test_sigterm_during_simulate_lidar_leaves_no_partial_files(tmp_path):
    """`simulate lidar` streams three files at once; a SIGTERM while they are being written
    removes all three temporary files (issue 38, kind 4)."""
    out = tmp_path / "scene"
    process = subprocess.Popen([sys.executable, "-m", "occtrack", "simulate", "lidar", "-o",
                                str(out), "--scans", "1000000", "--quiet"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (out.is_dir() and partial_files(out)):
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no temporary file appeared"
            time.sleep(0.05)
        process.send_signal(signal.SIGTERM)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 143, stderr
    one_line(stderr, "occtrack simulate: terminated (SIGTERM); output files are left as they")
    assert partial_files(out) == []
