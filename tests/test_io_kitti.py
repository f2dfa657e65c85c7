"""KITTI tracking files: read cell by cell with bad rows named by file and line, converted for
the tracker, written back in KITTI's result format, told apart from MOTChallenge files by
content, and their sequence information found in KITTI's folder layout."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.kitti import (
    TYPES,
    UNKNOWN_3D,
    detections_to_mot,
    find_seqinfo,
    layout_root,
    looks_like_kitti,
    parse_classes,
    read_kitti,
    write_kitti,
)
from occtrack.io.mot import read_seqinfo

CAR, PEDESTRIAN, PERSON, DONTCARE = (TYPES.index(n) for n in ("Car", "Pedestrian", "Person",
                                                              "DontCare"))
UNKNOWN = -1
BOX_TOL = 0.005 + 1e-9  # boxes are written with 2 decimals
SCORE_TOL = 0.00005 + 1e-12  # scores with 4
REAL_TOL = 0.0000005 + 1e-12  # alpha and the 3D columns with 6

SEQINFO = """[Sequence]
name={name}
imDir=image_02/{name}
frameRate=10
seqLength=144
imWidth=1242
imHeight=375
imExt=.png
"""


def row(frame, ident=-1, kind="Car", box=(10, 20, 50, 80), score=None, alpha=-10,
        box3d=UNKNOWN_3D):
    """One KITTI row as text: 17 columns, or 18 with a score."""
    cells = [frame, ident, kind, -1, -1, alpha, *box, *box3d]
    if score is not None:
        cells.append(score)
    return " ".join(str(c) for c in cells)


def write(tmp_path, text, name="det.txt"):
    path = tmp_path / name
    path.write_bytes(text.encode())
    return path


def corners(ltwh):
    return np.concatenate([ltwh[:, :2], ltwh[:, :2] + ltwh[:, 2:]], axis=1)


# -- reading ------------------------------------------------------------------------------


def test_columns_land_where_kitti_puts_them(tmp_path):
    text = (row(3, 7, "Pedestrian", (1.5, 2.25, 30, 90.75), 0.625, alpha=-1.25,
                box3d=(1.7, 0.6, 0.9, 2.5, 1.6, 12.0, 0.3)) + "\r\n\r\n"
            + row(1, -1, "car", (5, 6, 7, 8)) + "\n")
    table = read_kitti(write(tmp_path, text))
    assert len(table) == 2 and table.num_frames == 4
    assert table.frame.tolist() == [3, 1]  # as in the file, 0-based, any order
    assert table.id.tolist() == [7, -1]
    assert table.type.tolist() == [PEDESTRIAN, CAR]  # names matched without regard to case
    assert table.line.tolist() == [1, 3]  # the blank line counts
    np.testing.assert_array_equal(table.box, [[1.5, 2.25, 30, 90.75], [5, 6, 7, 8]])
    np.testing.assert_array_equal(table.box3d, [[1.7, 0.6, 0.9, 2.5, 1.6, 12.0, 0.3],
                                                UNKNOWN_3D])
    assert table.alpha.tolist() == [-1.25, -10]
    assert table.truncated.tolist() == [-1, -1] and table.occluded.tolist() == [-1, -1]
    assert table.score.tolist() == [0.625, 1.0]  # 17 columns: score 1
    assert table.unknown() is None


def test_empty_file_is_an_empty_table(tmp_path):
    table = read_kitti(write(tmp_path, "\n\n"))
    assert len(table) == 0 and table.num_frames == 0 and table.box.shape == (0, 4)
    mot, rows, note = detections_to_mot(table)
    assert len(mot) == 0 and len(rows) == 0 and note is None


def test_missing_file_is_named(tmp_path):
    path = tmp_path / "nope.txt"
    with pytest.raises(OcctrackError) as err:
        read_kitti(path)
    assert str(err.value) == f"{path}: no such file"


GOOD = row(0, -1, "Car", (10, 20, 50, 80), 0.9)
CELLS = GOOD.split()


def bad(col, text):
    """GOOD with column `col` (1-based) replaced by `text`."""
    cells = list(CELLS)
    cells[col - 1] = text
    return " ".join(cells)


@pytest.mark.parametrize("line,message", [
    ("1 -1 Car -1 -1 -10 10 20 50 80", "expected 17 columns"),
    ("1 -1 Car -1 -1 -10 10 20 50 80", "found 10"),
    (bad(7, "ten"), "column 7 is not a number: 'ten'"),
    (bad(15, "x"), "column 15 is not a number: 'x'"),
    (bad(18, "high"), "column 18 is not a number: 'high'"),
    (bad(1, "first"), "frame is not a number: 'first'"),
    (bad(2, "me"), "id is not a number: 'me'"),
    (bad(8, "nan"), "column 8 is nan"),
    (bad(10, "inf"), "column 10 is inf"),
    (bad(18, "-inf"), "column 18 is -inf"),
    (bad(1, "nan"), "frame nan is not a whole number"),
    (bad(1, "2.5"), "frame 2.5 is not a whole number"),
    (bad(2, "3.5"), "id 3.5 is not a whole number"),
    (bad(1, "-1"), "frame -1 is out of range"),
    (bad(1, "-1"), "KITTI frames are 0-based"),
    (bad(1, "1e19"), "frame 1e19 is out of range"),
    (bad(9, "5"), "negative box size: x1 y1 x2 y2 = 10 20 5 80"),
    (bad(9, "5"), "x2 must be at least x1"),
    (bad(10, "19.5"), "negative box size: x1 y1 x2 y2 = 10 20 50 19.5"),
    (bad(3, "1"), "column 3 should be a KITTI type name"),
    (bad(3, "1"), "found the number 1; is this a MOTChallenge file?"),
])
def test_bad_rows_are_named(tmp_path, line, message):
    path = write(tmp_path, f"{GOOD}\n\n{line}\n{GOOD}\n")
    with pytest.raises(OcctrackError) as err:
        read_kitti(path)
    assert str(err.value).startswith(f"{path}:3: ")
    assert message in str(err.value)
    assert err.value.path == str(path) and err.value.line == 3


def test_whole_floats_are_whole_numbers_and_a_zero_size_box_is_no_read_error(tmp_path):
    table = read_kitti(write(tmp_path, bad(1, "4.0").replace(" -1 Car", " 2.0 Car", 1) + "\n"
                             + row(0, box=(10, 20, 10, 20)) + "\n"))
    assert table.frame.tolist() == [4, 0] and table.id.tolist() == [2, -1]
    np.testing.assert_array_equal(table.box[1], [10, 20, 10, 20])


def test_unknown_types_are_counted_not_refused(tmp_path):
    text = "\n".join([row(0, kind="Car"), row(0, kind="Bus"), row(1, kind="DontCare"),
                      row(1, kind="Pedestrian"), row(2, kind="Ufo"), row(2, kind="Bus"),
                      row(3, kind="Person_sitting"), row(3, kind="DontCare")]) + "\n"
    path = write(tmp_path, text)
    table = read_kitti(path)
    assert len(table) == 8  # every row is read, unknown ones included
    assert table.type.tolist() == [CAR, UNKNOWN, DONTCARE, PEDESTRIAN, UNKNOWN, UNKNOWN,
                                   PERSON, DONTCARE]
    assert table.unknown_names == ("Bus", "Ufo")
    assert table.unknown() == "3 rows of a type KITTI does not know (Bus, Ufo, first at line 2)"

    mot, rows, note = detections_to_mot(table)
    assert rows.tolist() == [0, 3, 6]  # DontCare and unknown types are skipped
    assert mot.cls.tolist() == [CAR, PEDESTRIAN, PERSON]
    assert note.startswith(f"{path}: skipped ")
    assert "2 DontCare rows" in note
    assert "3 rows of a type KITTI does not know (Bus, Ufo, first at line 2)" in note
    assert "not asked for" not in note

    mot, rows, note = detections_to_mot(table, [PEDESTRIAN])
    assert rows.tolist() == [3] and mot.cls.tolist() == [PEDESTRIAN]
    assert "2 rows of classes not asked for (Car, Person)" in note
    assert "2 DontCare rows" in note and "3 rows of a type" in note


def test_detections_to_mot_converts_frames_and_boxes(tmp_path):
    text = "\n".join([row(5, 4, "Car", (10, 20, 50, 80), 0.5),
                      row(0, -1, "Cyclist", (1.5, 2.5, 3.0, 7.5))]) + "\n"
    path = write(tmp_path, text)
    mot, rows, note = detections_to_mot(read_kitti(path))
    assert note is None and rows.tolist() == [0, 1]
    assert mot.frame.tolist() == [6, 1]  # MotTable frames are 1-based
    np.testing.assert_array_equal(mot.box, [[10, 20, 40, 60], [1.5, 2.5, 1.5, 5.0]])
    assert mot.score.tolist() == [0.5, 1.0] and mot.id.tolist() == [4, -1]
    assert mot.cls.tolist() == [CAR, TYPES.index("Cyclist")]
    assert mot.line.tolist() == [1, 2] and mot.path == str(path)


def test_parse_classes():
    assert parse_classes("Car,Pedestrian") == [CAR, PEDESTRIAN]
    assert parse_classes(" pedestrian , Car,car,PEDESTRIAN, ") == [PEDESTRIAN, CAR]
    assert parse_classes("Person_sitting,Person") == [PERSON]
    assert parse_classes("Tram") == [TYPES.index("Tram")]


@pytest.mark.parametrize("text,message", [
    ("Car,Bus", "--classes: unknown class 'Bus'; choose from Car, Van, Truck, Pedestrian"),
    ("DontCare", "--classes: unknown class 'DontCare'; choose from"),
    ("Car,dontcare", "unknown class 'dontcare'"),
    ("1", "unknown class '1'"),
    ("", "--classes names no class"),
    (" , ,", "--classes names no class"),
])
def test_parse_classes_errors(text, message):
    with pytest.raises(OcctrackError) as err:
        parse_classes(text)
    assert message in str(err.value)
    choices = str(err.value).split("choose from")[-1]
    assert "Misc" in choices and "DontCare" not in choices


# -- writing and the round trip ------------------------------------------------------------


def round_trip(tmp_path, table, box3d=False, name="out.txt"):
    """read -> detections_to_mot -> write_kitti -> read: the table read back."""
    mot, rows, _ = detections_to_mot(table)
    kept = table.select(rows)
    out = tmp_path / name
    write_kitti(out, mot.frame - 1, mot.id, mot.cls, corners(mot.box), mot.score,
                kept.box3d if box3d else None, kept.alpha if box3d else None)
    return kept, read_kitti(out)


def assert_same_rows(a, b):
    assert b.frame.tolist() == a.frame.tolist()
    assert b.id.tolist() == a.id.tolist()
    assert b.type.tolist() == a.type.tolist()
    assert np.abs(b.box - a.box).max(initial=0) <= BOX_TOL
    assert np.abs(b.score - a.score).max(initial=0) <= SCORE_TOL


def test_round_trip_of_a_real_detection_file(kitti_root, tmp_path):
    table = read_kitti(kitti_root / "det_02" / "rrc" / "0000.txt")
    assert len(table) == 816 and set(table.type.tolist()) == {CAR, PEDESTRIAN}
    kept, back = round_trip(tmp_path, table)
    assert len(kept) == len(table)  # nothing of a detection file is skipped
    assert_same_rows(kept, back)  # the file is in frame order, ids all -1: the order stays
    np.testing.assert_array_equal(back.box3d, np.tile(UNKNOWN_3D, (len(back), 1)))
    assert (back.alpha == -10).all() and (back.truncated == -1).all()
    lines = (tmp_path / "out.txt").read_text().splitlines()
    assert lines[0] == ("0 -1 Car -1 -1 -10.000000 296.02 160.17 452.30 288.37 -1.000000 "
                        "-1.000000 -1.000000 -1000.000000 -1000.000000 -1000.000000 -10.000000 "
                        "0.5292")


def test_round_trip_keeps_the_3d_columns(kitti_root, tmp_path):
    table = read_kitti(kitti_root / "det_02" / "pointrcnn" / "0000.txt")
    kept, back = round_trip(tmp_path, table, box3d=True)
    assert_same_rows(kept, back)
    assert (kept.score < 0).any()  # raw logits, written as they are
    assert np.abs(back.box3d - kept.box3d).max() <= REAL_TOL
    assert np.abs(back.alpha - kept.alpha).max() <= REAL_TOL
    assert (back.box3d[:, 3] != -1000).all()


def test_round_trip_of_a_17_column_file_sorts_by_frame_then_id(tmp_path):
    boxes = [(100, 50, 140, 130.125), (0, 0, 1241, 374), (5.5, 6.25, 7.75, 8.995),
             (300, 100, 330, 180), (1.004, 2, 3.006, 4)]
    text = "\n".join([row(2, 9, "Pedestrian", boxes[0]), row(0, 3, "car", boxes[1]),
                      row(2, 1, "Cyclist", boxes[2]), row(0, 2, "Person_sitting", boxes[3]),
                      row(1, 5, "VAN", boxes[4])]) + "\n"
    table = read_kitti(write(tmp_path, text))
    assert (table.score == 1).all()
    kept, back = round_trip(tmp_path, table)
    order = np.lexsort((table.id, table.frame))
    assert order.tolist() == [3, 1, 4, 2, 0]
    assert_same_rows(table.select(order), back)
    assert back.frame.tolist() == [0, 0, 1, 2, 2] and back.id.tolist() == [2, 3, 5, 1, 9]
    assert [TYPES[t] for t in back.type] == ["Person", "Car", "Van", "Cyclist", "Pedestrian"]
    assert (tmp_path / "out.txt").read_text().splitlines()[0].split()[6:10] == [
        "300.00", "100.00", "330.00", "180.00"]
    assert back.score.tolist() == [1.0] * 5


def test_write_sorts_every_row_by_frame_then_id(tmp_path):
    rng = np.random.default_rng(4)
    n = 200
    frame = rng.integers(0, 20, n)
    ids = rng.permutation(n) + 1
    types = rng.integers(0, len(TYPES) - 1, n)
    left = rng.uniform(-50, 1200, (n, 2))
    box = np.concatenate([left, left + rng.uniform(1, 200, (n, 2))], axis=1)
    score = rng.uniform(0, 1, n)
    box3d = rng.uniform(-50, 50, (n, 7))
    out = tmp_path / "out.txt"
    write_kitti(out, frame, ids, types, box, score, box3d)
    back = read_kitti(out)
    key = list(zip(back.frame.tolist(), back.id.tolist(), strict=True))
    assert key == sorted(key) and len(back) == n
    order = np.lexsort((ids, frame))
    assert back.type.tolist() == types[order].tolist()
    assert np.abs(back.box - box[order]).max() <= BOX_TOL
    assert np.abs(back.score - score[order]).max() <= SCORE_TOL
    assert np.abs(back.box3d - box3d[order]).max() <= REAL_TOL
    assert (back.alpha == -10).all()


def test_write_refuses_an_existing_file(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("keep me\n")
    args = (np.array([1]), np.array([4]), np.array([CAR]), np.array([[1.0, 2, 3, 4]]),
            np.array([0.5]))
    with pytest.raises(OcctrackError) as err:
        write_kitti(out, *args)
    assert str(err.value).startswith(f"{out}: exists already")
    assert out.read_text() == "keep me\n"
    write_kitti(out, *args, overwrite=True)
    back = read_kitti(out)
    assert back.frame.tolist() == [1] and back.id.tolist() == [4] and back.score.tolist() == [0.5]


def test_write_nothing_is_an_empty_file(tmp_path):
    out = tmp_path / "out.txt"
    write_kitti(out, np.zeros(0, int), np.zeros(0, int), np.zeros(0, int), np.zeros((0, 4)),
                np.zeros(0))
    assert out.read_text() == "" and len(read_kitti(out)) == 0


# -- telling the formats apart -------------------------------------------------------------


def test_looks_like_kitti(tmp_path):
    assert looks_like_kitti(write(tmp_path, GOOD + "\n", "k.txt"))
    assert looks_like_kitti(write(tmp_path, "\ufeff\n  \n" + row(0, kind="DontCare") + "\n",
                                  "k2.txt"))
    assert not looks_like_kitti(write(tmp_path, "1,-1,10,20,30,40,0.9,-1,-1,-1\n", "m.txt"))
    assert not looks_like_kitti(write(tmp_path, "1, -1, 10, 20, 30, 40, 0.9\n", "m2.txt"))
    assert not looks_like_kitti(write(tmp_path, "1 -1 10 20 30 40 0.9 -1 -1 -1\n", "m3.txt"))
    assert not looks_like_kitti(write(tmp_path, "", "empty.txt"))
    assert not looks_like_kitti(write(tmp_path, "\n\n", "blank.txt"))
    assert not looks_like_kitti(tmp_path / "missing.txt")


def test_looks_like_kitti_on_the_real_files(kitti_root):
    for path in (kitti_root / "label_02" / "0000.txt",
                 kitti_root / "det_02" / "rrc" / "0000.txt",
                 kitti_root / "det_02" / "pointrcnn" / "0000.txt"):
        assert looks_like_kitti(path), path


# -- the layout and seqinfo ----------------------------------------------------------------


@pytest.fixture
def layout(tmp_path):
    """DIR/{label_02/0003.txt, det_02/rrc/0003.txt, det_02/rrc/0004.txt, seqinfo/0003.ini}."""
    root = tmp_path / "kitti"
    for folder in ("label_02", "det_02/rrc", "seqinfo"):
        (root / folder).mkdir(parents=True)
    for name in ("label_02/0003.txt", "det_02/rrc/0003.txt", "det_02/rrc/0004.txt"):
        (root / name).write_text(GOOD + "\n")
    (root / "seqinfo" / "0003.ini").write_text(SEQINFO.format(name="0003"))
    return root


def test_find_seqinfo_in_a_layout(layout, tmp_path):
    ini = (layout / "seqinfo" / "0003.ini").resolve()
    assert find_seqinfo(layout / "det_02" / "rrc" / "0003.txt") == ini
    assert find_seqinfo(layout / "label_02" / "0003.txt") == ini
    assert find_seqinfo(str(layout / "det_02" / "rrc" / "0003.txt")) == ini
    assert layout_root(layout / "det_02" / "rrc" / "0003.txt") == layout.resolve()
    assert layout_root(layout / "label_02" / "0003.txt") == layout.resolve()
    # in the layout, but no seqinfo for this sequence
    assert find_seqinfo(layout / "det_02" / "rrc" / "0004.txt") is None
    # outside a layout
    loose = write(tmp_path, GOOD + "\n", "0003.txt")
    assert find_seqinfo(loose) is None and layout_root(loose) is None
    (layout / "det_02" / "0003.txt").write_text(GOOD + "\n")
    assert find_seqinfo(layout / "det_02" / "0003.txt") is None
    (tmp_path / "other" / "0003").mkdir(parents=True)
    assert find_seqinfo(write(tmp_path / "other" / "0003", GOOD + "\n", "0003.txt")) is None


def test_read_seqinfo_takes_the_ini_file(layout):
    ini = layout / "seqinfo" / "0003.ini"
    assert read_seqinfo(ini) == {"name": "0003", "width": 1242, "height": 375, "length": 144,
                                 "fps": 10}
    assert read_seqinfo(str(ini)) == read_seqinfo(ini)
    ini.write_text(SEQINFO.format(name="0003").replace("name=0003\n", ""))
    assert read_seqinfo(ini)["name"] == "0003"  # the file's stem without a name
    ini.write_text("[Sequence]\nname=0003\n")
    with pytest.raises(OcctrackError, match="malformed seqinfo.ini"):
        read_seqinfo(ini)


def test_read_seqinfo_on_the_real_layout(kitti_root):
    det = kitti_root / "det_02" / "rrc" / "0000.txt"
    ini = find_seqinfo(det)
    assert ini == (kitti_root / "seqinfo" / "0000.ini").resolve()
    assert read_seqinfo(ini) == {"name": "0000", "width": 1242, "height": 375, "length": 154,
                                 "fps": 10}
    assert read_kitti(det).num_frames <= 154
