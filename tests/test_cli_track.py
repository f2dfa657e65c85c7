"""`occtrack track` and `occtrack demo` from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from occtrack.cli import main
from occtrack.io.mot import read_mot
from occtrack.scenarios.pedestrians import Crowd, crowd_scene

SEQINFO = """[Sequence]
name=SYN
imDir=img1
frameRate=30
seqLength={length}
imWidth=1920
imHeight=1080
imExt=.jpg
"""


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """A MOTChallenge-style folder SYN/{seqinfo.ini, det/det.txt} of a synthetic scene."""
    root = tmp_path_factory.mktemp("seq") / "SYN"
    (root / "det").mkdir(parents=True)
    scene = crowd_scene(Crowd(people=8, frames=60), seed=2)
    (root / "seqinfo.ini").write_text(SEQINFO.format(length=64))
    d = scene.detections
    rows = [f"{d.frame[i]},-1,{d.box[i, 0]:.2f},{d.box[i, 1]:.2f},{d.box[i, 2]:.2f},"
            f"{d.box[i, 3]:.2f},{d.score[i]:.3f},-1,-1,-1" for i in range(len(d))]
    (root / "det" / "det.txt").write_text("\n".join(rows) + "\n")
    return root


def test_track_writes_a_result_file_and_a_summary(sequence, tmp_path, capsys):
    out = tmp_path / "result.txt"
    code = main(["track", str(sequence / "det" / "det.txt"), "--occlusion", "object-wise",
                 "-o", str(out), "--quiet"])
    assert code == 0 and capsys.readouterr().out == ""
    result = read_mot(out, "result")
    assert result.frame.max() <= 64 and len(result) > 300
    assert set(np.unique(result.cls)) == {-1}
    code = main(["track", str(sequence / "det" / "det.txt"), "-o", str(out), "--force",
                 "--frame-step", "1"])
    summary = capsys.readouterr().out.strip()
    assert code == 0 and summary.startswith("64 frames, ") and "frames per second" in summary


def test_track_refuses_to_overwrite(sequence, tmp_path, capsys):
    out = tmp_path / "result.txt"
    out.write_text("keep me\n")
    assert main(["track", str(sequence / "det" / "det.txt"), "-o", str(out)]) == 1
    assert "exists already" in capsys.readouterr().err
    assert out.read_text() == "keep me\n"


def test_malformed_detection_line_is_named(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n1,-1,10,10,thirty,90,0.9\n")
    code = main(["track", str(det), "--image-size", "640x480", "--fps", "25", "-o",
                 str(tmp_path / "r.txt")])
    err = capsys.readouterr().err.strip()
    assert code == 1
    assert err == f"occtrack track: error: {det}:2: column 5 is not a number: 'thirty'"
    assert not (tmp_path / "r.txt").exists()


def test_an_empty_detection_file_gives_an_empty_result_and_says_so(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("")
    out = tmp_path / "r.txt"
    assert main(["track", str(det), "--image-size", "640x480", "--fps", "25", "-o",
                 str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err == (f"occtrack track: warning: {det} holds no detections, so the result "
                            f"has no tracks\n")
    assert captured.out.startswith("0 frames, 0 tracks")
    assert out.read_text() == ""


def test_image_size_is_required_without_seqinfo(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,30,90,0.9\n")
    assert main(["track", str(det), "-o", str(tmp_path / "r.txt")]) == 1
    assert "image size unknown: pass --image-size WxH" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["track", str(det), "--image-size", "640by480", "-o", str(tmp_path / "r.txt")])
    assert exit_.value.code == 2
    assert "is not an image size" in capsys.readouterr().err
    assert main(["track", str(det), "--image-size", "640x480", "-o", str(tmp_path / "r.txt")]) == 1
    assert "fps unknown: pass --fps HZ" in capsys.readouterr().err


def test_config_file_settings_and_errors(sequence, tmp_path, capsys):
    config = tmp_path / "tracker.toml"
    config.write_text('occlusion = "none"\ncapacity = 256\n')
    out = tmp_path / "r.txt"
    assert main(["track", str(sequence / "det" / "det.txt"), "--config", str(config),
                 "-o", str(out), "--quiet"]) == 0
    config.write_text("capacity = -4\n")
    assert main(["track", str(sequence / "det" / "det.txt"), "--config", str(config),
                 "-o", str(out), "--force"]) == 1
    assert f"{config}: capacity must be between 0 and 10000000" in capsys.readouterr().err


def test_track_help_explains_the_models(capsys):
    with pytest.raises(SystemExit):
        main(["track", "--help"])
    text = capsys.readouterr().out
    for word in ("measurement-wise", "object-wise", "seqinfo.ini", "--frame-step", "TOML"):
        assert word in text


def test_demo_prints_scores_for_the_three_models(tmp_path, capsys):
    figure = tmp_path / "demo.png"
    assert main(["demo", "--people", "5", "--frames", "80", "--json", "--quiet",
                 "--figure", str(figure)]) == 0
    scores = json.loads(capsys.readouterr().out)
    assert set(scores["trackers"]) == {"none", "object-wise", "measurement-wise"}
    for s in scores["trackers"].values():
        assert 0 < s["idf1"] <= 1 and s["mota"] <= 1 and 0 <= s["ece"] <= 1
        assert 0 <= s["kept"] <= s["occlusions"] and s["false_boxes"] >= 0
    assert 0 < scores["detector"]["recall"] <= 1
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["demo", "--frames", "10", "--figure", str(figure)]) == 1
    assert "exists already; pass --force" in capsys.readouterr().err
