"""Issue 38, kind 2: plausible mistakes get a word, not silent nonsense. The API validates as
the TOML loader does, naming the field; a detection file whose rows repeat (a file
concatenated twice) is tracked as the file once, with a count of the merged rows."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occtrack.cli import main
from occtrack.config import TrackerConfig
from occtrack.errors import OcctrackError
from occtrack.io.mot import exact_duplicates, read_detections

INTEGER_FIELDS = [f.name for f in dataclasses.fields(TrackerConfig)
                  if isinstance(f.default, int) and not isinstance(f.default, bool)]


@pytest.mark.parametrize("changes, message", [
    ({"frame_step": 1.5}, "frame_step must be an integer, not 1.5"),
    ({"capacity": 20.5}, "capacity must be an integer, not 20.5"),
    ({"fps": "30"}, "fps must be a number, not '30'"),
    ({"image_size": (1920,)}, "image_size must be a pair of numbers like [1.0, 2.0], not "
                              "(1920,)"),
    ({"gating": 1}, "gating must be true or false, not 1"),
    ({"birth_half_size_std": (1.0, 2.0, 3.0)}, "birth_half_size_std must be a pair of "
                                               "numbers like [1.0, 2.0], not (1.0, 2.0, 3.0)"),
    ({"occlusion": 3}, "occlusion must be a string, not 3"),
])
def test_the_api_refuses_what_the_toml_loader_refuses(changes, message, tmp_path):
    with pytest.raises(TypeError) as err:
        TrackerConfig(**changes)
    assert str(err.value) == message
    name, value = next(iter(changes.items()))
    toml = tmp_path / "c.toml"
    shown = f'"{value}"' if isinstance(value, str) else (
        "true" if value is True else str(list(value)) if isinstance(value, tuple) else value)
    toml.write_text(f"{name} = {shown}\n")
    with pytest.raises(OcctrackError) as loaded:
        TrackerConfig.from_toml(toml)
    assert name in str(loaded.value)


@given(st.sampled_from(INTEGER_FIELDS), st.floats(allow_nan=False, allow_infinity=False)
       .filter(lambda v: not float(v).is_integer()))
def test_a_fractional_integer_setting_names_its_field(name, value):
    with pytest.raises(TypeError, match=f"^{name} must be an integer"):
        TrackerConfig(**{name: value})


def test_numbers_of_any_kind_are_taken_as_the_fields_type():
    config = TrackerConfig(fps=np.int64(25), frame_step=np.int32(2), capacity=np.int64(0),
                           image_size=[np.float32(640), 480], gating=np.bool_(False))
    assert config.fps == 25.0 and isinstance(config.fps, float)
    assert config.frame_step == 2 and type(config.frame_step) is int
    assert config.image_size == (640.0, 480.0) and config.gating is False
    assert config.replace(fps=12).fps == 12.0


def test_rows_repeated_in_their_frame_are_merged_with_a_count(tmp_path):
    rows = ["1,-1,10,10,20,50,0.9", "1,-1,40,10,20,50,0.8", "2,-1,12,10,20,50,0.9"]
    text = "\n".join(rows + rows + [rows[0]]) + "\n"
    path = tmp_path / "det.txt"
    path.write_text(text)
    table, warning = read_detections(path, (640, 480))
    assert table.line.tolist() == [1, 2, 3]
    assert warning == (f"{path}: merged 4 rows that repeat another row of their frame exactly "
                       f"(first at line 4; a file concatenated twice?)")
    # the same box in another frame, or with another score, is no repeat
    path.write_text("1,-1,10,10,20,50,0.9\n2,-1,10,10,20,50,0.9\n1,-1,10,10,20,50,0.8\n")
    table, warning = read_detections(path, (640, 480))
    assert len(table) == 3 and warning is None


@given(st.lists(st.tuples(st.integers(1, 3), st.integers(0, 3), st.sampled_from([0.5, 0.9])),
                min_size=1, max_size=30))
def test_exact_duplicates_leave_one_of_each_row(rows):
    from occtrack.io.mot import MotTable

    frame = np.array([r[0] for r in rows])
    box = np.array([[10.0 * r[1], 0, 5, 5] for r in rows])
    score = np.array([r[2] for r in rows])
    n = len(rows)
    table = MotTable(frame, np.full(n, -1), box, score, np.full(n, -1), np.full(n, -1.0))
    twins = exact_duplicates(table)
    kept = {rows[i] for i in np.flatnonzero(~twins)}
    assert kept == set(rows) and (~twins).sum() == len(set(rows))
    first = {}
    for i, r in enumerate(rows):
        first.setdefault(r, i)
    assert all(not twins[i] for i in first.values())  # the first of each is the one kept


def test_a_file_concatenated_twice_tracks_as_the_file_once(tmp_path, capsys):
    rng = np.random.default_rng(3)
    lines = []
    for frame in range(1, 31):
        for k in range(3):
            lines.append(f"{frame},-1,{100 + 200 * k + 2 * frame},{50 + rng.normal():.2f},40,"
                         f"100,0.9")
    once, twice = tmp_path / "once.txt", tmp_path / "twice.txt"
    once.write_text("\n".join(lines) + "\n")
    twice.write_text("\n".join(lines + lines) + "\n")
    for det in (once, twice):
        assert main(["track", str(det), "-o", str(tmp_path / f"r_{det.name}"), "--image-size",
                     "1280x720", "--fps", "30", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("merged 90 rows") == 1 and "(first at line 91;" in err
    assert (tmp_path / "r_once.txt").read_bytes() == (tmp_path / "r_twice.txt").read_bytes()
