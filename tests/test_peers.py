"""occtrack.peers: Roboflow `trackers` behind one function per peer, MotTable in and out."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable, read_mot
from occtrack.peers import BOXMOT_PEERS, PEERS, track_peer

PEOPLE, FRAMES, GAP = 4, 40, 25  # people, frames, frames 1..GAP-1 only for the last person


def _scene(tmp_path) -> tuple[MotTable, np.ndarray]:
    """Well-separated people walking right, detected in every frame with small noise, written
    to a file in shuffled row order (as MOT17's det.txt files are) and read back; and the
    person behind each detection row."""
    rng = np.random.default_rng(3)
    lines, who = [], []
    for person in range(PEOPLE):
        last = GAP - 1 if person == PEOPLE - 1 else FRAMES
        for frame in range(1, last + 1):
            l, t, w, h = np.array([40 + 150 * person + 2.0 * frame, 200 + 30 * person, 40, 100])
            l, t = (l, t) + rng.normal(0, 0.5, 2)
            lines.append(f"{frame},-1,{l:.2f},{t:.2f},{w:.2f},{h:.2f},0.9,-1,-1,-1")
            who.append(person)
    order = rng.permutation(len(lines))
    path = tmp_path / "det.txt"
    path.write_text("\n".join(lines[i] for i in order) + "\n")
    return read_mot(path, "det"), np.array(who)[order]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    pytest.importorskip("trackers", reason="the peers need `pip install occtrack[peers]`")
    return _scene(tmp_path_factory.mktemp("peers"))


@pytest.mark.parametrize("name", list(PEERS))
def test_peer_rows_are_valid_and_follow_each_person(scene, name):
    det, person = scene
    out = track_peer(name, det, FRAMES + 5, 30.0)
    assert isinstance(out, MotTable) and len(out) > 0
    assert out.frame.min() >= 1 and out.frame.max() <= FRAMES
    assert (out.id >= 1).all() and (out.box[:, 2:] > 0).all()
    key = out.frame * 1000 + out.id
    assert len(np.unique(key)) == len(out), "an id twice in one frame"
    assert np.all(np.diff(out.frame) >= 0)
    # Each reported box is the detection a track took in that frame, so it names one person;
    # with people this far apart every person keeps a single id.
    owner = np.empty(len(out), dtype=int)
    for k in range(len(out)):
        at = np.flatnonzero(det.frame == out.frame[k])
        match = at[np.all(np.abs(det.box[at] - out.box[k]) < 1e-6, axis=1)]
        assert len(match) == 1
        owner[k] = person[match[0]]
        assert out.score[k] == pytest.approx(det.score[match[0]])
    pairs = set(zip(owner.tolist(), out.id.tolist(), strict=True))
    assert len(pairs) == PEOPLE == len({p for p, _ in pairs}) == len({i for _, i in pairs})


def test_peers_take_an_empty_sequence(scene):
    det, _ = scene
    empty = det.select(np.zeros(len(det), dtype=bool))
    for name in PEERS:
        assert len(track_peer(name, empty, 10, 14.0)) == 0


def test_bad_input_is_named(scene):
    det, _ = scene
    with pytest.raises(OcctrackError, match="beyond the 10 frames"):
        track_peer("sort", det, 10, 30.0)
    with pytest.raises(OcctrackError, match="unknown peer tracker 'deepsort'"):
        track_peer("deepsort", det, FRAMES, 30.0)
    with pytest.raises(OcctrackError, match="frame rate must be positive"):
        track_peer("bytetrack", det, FRAMES, 0.0)


def test_missing_library_says_how_to_install(tmp_path, monkeypatch):
    det, _ = _scene(tmp_path)
    monkeypatch.setitem(sys.modules, "trackers", None)
    with pytest.raises(OcctrackError, match=r'pip install "occtrack\[peers\]"'):
        track_peer("bytetrack", det, FRAMES, 30.0)


@pytest.fixture(scope="module")
def boxmot_scene(tmp_path_factory):
    pytest.importorskip("boxmot", reason='boxmot peers need pip install "occtrack[boxmot]"')
    return _scene(tmp_path_factory.mktemp("boxmot"))


@pytest.mark.parametrize("name", list(BOXMOT_PEERS))
def test_boxmot_peer_rows_are_valid_and_follow_each_person(boxmot_scene, name):
    """boxmot returns its own estimate of each tracked box: every row lies on one person's
    detection of that frame (IoU >= 0.5) and, with people this far apart, each person keeps
    one id."""
    det, person = boxmot_scene
    out = track_peer(name, det, FRAMES + 5, 30.0, (1280, 720))
    assert isinstance(out, MotTable) and len(out) > 0
    assert out.frame.min() >= 1 and out.frame.max() <= FRAMES
    assert len(np.unique(out.frame * 1000 + out.id)) == len(out), "an id twice in one frame"
    owner = np.empty(len(out), dtype=int)
    for k in range(len(out)):
        at = np.flatnonzero(det.frame == out.frame[k])
        lo = np.maximum(det.box[at, :2], out.box[k, :2])
        hi = np.minimum(det.box[at, :2] + det.box[at, 2:], out.box[k, :2] + out.box[k, 2:])
        inter = np.prod(np.clip(hi - lo, 0, None), axis=1)
        iou = inter / (np.prod(det.box[at, 2:], axis=1) + np.prod(out.box[k, 2:]) - inter)
        assert iou.max() >= 0.5
        owner[k] = person[at[np.argmax(iou)]]
    pairs = set(zip(owner.tolist(), out.id.tolist(), strict=True))
    assert len(pairs) == PEOPLE == len({p for p, _ in pairs}) == len({i for _, i in pairs})
    empty = det.select(np.zeros(len(det), dtype=bool))
    assert len(track_peer(name, empty, 10, 14.0, (1280, 720))) == 0


def test_missing_boxmot_says_how_to_install(tmp_path, monkeypatch):
    from occtrack.experiments.benchmark import parse_trackers
    from occtrack.peers import boxmot

    det, _ = _scene(tmp_path)
    monkeypatch.setitem(sys.modules, "boxmot", None)
    monkeypatch.setitem(sys.modules, "boxmot.trackers.specs", None)
    with pytest.raises(OcctrackError, match=r'pip install "occtrack\[boxmot\]"'):
        track_peer("occluboost", det, FRAMES, 30.0)
    monkeypatch.setattr(boxmot, "available", lambda: False)
    with pytest.raises(OcctrackError, match=r"boxmot peer trackers need the `boxmot` package"):
        parse_trackers("object-wise,occluboost")
