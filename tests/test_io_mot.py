"""MOTChallenge files: read as TrackEval reads them, bad rows named by file and line."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.mot import read_mot, read_seqinfo, write_mot


def write(tmp_path, text, name="f.txt"):
    path = tmp_path / name
    path.write_bytes(text.encode())
    return path


def test_reads_crlf_float_ids_and_extra_columns(tmp_path):
    path = write(tmp_path, "1,1.0,10,20,30,40,0.9,-1,-1,-1,extra\r\n"
                           "2,3.0,11,21,31,41,0.8,-1,-1,-1\r\n\r\n")
    table = read_mot(path, "result")
    assert table.frame.tolist() == [1, 2]
    assert table.id.tolist() == [1, 3]
    np.testing.assert_array_equal(table.box[1], [11, 21, 31, 41])
    assert table.score.tolist() == [0.9, 0.8]


def test_gt_columns_and_frame_slices(tmp_path):
    path = write(tmp_path, "2,1,0,0,5,5,1,1,0.5\n1,1,0,0,5,5,0,7,1.0\n2,2,9,9,5,5,1,2,0.2\n")
    table = read_mot(path, "gt")
    assert table.cls.tolist() == [1, 7, 2]
    assert table.visibility.tolist() == [0.5, 1.0, 0.2]
    slices = table.frame_slices(3)
    assert [s.tolist() for s in slices] == [[1], [0, 2], []]


@pytest.mark.parametrize("text,line,message", [
    ("1,-1,0,0,5,5,1\n1,-1,0,0,5\n", 2, "expected at least 6 columns"),
    ("1,-1,0,0,5,5,1\n2,-1,a,0,5,5,1\n", 2, "column 3 is not a number"),
    ("1,-1,0,0,nan,5,1\n", 1, "column 5 is nan"),
    ("1,-1,0,0,-5,5,1\n", 1, "negative box size"),
    ("0,-1,0,0,5,5,1\n", 1, "below 1"),
])
def test_bad_rows_are_named(tmp_path, text, line, message):
    path = write(tmp_path, text)
    with pytest.raises(OcctrackError) as err:
        read_mot(path, "det")
    assert str(err.value).startswith(f"{path}:{line}: ")
    assert message in str(err.value)


def test_duplicate_gt_id_in_a_frame(tmp_path):
    path = write(tmp_path, "1,4,0,0,5,5,1,1,1\n1,4,3,3,5,5,1,1,1\n")
    with pytest.raises(OcctrackError, match="id 4 appears twice in frame 1"):
        read_mot(path, "gt")


def test_missing_file(tmp_path):
    with pytest.raises(OcctrackError, match="no such file"):
        read_mot(tmp_path / "nope.txt")


def test_write_refuses_to_overwrite(tmp_path):
    path = tmp_path / "out.txt"
    args = (np.array([2, 1]), np.array([5, 7]), np.array([[1.0, 2, 3, 4], [5, 6, 7, 8]]))
    write_mot(path, *args)
    assert path.read_text().splitlines() == ["1,7,5.00,6.00,7.00,8.00,1.0000,-1,-1,-1",
                                             "2,5,1.00,2.00,3.00,4.00,1.0000,-1,-1,-1"]
    with pytest.raises(OcctrackError, match="exists already"):
        write_mot(path, *args)
    write_mot(path, *args, overwrite=True)


def test_seqinfo(tmp_path):
    (tmp_path / "seqinfo.ini").write_text("[Sequence]\nname=S\nimWidth=640\nimHeight=480\n"
                                          "seqLength=9\nframeRate=30\n")
    assert read_seqinfo(tmp_path) == {"name": "S", "width": 640, "height": 480, "length": 9,
                                      "fps": 30}
    (tmp_path / "seqinfo.ini").write_text("[Sequence]\nname=S\n")
    with pytest.raises(OcctrackError, match="malformed seqinfo.ini"):
        read_seqinfo(tmp_path)


def test_detections_in_any_frame_order_keep_every_row(tmp_path):
    text = "3,-1,0,0,5,5,1\n3,-1,9,0,5,5,0.5\n1,-1,1,0,5,5,1\n2,-1,2,0,5,5,1\n1,-1,4,0,5,5,1\n"
    table = read_mot(write(tmp_path, text), "det")
    assert len(table) == 5
    slices = table.frame_slices()
    assert [table.box[rows, 0].tolist() for rows in slices] == [[1.0, 4.0], [2.0], [0.0, 9.0]]
