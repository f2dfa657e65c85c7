"""Outputs are written whole or not at all, and never over one of the run's inputs."""

from __future__ import annotations

import errno
import os

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io import atomic
from occtrack.io.atomic import atomic_path, atomic_write, check_output
from occtrack.io.mot import read_mot, write_mot

ROWS = (np.array([1, 2, 3]), np.array([7, 7, 7]), np.array([[1.0, 2, 3, 4]] * 3))


def leftovers(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial" in p.name)


class FullDisk:
    """A file whose writes fail with ENOSPC once `room` characters are written."""

    def __init__(self, fh, room: int):
        self.fh, self.room = fh, room

    def write(self, text: str) -> int:
        if len(text) > self.room:
            self.fh.write(text[:self.room])
            self.fh.flush()
            raise OSError(errno.ENOSPC, "No space left on device")
        self.room -= len(text)
        return self.fh.write(text)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.fh.close()


@pytest.fixture
def full_disk(monkeypatch):
    """Every file atomic_write opens runs out of space after 30 characters."""
    monkeypatch.setattr(atomic, "open", lambda *a, **k: FullDisk(open(*a, **k), 30),
                        raising=False)


def test_failed_write_leaves_the_old_file_and_no_partial_one(tmp_path, full_disk):
    path = tmp_path / "result.txt"
    path.write_text("the old, complete result\n")
    with pytest.raises(OSError) as err:
        write_mot(path, *ROWS, overwrite=True)
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(path)
    assert path.read_text() == "the old, complete result\n"
    assert leftovers(tmp_path) == []


def test_failed_first_write_leaves_no_file(tmp_path, full_disk):
    with pytest.raises(OSError):
        write_mot(tmp_path / "result.txt", *ROWS)
    assert list(tmp_path.iterdir()) == []


def test_interrupt_midway_leaves_the_old_file(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old\n")
    with pytest.raises(KeyboardInterrupt), atomic_write(path, overwrite=True) as fh:
        fh.write("half of the new")
        raise KeyboardInterrupt
    assert path.read_text() == "old\n" and leftovers(tmp_path) == []


def test_complete_write_replaces_and_keeps_permissions(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old\n")
    path.chmod(0o640)
    write_mot(path, *ROWS, overwrite=True)
    assert len(read_mot(path, "result")) == 3
    assert path.stat().st_mode & 0o777 == 0o640
    assert leftovers(tmp_path) == []


def test_refuses_an_existing_file_even_if_it_appears_meanwhile(tmp_path):
    path = tmp_path / "out.txt"
    with pytest.raises(OcctrackError, match="exists already"):
        with atomic_write(path) as fh:
            fh.write("new\n")
            path.write_text("written by someone else meanwhile\n")
    assert path.read_text() == "written by someone else meanwhile\n"
    assert leftovers(tmp_path) == []


def test_writes_through_a_symlink(tmp_path):
    real = tmp_path / "real.txt"
    real.write_text("old\n")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    with atomic_write(link, overwrite=True) as fh:
        fh.write("new\n")
    assert link.is_symlink() and real.read_text() == "new\n"


def test_temporary_name_keeps_the_suffix(tmp_path):
    with atomic_path(tmp_path / "figure.png") as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".png" and tmp.exists()
        tmp.write_bytes(b"png")
    assert (tmp_path / "figure.png").read_bytes() == b"png"


def test_dash_is_standard_output(capsys):
    write_mot("-", *ROWS)
    assert capsys.readouterr().out.splitlines()[0] == "1,7,1.00,2.00,3.00,4.00,1.0000,-1,-1,-1"


def test_check_output_refuses_inputs_folders_and_missing_folders(tmp_path):
    source = tmp_path / "det.txt"
    source.write_text("1,-1,0,0,1,1,1\n")
    with pytest.raises(OcctrackError, match="is also an input"):
        check_output(source, overwrite=True, inputs=[source])
    os.symlink(source, tmp_path / "alias.txt")
    with pytest.raises(OcctrackError, match="is also an input"):
        check_output(tmp_path / "alias.txt", overwrite=True, inputs=[None, source])
    with pytest.raises(OcctrackError, match="is a folder"):
        check_output(tmp_path, overwrite=True)
    with pytest.raises(OcctrackError, match="folder does not exist"):
        check_output(tmp_path / "no" / "out.txt")
    assert check_output(tmp_path / "new.txt", inputs=[source]) == tmp_path / "new.txt"
    assert check_output("-", inputs=[source]) is None


def test_failed_figure_leaves_the_old_picture(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from occtrack.viz.output import save

    path = tmp_path / "fig.png"
    path.write_bytes(b"old picture")
    fig = plt.figure()

    def half_then_fail(target, **kwargs):
        with open(target, "wb") as fh:
            fh.write(b"\x89PNG half")
        raise OSError(errno.ENOSPC, "No space left on device")

    fig.savefig = half_then_fail
    with pytest.raises(OSError) as err:
        save(fig, path, overwrite=True)
    assert err.value.filename == str(path)
    assert path.read_bytes() == b"old picture" and leftovers(tmp_path) == []
    assert not plt.fignum_exists(fig.number)


def test_a_folder_one_cannot_write_in_is_refused_up_front_naming_the_output(tmp_path,
                                                                            monkeypatch):
    """tests/test_faults.py makes the folder read-only for real; here the refusal is checked
    wherever the tests run (root ignores chmod)."""
    def denied(target):
        raise PermissionError(errno.EACCES, "Permission denied",
                              str(target.with_name(".out.1234.partial.txt")))

    monkeypatch.setattr(atomic, "_temporary", denied)
    with pytest.raises(PermissionError) as err:
        check_output(tmp_path / "out.txt")
    assert err.value.filename == str(tmp_path / "out.txt")
    # the folder turned read-only between the check and the write
    monkeypatch.setattr(atomic, "_probe", lambda target: None)
    with pytest.raises(PermissionError) as err, atomic_write(tmp_path / "out.txt") as fh:
        fh.write("never written")
    assert err.value.filename == str(tmp_path / "out.txt")
    assert list(tmp_path.iterdir()) == []
