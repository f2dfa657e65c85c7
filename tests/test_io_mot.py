"""MOTChallenge files: read as TrackEval reads them, bad rows named by file and line."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.mot import (
    MotTable,
    first_duplicate,
    read_detections,
    read_mot,
    read_seqinfo,
    write_mot,
)
from occtrack.metrics.protocols import check_tables


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
    ("1,-1,0,0,5,5,1\n2.5,-1,0,0,5,5,1\n", 2, "frame 2.5 is not a whole number"),
    ("1,-1,0,0,5,5,1\n1e19,-1,0,0,5,5,1\n", 2, "frame 1e19 is out of range"),
    ("1e30,-1,0,0,5,5,1\n", 1, "frame 1e30 is out of range"),
    ("2147483648,-1,0,0,5,5,1\n", 1, "frame 2147483648 is out of range"),
    ("1,1e19,0,0,5,5,1\n", 1, "id 1e19 is out of range"),
    ("1,99999999999999999999,0,0,5,5,1\n", 1, "id 99999999999999999999 is out of range"),
    ("1,3.5,0,0,5,5,1\n", 1, "id 3.5 is not a whole number"),
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


def test_integral_floats_are_whole_numbers(tmp_path):
    table = read_mot(write(tmp_path, "3.0,2.0,0,0,5,5,1,1.0,1\n2147483647,-2147483648,0,0,5,5,1\n"),
                     "gt")
    assert table.frame.tolist() == [3, 2147483647] and table.id.tolist() == [2, -2147483648]
    assert table.cls.tolist() == [1, -1] and table.line.tolist() == [1, 2]


def test_class_of_ground_truth_is_whole_but_unused_detection_columns_are_free(tmp_path):
    with pytest.raises(OcctrackError, match="class 1.5 is not a whole number"):
        read_mot(write(tmp_path, "1,1,0,0,5,5,1,1.5,1\n"), "gt")
    det = read_mot(write(tmp_path, "1,-1,0,0,5,5,0.9,12.75,3.5,0\n", "d.txt"), "det")
    assert det.cls.tolist() == [-1]


def test_gap_of_empty_frames_is_bounded(tmp_path):
    path = write(tmp_path, "1,-1,0,0,5,5,1\n5,-1,0,0,5,5,1\n1000000000,-1,0,0,5,5,1\n")
    assert len(read_mot(path, "det")) == 3
    with pytest.raises(OcctrackError) as err:
        read_mot(path, "det", max_gap_frames=10)
    assert str(err.value).startswith(f"{path}:3: frame 1000000000 follows frame 5 after "
                                     f"999999994 empty frames")
    assert "--max-gap-frames" in str(err.value)
    late = write(tmp_path, "1000,-1,0,0,5,5,1\n", "late.txt")
    with pytest.raises(OcctrackError, match=r"late.txt:1: the first row is in frame 1000"):
        read_mot(late, "det", max_gap_frames=998)
    assert len(read_mot(late, "det", max_gap_frames=999)) == 1


def detections(tmp_path, text, **kwargs):
    return read_detections(write(tmp_path, text), (640, 480), **kwargs)


@pytest.mark.parametrize("row,message", [
    ("1,-1,10,10,0,50,0.9", "box size 0 x 50: width and height must be positive; pass --lenient"),
    ("1,-1,10,10,-4,50,0.9", "box size -4 x 50"),
    ("1,-1,700,10,20,50,0.9", "lies wholly outside the 640x480 image"),
    ("1,-1,-30,10,20,50,0.9", "lies wholly outside"),
    ("1,-1,10,10,20,50,57", "score 57 is outside [0, 1] (this file's scores run from 0.5 to 57); "
                            "pass --score-range LO,HI"),
    ("1,-1,10,10,20,50,-3", "score -3 is outside [0, 1]"),
])
def test_bad_detection_rows_stop_with_the_way_out(tmp_path, row, message):
    with pytest.raises(OcctrackError) as err:
        detections(tmp_path, f"1,-1,1,1,20,50,0.5\n{row}\n")
    assert str(err.value).startswith(f"{tmp_path / 'f.txt'}:2: ") and message in str(err.value)


def test_lenient_skips_and_clips_with_one_warning(tmp_path):
    text = ("1,-1,1,1,20,50,0.5\n1,-1,10,10,0,50,0.9\n2,-1,1,1,20,50,1.7\n"
            "2,-1,900,1,20,50,0.5\n3,-1,1,1,20,50,-0.2\n")
    table, warning = detections(tmp_path, text, lenient=True)
    assert table.line.tolist() == [1, 3, 5] and table.score.tolist() == [0.5, 1.0, 0.0]
    assert warning == (f"{tmp_path / 'f.txt'}: skipped 2 rows with a zero or negative size or "
                       f"wholly outside the 640x480 image (first at line 2); clipped 2 scores "
                       f"to [0, 1] (first at line 3)")
    assert detections(tmp_path, "1,-1,1,1,20,50,0.5\n", lenient=True)[1] is None


def test_score_range_maps_raw_scores_onto_probabilities(tmp_path):
    text = "1,-1,1,1,20,50,-3\n1,-1,5,1,20,50,60\n2,-1,1,1,20,50,18\n"
    table, warning = detections(tmp_path, text, score_range=(-3.0, 60.0))
    np.testing.assert_allclose(table.score, [0.0, 1.0, 1 / 3])
    assert warning is None
    with pytest.raises(OcctrackError, match=r"f.txt:2: score 60 is outside --score-range -3,50"):
        detections(tmp_path, text, score_range=(-3.0, 50.0))


def test_detection_gap_counts_empty_frames_at_the_end(tmp_path):
    with pytest.raises(OcctrackError, match="the sequence has 100 frames"):
        detections(tmp_path, "1,-1,1,1,20,50,0.5\n", max_gap_frames=50, num_frames=100)


def test_duplicate_keys_cannot_overflow():
    big = 2**62 - 1
    frame, ids = np.array([1, 4, 8]), np.array([big, 5, 5])
    assert first_duplicate(frame, ids) is None
    table = MotTable(frame, ids, np.ones((3, 4)), np.ones(3), np.ones(3, dtype=np.int64),
                     np.ones(3))
    assert check_tables(table, table) == 8
    assert first_duplicate(np.array([8, 1, 8]), np.array([big, 5, big])) == (0, 2)
