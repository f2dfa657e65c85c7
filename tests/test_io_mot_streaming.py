"""Reading a MOTChallenge file streams it (issue 38, kind 3): the table is the same whatever
the line endings, whether the file is a regular one (arrays allocated once at the counted
length) or a pipe (grown as rows come), across chunk boundaries, and an error past a chunk
boundary still names its line."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io import mot

ROWS = mot.CHUNK + 1234  # past one chunk


def _text(rows: int = ROWS, newline: str = "\n") -> str:
    rng = np.random.default_rng(3)
    box = rng.uniform(0, 500, (rows, 4)).round(2)
    return newline.join(f"{1 + i // 7},-1,{b[0]},{b[1]},{b[2]},{b[3]},{(i % 100) / 100}"
                        for i, b in enumerate(box)) + newline


def _same(a: mot.MotTable, b: mot.MotTable) -> None:
    for name in ("frame", "id", "box", "score", "cls", "visibility", "line"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_line_endings_give_one_table(tmp_path, newline):
    unix = tmp_path / "unix.txt"
    unix.write_text(_text(), newline="")
    other = tmp_path / "other.txt"
    other.write_text(_text(newline=newline), newline="")
    table = mot.read_mot(unix, "det")
    assert len(table) == ROWS and table.line[-1] == ROWS and table.frame[-1] == 1 + (ROWS - 1) // 7
    _same(table, mot.read_mot(other, "det"))


def test_a_pipe_reads_as_the_file_does(tmp_path):
    path = tmp_path / "det.txt"
    path.write_text(_text())
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)

    def feed():
        with open(fifo, "w") as fh:
            fh.write(path.read_text())

    writer = threading.Thread(target=feed)
    writer.start()
    try:
        piped = mot.read_mot(fifo, "det")
    finally:
        writer.join(timeout=60)
    table = mot.read_mot(path, "det")
    _same(piped, mot.MotTable(table.frame, table.id, table.box, table.score, table.cls,
                              table.visibility, str(fifo), table.line))


def test_blank_lines_keep_the_line_numbers(tmp_path):
    path = tmp_path / "det.txt"
    path.write_text("\n\n" + _text(5) + "\n\n")
    table = mot.read_mot(path, "det")
    assert len(table) == 5 and list(table.line) == [3, 4, 5, 6, 7]


def test_an_error_after_a_chunk_names_its_line(tmp_path):
    lines = _text().splitlines()
    lines[mot.CHUNK + 10] = "9,-1,1,2,3,nan,1"
    path = tmp_path / "det.txt"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(OcctrackError, match=f"det.txt:{mot.CHUNK + 11}: column 6 is nan"):
        mot.read_mot(path, "det")


@pytest.mark.parametrize("kind", ["det", "gt", "result"])
def test_numpy_reads_a_chunk_as_the_row_reader_does(tmp_path, monkeypatch, kind):
    """The C parser's fast path and `_row` give the same table, on rows of every width and
    with values each column's rules treat apart (a fractional class in a detection file, 3.0
    as a frame, negative ids in results, exponents, whitespace separation)."""
    rows = ["1,-1,10,20,30,40", "2.0,-1,1e1,2E1,30.5,40,0.5", "3,7,1,2,3,4,0.9,2.5,0.3",
            "4,-5,1,2,3,4,1,-1,-1,99,hello", "5 3 1 2 3 4 0.25 1 1"]
    if kind != "det":  # a fractional class is an error there (test_io_mot)
        rows = [r for r in rows if "2.5" not in r]
    for name, text in (("mixed", rows), ("uniform", [f"{f},{f % 5},1,2,3,4,0.5,1,0.75"
                                                     for f in range(1, 200)])):
        path = tmp_path / f"{name}.txt"
        path.write_text("\n".join(text) + "\n")
        fast = mot.read_mot(path, kind)
        monkeypatch.setattr(mot, "_fast_chunk", lambda *a: None)
        slow = mot.read_mot(path, kind)
        monkeypatch.undo()
        _same(fast, slow)
