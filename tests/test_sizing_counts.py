"""Issue 38, kind 3: no number in an input or a flag sizes an allocation beyond the scene.

A sequence length (--frames, seqinfo.ini's seqLength) larger than the data is scored exactly
as the data's own length (the frames after the last row hold no box, so no metric changes) and
costs nothing; `calibrate`, whose rates are per frame, refuses a trailing run of empty frames
longer than a day, as `track` does; a stray frame number in a KITTI file is refused; and
`simulate lidar` refuses a scene larger than any disk would hold, before it writes anything.
"""

from __future__ import annotations

import json

import pytest

from occtrack.cli import main
from occtrack.cli.simulate import MAX_SCAN_ROWS
from occtrack.config.arguments import DAY_AT_30_FPS

HUGE = 100_000_000


def _sequence(folder, length: int):
    """A MOTChallenge sequence folder: 3 people over 40 frames, a result that tracks them
    with one switch and one false box, and a seqinfo.ini that says `length` frames."""
    (folder / "gt").mkdir(parents=True)
    (folder / "det").mkdir()
    gt, det, res = [], [], []
    for f in range(1, 41):
        for i in range(3):
            box = f"{100 + 200 * i + 2 * f},{100 + 10 * i},40,100"
            gt.append(f"{f},{i + 1},{box},1,1,1.0\n")
            det.append(f"{f},-1,{box},0.9\n")
            res.append(f"{f},{i + 1 + (f > 30 and i == 0) * 10},{box},0.8,-1,-1,-1\n")
        if f % 7 == 0:
            res.append(f"{f},99,900,300,40,100,0.3,-1,-1,-1\n")
    (folder / "gt" / "gt.txt").write_text("".join(gt))
    (folder / "det" / "det.txt").write_text("".join(det))
    (folder / "res.txt").write_text("".join(res))
    (folder / "seqinfo.ini").write_text(
        f"[Sequence]\nname=S\nimDir=img1\nframeRate=30\nseqLength={length}\n"
        f"imWidth=1280\nimHeight=720\nimExt=.jpg\n")
    return folder


def _eval_json(capsys, *argv) -> dict:
    capsys.readouterr()
    assert main(["eval", *map(str, argv), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_a_sequence_length_beyond_the_data_scores_as_the_data(tmp_path, capsys):
    short = _sequence(tmp_path / "short", 40)
    long = _sequence(tmp_path / "long", HUGE)
    base = _eval_json(capsys, short / "gt" / "gt.txt", short / "res.txt")
    assert base["id_switches"] == 1 and base["fp"] == 5
    for scored in (_eval_json(capsys, long / "gt" / "gt.txt", long / "res.txt"),
                   _eval_json(capsys, short / "gt" / "gt.txt", short / "res.txt", "--frames",
                              HUGE),
                   _eval_json(capsys, short / "gt" / "gt.txt", short / "res.txt", "--frames",
                              40, "--protocol", "mot17")):
        assert scored == base


def test_the_table_says_the_stated_length(tmp_path, capsys):
    long = _sequence(tmp_path / "long", HUGE)
    assert main(["eval", str(long / "gt" / "gt.txt"), str(long / "res.txt")]) == 0
    assert f"scored {HUGE} frames, 120 true boxes" in capsys.readouterr().out


def test_a_length_shorter_than_the_data_is_still_an_error(tmp_path, capsys):
    seq = _sequence(tmp_path / "s", 40)
    assert main(["eval", str(seq / "gt" / "gt.txt"), str(seq / "res.txt"),
                 "--frames", "30"]) == 1
    assert "has frame 31 but the sequence has 30 frames" in capsys.readouterr().err


def test_a_stray_frame_number_in_a_result_is_refused_even_with_a_length(tmp_path, capsys):
    seq = _sequence(tmp_path / "s", HUGE)
    with open(seq / "res.txt", "a") as fh:
        fh.write(f"{HUGE - 1},5,10,10,40,100,0.5,-1,-1,-1\n")
    assert main(["eval", str(seq / "gt" / "gt.txt"), str(seq / "res.txt")]) == 1
    err = capsys.readouterr().err
    assert f"frame {HUGE - 1} follows frame 40" in err and "--max-gap-frames" in err


def test_calibrate_refuses_a_seqinfo_of_a_hundred_million_frames(tmp_path, capsys):
    seq = _sequence(tmp_path / "s", HUGE)
    assert main(["calibrate", str(seq / "gt" / "gt.txt"), str(seq / "det" / "det.txt"),
                 "--quiet"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert (f"the last row is in frame 40 but the sequence has {HUGE} frames (seqinfo.ini): "
            f"{HUGE - 40} empty frames at the end, more than the {DAY_AT_30_FPS} allowed; check "
            f"the frame numbers") in err
    assert "--max-gap-frames" not in err  # calibrate has no such flag


def _kitti_pair(folder, last_frame: int):
    folder.mkdir()
    rows = []
    for f in range(20):
        rows.append(f"{f} 1 Car 0 0 0 {100 + 3 * f} 150 {180 + 3 * f} 210 -1 -1 -1 -1000 -1000 "
                    f"-1000 -10\n")
    (folder / "gt.txt").write_text("".join(rows))
    res = [r.rstrip("\n") + " 0.9\n" for r in rows]
    res.append(f"{last_frame} 7 Car 0 0 0 500 150 560 210 -1 -1 -1 -1000 -1000 -1000 -10 "
               f"0.4\n")
    (folder / "res.txt").write_text("".join(res))
    return folder


def test_kitti_scores_a_huge_length_as_the_data(tmp_path, capsys):
    pair = _kitti_pair(tmp_path / "k", 25)
    base = _eval_json(capsys, pair / "gt.txt", pair / "res.txt", "--protocol", "kitti")
    huge = _eval_json(capsys, pair / "gt.txt", pair / "res.txt", "--protocol", "kitti",
                      "--frames", HUGE)
    assert huge["classes"]["car"]["combined"] == base["classes"]["car"]["combined"]
    assert base["classes"]["car"]["combined"]["fp"] == 1


def test_kitti_refuses_a_stray_frame_number(tmp_path, capsys):
    pair = _kitti_pair(tmp_path / "k", HUGE)
    assert main(["eval", str(pair / "gt.txt"), str(pair / "res.txt"),
                 "--protocol", "kitti"]) == 1
    err = capsys.readouterr().err
    assert f"frame {HUGE} follows frame 19" in err and "raise --max-gap-frames" in err
    # and the flag does raise the bound (the result's frames are then scored, none of them
    # the ground truth's)
    pair2 = _kitti_pair(tmp_path / "k2", 5000)
    assert main(["eval", str(pair2 / "gt.txt"), str(pair2 / "res.txt"), "--protocol",
                 "kitti", "--max-gap-frames", "100"]) == 1
    assert "more than the 100 allowed" in capsys.readouterr().err
    assert main(["eval", str(pair2 / "gt.txt"), str(pair2 / "res.txt"), "--protocol",
                 "kitti", "--max-gap-frames", "10000", "--json"]) == 0


@pytest.mark.parametrize("argv", [["--scans", "1000000000"], ["--duration", "1e12"],
                                  ["--scans", "3000000", "--beams", "1000"]])
def test_simulate_lidar_refuses_a_scene_no_disk_holds(tmp_path, capsys, argv):
    out = tmp_path / "scene"
    assert main(["simulate", "lidar", "-o", str(out), "--quiet", *argv]) == 1
    err = capsys.readouterr().err
    assert f"more than {MAX_SCAN_ROWS:.0e}" in err and "rows of scans.csv" in err
    assert not out.exists()

