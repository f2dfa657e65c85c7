"""MOTChallenge files: read as TrackEval reads them, bad rows named by file and line."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.mot import (
    MotTable,
    check_gaps,
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
    assert warning == (f"{tmp_path / 'f.txt'}: skipped 1 boxes wholly outside the 640x480 image "
                       f"(first at line 4; check the image size if that is many); skipped 1 rows "
                       f"with a zero or negative size or a coordinate beyond 1e+06 px (first at "
                       f"line 2); clipped 2 scores to [0, 1] (first at line 3)")


@pytest.mark.parametrize("row", ["1,-1,700,10,20,50,0.9", "1,-1,-30,10,20,50,0.9",
                                 "1,-1,10,480,20,50,0.9", "1,-1,10,-50,20,50,0.9"])
def test_boxes_wholly_outside_the_image_are_skipped_with_a_count(tmp_path, row):
    """Real detectors report boxes beyond the border: skipped and counted, never a stop; a box
    partly outside is kept."""
    text = f"1,-1,1,1,20,50,0.5\n{row}\n2,-1,630,470,20,50,0.5\n{row}\n"
    table, warning = detections(tmp_path, text)
    assert table.line.tolist() == [1, 3]
    assert warning == (f"{tmp_path / 'f.txt'}: skipped 2 boxes wholly outside the 640x480 "
                       f"image (first at line 2; check the image size if that is many)")
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


# -- what the mutation run of io/mot.py showed untested (benchmarks/mutation.py --modules io-mot)


def test_trailing_empty_columns_blank_lines_and_a_bom_are_not_rows(tmp_path):
    """TrackEval's files may end rows with empty columns ("...,0.9,,,"), hold blank lines
    anywhere and start with a byte-order mark: none of these is data, and no row after a
    blank line is lost; lines keep their numbers in the file."""
    text = ("\ufeff1,-1,0,0,5,5,0.9,,,\n"
            "\n"
            "  \n"
            "2,-1,1,0,5,5,0.8,,\n"
            "3,-1,2,0,5,5,,\n"
            "4,-1,3,0,5,5,0.7,-1,-1,not-a-number, neither\n")
    table = read_mot(write(tmp_path, text), "det")
    assert table.frame.tolist() == [1, 2, 3, 4] and table.line.tolist() == [1, 4, 5, 6]
    assert table.score.tolist() == [0.9, 0.8, 1.0, 0.7]  # no score column: 1
    assert table.box[:, 0].tolist() == [0, 1, 2, 3]


def test_only_a_leading_byte_order_mark_is_dropped(tmp_path):
    with pytest.raises(OcctrackError, match=r"f.txt:1: column 1 is not a number: 'X1'"):
        read_mot(write(tmp_path, "X1,-1,0,0,5,5,1\n"), "det")
    with pytest.raises(OcctrackError, match=r"f.txt:1: column 7 is not a number"):
        read_mot(write(tmp_path, "1,-1,0,0,5,5,1\ufeff\n"), "det")


def test_a_short_row_is_quoted_by_its_first_60_characters(tmp_path):
    line = "1 " + "x" * 80
    with pytest.raises(OcctrackError) as err:
        read_mot(write(tmp_path, line + "\n"), "det")
    assert str(err.value) == (f"{tmp_path / 'f.txt'}:1: expected at least 6 columns (frame, id, "
                              f"left, top, width, height), found 2: {line[:60]!r}")


def test_a_directory_and_a_binary_file_are_named(tmp_path):
    with pytest.raises(OcctrackError) as err:
        read_mot(tmp_path, "gt")
    assert str(err.value) == f"{tmp_path}: is a directory, expected a MOTChallenge text file"
    binary = tmp_path / "b.txt"
    binary.write_bytes(b"1,-1,0,0,5,5,1\n\xff\xfe1,2")
    with pytest.raises(OcctrackError) as err:
        read_mot(binary, "det")
    assert str(err.value) == f"{binary}: not a text file (byte 15 is not UTF-8)"


def test_a_bad_kind_is_a_programming_error():
    with pytest.raises(ValueError, match=r"kind must be one of \('det', 'gt', 'result'\)"):
        read_mot("x.txt", "detections")


def test_zero_and_small_boxes_are_read_but_negative_ones_named(tmp_path):
    """read_mot refuses only negative sizes (ground truth may hold empty boxes); the message
    gives width x height."""
    table = read_mot(write(tmp_path, "1,1,0,0,0,0,1,1,1\n1,2,0,0,0.5,0.5,1,1,1\n"), "gt")
    assert table.box[:, 2:].tolist() == [[0, 0], [0.5, 0.5]]
    with pytest.raises(OcctrackError) as err:
        read_mot(write(tmp_path, "1,1,0,0,5,5,1,1,1\n2,1,0,0,7,-3,1,1,1\n"), "gt")
    assert str(err.value) == f"{tmp_path / 'f.txt'}:2: negative box size 7 x -3"


def test_duplicate_gt_id_names_both_lines(tmp_path):
    path = write(tmp_path, "2,4,0,0,5,5,1,1,1\n1,4,0,0,5,5,1,1,1\n2,4,3,3,5,5,1,1,1\n")
    with pytest.raises(OcctrackError) as err:
        read_mot(path, "gt")
    assert str(err.value) == f"{path}:3: id 4 appears twice in frame 2 (lines 1 and 3)"


def test_a_detection_files_class_column_is_free(tmp_path):
    """read_detections reads a detection file: its unused class column may hold anything
    numeric, as read_mot(..., "det") allows."""
    table, warning = detections(tmp_path, "1,-1,1,1,20,50,0.5,12.75,3.5\n")
    assert table.cls.tolist() == [-1] and warning is None


@pytest.mark.parametrize("box,kept", [
    ((10, 10, 0.5, 0.5), True),  # small but positive
    ((10, 10, 20, 0), False),  # zero height
    ((-20, 10, 20, 50), False),  # right edge on the image's left border
    ((-19.5, 10, 20, 50), True),
    ((10, -50, 20, 50), False),  # bottom edge on the top border
    ((10, -49.5, 20, 50), True),
    ((640, 10, 20, 50), False),  # left edge on the right border
    ((639.5, 10, 20, 50), True),
    ((10, 480, 20, 50), False),  # top edge on the bottom border
    ((10, 479.5, 20, 50), True),
])
def test_a_box_needs_a_positive_size_and_some_area_inside_the_image(tmp_path, box, kept):
    row = "1,-1," + ",".join(f"{v:g}" for v in box) + ",0.9\n"
    table, warning = detections(tmp_path, row, lenient=True)
    assert (len(table) == 1) == kept and (warning is None) == kept
    if kept:
        assert detections(tmp_path, row)[0].box.tolist() == [list(box)]
    elif box[2] > 0 and box[3] > 0:  # wholly outside: skipped with a count, lenient or not
        table, strict_warning = detections(tmp_path, row)
        assert len(table) == 0 and strict_warning == warning
        assert "skipped 1 boxes wholly outside" in warning
    else:
        with pytest.raises(OcctrackError, match="f.txt:1: box "):
            detections(tmp_path, row)


def test_select_keeps_every_column(tmp_path):
    table = read_mot(write(tmp_path, "1,1,0,0,5,5,1,1,0.5\n2,2,9,9,5,5,0,7,0.25\n"), "gt")
    two = table.select(np.array([False, True]))
    assert (two.frame.tolist(), two.id.tolist(), two.cls.tolist()) == ([2], [2], [7])
    assert two.box.tolist() == [[9, 9, 5, 5]] and two.score.tolist() == [0.0]
    assert two.visibility.tolist() == [0.25] and two.line.tolist() == [2]
    assert two.path == table.path
    bare = MotTable(table.frame, table.id, table.box, table.score, table.cls, table.visibility)
    assert bare.select(np.array([True, False])).line is None


def test_gaps_at_their_limits(tmp_path):
    """max_gap_frames empty frames are allowed, one more is not: before the first row, between
    rows and at the end; the message counts them."""
    assert len(read_mot(write(tmp_path, "11,-1,0,0,5,5,1\n22,-1,0,0,5,5,1\n"), "det",
                        max_gap_frames=10)) == 2
    with pytest.raises(OcctrackError) as err:
        read_mot(write(tmp_path, "12,-1,0,0,5,5,1\n"), "det", max_gap_frames=10)
    assert str(err.value).startswith(f"{tmp_path / 'f.txt'}:1: the first row is in frame 12, "
                                     f"after 11 empty frames: more than the 10 allowed")
    with pytest.raises(OcctrackError) as err:
        read_mot(write(tmp_path, "1,-1,0,0,5,5,1\n13,-1,0,0,5,5,1\n"), "det", max_gap_frames=10)
    assert str(err.value).startswith(f"{tmp_path / 'f.txt'}:2: frame 13 follows frame 1 after "
                                     f"11 empty frames: more than the 10 allowed")
    row = "60,-1,1,1,20,50,0.5\n"
    assert len(detections(tmp_path, row, max_gap_frames=59, num_frames=119)[0]) == 1
    with pytest.raises(OcctrackError) as err:
        detections(tmp_path, row, max_gap_frames=59, num_frames=120)
    assert str(err.value).startswith(
        f"{tmp_path / 'f.txt'}: the last row is in frame 60 but the sequence has 120 frames "
        f"(seqinfo.ini): 60 empty frames at the end, more than the 59 allowed")


def test_gaps_of_a_table_not_read_from_a_file():
    """A table built in memory (no path, no line numbers) is checked all the same."""
    table = MotTable(np.array([1, 50]), np.array([1, 1]), np.ones((2, 4)), np.ones(2),
                     np.ones(2, dtype=np.int64), np.ones(2))
    with pytest.raises(OcctrackError) as err:
        check_gaps(table, 10)
    assert str(err.value).startswith("frame 50 follows frame 1 after 48 empty frames")
    late = MotTable(np.array([30]), np.array([1]), np.ones((1, 4)), np.ones(1),
                    np.ones(1, dtype=np.int64), np.ones(1))
    with pytest.raises(OcctrackError) as err:
        check_gaps(late, 10)
    assert str(err.value).startswith("the first row is in frame 30, after 29 empty frames")
    check_gaps(late, 29)


def test_write_keeps_the_scores(tmp_path):
    path = tmp_path / "out.txt"
    write_mot(path, np.array([1, 1]), np.array([2, 1]), np.ones((2, 4)),
              score=np.array([0.25, 0.125]))
    assert [line.split(",")[6] for line in path.read_text().splitlines()] == ["0.1250", "0.2500"]


def seqinfo(folder, body):
    folder.mkdir(exist_ok=True)
    (folder / "seqinfo.ini").write_text(f"[Sequence]\n{body}", encoding="utf-8")
    return folder / "seqinfo.ini"


def test_seqinfo_defaults_name_and_frame_rate(tmp_path):
    seqinfo(tmp_path / "MOT17-09", "imWidth=1\nimHeight=2147483647\nseqLength=3\n")
    assert read_seqinfo(tmp_path / "MOT17-09") == {"name": "MOT17-09", "width": 1,
                                                   "height": 2147483647, "length": 3, "fps": 30}
    seqinfo(tmp_path / "a", "name=S\nimWidth=640\nimHeight=480\nseqLength=9\nframeRate=14\n")
    assert read_seqinfo(tmp_path / "a")["fps"] == 14


@pytest.mark.parametrize("body,message", [
    ("imWidth=0\nimHeight=480\nseqLength=9\n", "width 0 is not a positive whole number"),
    ("imWidth=640\nimHeight=2147483648\nseqLength=9\n",
     "height 2147483648 is not a positive whole number below 2**31"),
    ("imWidth=640\nimHeight=480\nseqLength=-1\n", "length -1 is not a positive"),
    ("imWidth=640\nimHeight=480\nseqLength=9\nframeRate=0.5\n", "fps 0 is not a positive"),
    ("imWidth=640\nimHeight=480\n", "malformed seqinfo.ini: 'seqLength'"),
    ("imHeight=480\nseqLength=9\n", "malformed seqinfo.ini: 'imWidth'"),
    ("imWidth=640\nseqLength=9\n", "malformed seqinfo.ini: 'imHeight'"),
    ("imWidth=640\nimHeight=480\nseqLength=many\n", "malformed seqinfo.ini: invalid literal"),
])
def test_malformed_seqinfo_is_named(tmp_path, body, message):
    ini = seqinfo(tmp_path, body)
    with pytest.raises(OcctrackError) as err:
        read_seqinfo(tmp_path)
    assert str(err.value).startswith(f"{ini}: malformed seqinfo.ini: ") and message in str(
        err.value)


def test_missing_seqinfo_is_named(tmp_path):
    with pytest.raises(OcctrackError) as err:
        read_seqinfo(tmp_path)
    assert str(err.value) == f"{tmp_path / 'seqinfo.ini'}: no seqinfo.ini here"


def test_files_are_read_as_utf8_whatever_the_locale(tmp_path):
    """Under the C locale without UTF-8 mode, Python's default encoding is ASCII: a detection
    file with a byte-order mark and a seqinfo.ini with a non-ASCII name must still read."""
    (tmp_path / "det.txt").write_bytes("\ufeff1,-1,0,0,5,5,0.9\n".encode())
    seqinfo(tmp_path, "name=Straße\nimWidth=640\nimHeight=480\nseqLength=9\n")
    # as read here (whatever this process's locale), and as read under the C locale below
    assert len(read_mot(tmp_path / "det.txt", "det")) == 1
    assert read_seqinfo(tmp_path)["name"] == "Straße"
    script = ("import locale, sys\n"
              "from occtrack.io.mot import read_mot, read_seqinfo\n"
              "print(locale.getpreferredencoding(False))\n"
              "print(len(read_mot(sys.argv[1] + '/det.txt', 'det')))\n"
              "print(ascii(read_seqinfo(sys.argv[1])['name']))\n")
    env = {**os.environ, "LC_ALL": "C", "LANG": "C", "PYTHONCOERCECLOCALE": "0",
           "PYTHONUTF8": "0"}
    done = subprocess.run([sys.executable, "-X", "utf8=0", "-c", script, str(tmp_path)],
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    encoding, rows, name = done.stdout.split()
    assert encoding.lower().replace("-", "").replace("_", "") != "utf8"  # the premise
    assert (rows, name) == ("1", ascii("Straße"))


def test_class_and_visibility_columns_when_present(tmp_path):
    """Eight columns: the class without a visibility (-1); seven: neither. A detection file's
    class is kept when it is a whole number in the id range, whatever the visibility."""
    gt = read_mot(write(tmp_path, "1,1,0,0,5,5,1,7\n1,2,0,0,5,5,0\n1,3,0,0,5,5,1,2,0.5\n"), "gt")
    assert gt.cls.tolist() == [7, -1, 2] and gt.visibility.tolist() == [-1.0, -1.0, 0.5]
    det = read_mot(write(tmp_path, "1,-1,0,0,5,5,0.9,3\n"
                                   "1,-1,0,0,5,5,0.9,3,0.5\n"
                                   "1,-1,0,0,5,5,0.9,5,3e10\n"
                                   "1,-1,0,0,5,5,0.9,-2147483648,1\n"
                                   "1,-1,0,0,5,5,0.9,2147483647,1\n"
                                   "1,-1,0,0,5,5,0.9,2147483648,1\n", "d.txt"), "det")
    assert det.cls.tolist() == [3, 3, 5, -2147483648, 2147483647, -1]
    assert det.visibility.tolist() == [-1.0, 0.5, 3e10, 1.0, 1.0, 1.0]


def test_a_fractional_class_of_ground_truth_is_named_by_line(tmp_path):
    path = write(tmp_path, "1,1,0,0,5,5,1,1,1\n1,2,0,0,5,5,1,1.5,1\n")
    with pytest.raises(OcctrackError) as err:
        read_mot(path, "gt")
    assert str(err.value) == f"{path}:2: class 1.5 is not a whole number"


def test_an_empty_file_gives_empty_integer_columns(tmp_path):
    """No rows: the columns keep their types, so frame and line numbers still index and
    count (np.bincount refuses float arrays)."""
    table = read_mot(write(tmp_path, "\n"), "gt")
    assert len(table) == 0 and table.num_frames == 0 and table.box.shape == (0, 4)
    for column in (table.frame, table.id, table.cls, table.line):
        assert column.dtype == np.int64
    assert np.bincount(table.frame).tolist() == [] and table.frame_slices(2)[1].tolist() == []
