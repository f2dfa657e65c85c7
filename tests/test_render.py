"""`occtrack render`: tracks drawn on frames the test makes (pictures and a video)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

iio = pytest.importorskip("imageio.v3", reason='needs pip install "occtrack[viz]"')
pytest.importorskip("PIL", reason='needs pip install "occtrack[viz]"')
pytest.importorskip("av", reason='needs pip install "occtrack[viz]"')

from occtrack.cli import main  # noqa: E402
from occtrack.viz.render import PALETTE, Overlay, Painter, colour, image_files  # noqa: E402

W, H, FRAMES = 320, 240, 12


def box_at(k: int) -> tuple[float, float, float, float]:
    """A person walking right, 4 px a frame, missed (behind a pillar) in frames 8 and 9."""
    return 40.0 + 4 * k, 60.0, 30.0, 90.0


@pytest.fixture
def sequence(tmp_path):
    """A MOT-style folder: img1/000001.png.. (a grey gradient with a darker 'person'),
    det/det.txt with the person's box, seqinfo.ini."""
    seq = tmp_path / "SEQ"
    (seq / "img1").mkdir(parents=True)
    (seq / "det").mkdir()
    rows = []
    for k in range(1, FRAMES + 1):
        image = np.tile(np.linspace(90, 170, W, dtype=np.uint8), (H, 1))[:, :, None].repeat(3, 2)
        left, top, w, h = box_at(k)
        image[int(top):int(top + h), int(left):int(left + w)] = 40
        iio.imwrite(seq / "img1" / f"{k:06d}.png", image)
        if k not in (8, 9):
            rows.append(f"{k},-1,{left},{top},{w},{h},0.95\n")
    (seq / "det" / "det.txt").write_text("".join(rows))
    (seq / "seqinfo.ini").write_text(f"[Sequence]\nname=SEQ\nimDir=img1\nframeRate=10\n"
                                     f"seqLength={FRAMES}\nimWidth={W}\nimHeight={H}\n"
                                     f"imExt=.png\n")
    return seq


def render(*argv) -> int:
    return main(["render", *map(str, argv), "--quiet"])


def test_detections_are_tracked_and_drawn_on_every_picture(sequence, tmp_path):
    out = tmp_path / "out"
    assert render(sequence / "det" / "det.txt", "--images", sequence / "img1", "-o", out) == 0
    written = sorted(p.name for p in out.iterdir())
    assert written == [f"{k:06d}.png" for k in range(1, FRAMES + 1)]  # PNG in, PNG out
    # frame 6: track 1's box is drawn in its colour on the person's top edge, solid
    image = iio.imread(out / "000006.png")
    left, top, w, h = box_at(6)
    edge = image[int(top), int(left) + 2:int(left + w) - 2]
    assert (edge == colour(1)).all(axis=1).all()
    original = iio.imread(sequence / "img1" / "000006.png")
    assert (image[H - 10:] == original[H - 10:]).all()  # far from the track: untouched


def test_a_coasting_track_is_dashed(sequence, tmp_path):
    out = tmp_path / "out"
    render(sequence / "det" / "det.txt", "--images", sequence / "img1", "-o", out)
    image = iio.imread(out / "000008.png")  # missed in frame 8: coasting
    tracked = (image == colour(1)).all(axis=2)
    rows = np.flatnonzero(tracked.any(axis=1))
    assert len(rows)
    # the box's top edge is the first row in the id's colour below the label; dashed: the
    # colour covers part of the edge only
    left, top, w, h = box_at(8)
    band = tracked[int(top) - 3:int(top) + 4, int(left) - 4:int(left + w) + 4]
    covered = band.any(axis=0).mean()
    assert 0.2 < covered < 0.9


def test_a_result_file_is_drawn_as_it_is_to_a_video_and_a_picture(sequence, tmp_path):
    result = tmp_path / "result.txt"
    result.write_text("".join(f"{k},7,{','.join(map(str, box_at(k)))},1,-1,-1,-1\n"
                              for k in range(1, FRAMES + 1)))
    video = tmp_path / "tracks.mp4"
    assert render(result, "--images", sequence / "img1", "-o", video, "--fps", "10") == 0
    frames = np.stack(list(iio.imiter(video, plugin="pyav")))
    assert frames.shape == (FRAMES, H, W, 3)

    gif = tmp_path / "tracks.gif"
    assert render(result, "--images", sequence / "img1", "-o", gif, "--fps", "10") == 0
    assert iio.imread(gif, index=None).shape[0] == FRAMES

    picture = tmp_path / "frame5.png"
    assert render(result, "--images", sequence / "img1", "-o", picture, "--frames", "2:5",
                  "--scale", "0.5") == 0
    image = iio.imread(picture)
    assert image.shape == (H // 2, W // 2, 3)
    left, top, w, h = (v / 2 for v in box_at(5))
    assert (image[int(top), int(left) + 2:int(left + w) - 2] == colour(7)).all()


def test_a_video_can_be_the_source_of_frames(sequence, tmp_path):
    video = tmp_path / "in.mp4"
    with iio.imopen(video, "w", plugin="pyav") as writer:
        writer.init_video_stream("libx264", fps=10)
        for _, path in image_files(sequence / "img1"):
            writer.write_frame(iio.imread(path))
    det = tmp_path / "det.txt"  # outside a sequence folder: the fps comes from the video
    det.write_text((sequence / "det" / "det.txt").read_text())
    out = tmp_path / "frames"
    assert render(det, "--video", video, "-o", out, "--frames", "3:6") == 0
    assert sorted(p.name for p in out.iterdir()) == [f"{k:06d}.jpg" for k in range(3, 7)]


def test_outputs_are_refused_or_replaced_as_asked(sequence, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    det = sequence / "det" / "det.txt"
    assert render(det, "--images", sequence / "img1", "-o", out) == 1
    assert "--force" in capsys.readouterr().err
    assert render(det, "--images", sequence / "img1", "-o", out, "--force") == 0
    assert not (out / "old.txt").exists() and len(list(out.iterdir())) == FRAMES
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    assert render(det, "--images", tmp_path / "nowhere", "-o", tmp_path / "x") == 1
    assert "no such folder" in capsys.readouterr().err
    assert render(det, "--images", sequence / "img1", "-o", tmp_path / "y",
                  "--frames", "50:60") == 1
    assert "no pictures" in capsys.readouterr().err


def test_trails_follow_the_bottom_centres_of_the_last_boxes():
    frame = np.repeat(np.arange(1, 6), 2)
    ids = np.tile([3, 4], 5)
    box = np.array([[10.0 * f, 5.0 * i, 4.0, 8.0] for f, i in zip(frame, ids, strict=True)])
    overlay = Overlay(frame, ids, box, np.zeros(10, bool), np.zeros(10, bool))
    painter = Painter(overlay, 100, trail=3)
    assert painter.trail_of(3, 4).tolist() == [[22.0, 23.0], [32.0, 23.0], [42.0, 23.0]]
    assert len(PALETTE) >= 10 and colour(3) != colour(4)


def test_the_viz_extra_is_named_when_missing(sequence, tmp_path):
    code = ("import sys; sys.modules['imageio'] = None\n"
            "from occtrack.cli import main\n"
            f"sys.exit(main(['render', {str(sequence / 'det' / 'det.txt')!r}, '--images', "
            f"{str(sequence / 'img1')!r}, '-o', {str(tmp_path / 'o')!r}]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 1
    assert 'pip install "occtrack[viz]"' in done.stderr

