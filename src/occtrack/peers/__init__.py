"""Box-only peer trackers, run the way a user would run them, to be scored beside occtrack.

occtrack claims that occlusion reasoning keeps identities that plain trackers lose; that claim
is only worth what it beats. The peers here are the ones a user would otherwise pick: SORT,
ByteTrack, OC-SORT, BoT-SORT and C-BIoU as Roboflow's `trackers` package (2.6.1) implements
them (`occtrack.peers.roboflow`), and boxmot 25.0.0's box-only trackers, OccluBoost among them
(`occtrack.peers.boxmot`). Each runs with its library's defaults on every frame and reports the
boxes its confirmed tracks hold in that frame; what each needs set is said in its module.

`trackers` is the optional extra `pip install "occtrack[peers]"`; boxmot, which brings torch,
is its own: `pip install "occtrack[boxmot]"`.
"""

from __future__ import annotations

from occtrack.errors import OcctrackError
from occtrack.io.mot import MotTable
from occtrack.peers import boxmot
from occtrack.peers.roboflow import (
    INSTALL_HINT,
    PEERS,
    available,
    botsort,
    bytetrack,
    cbiou,
    load,
    ocsort,
    sort,
)

BOXMOT_PEERS = boxmot.PEERS
"""boxmot's box-only trackers by name (`PEERS` are Roboflow's)."""
ALL_PEERS = (*PEERS, *BOXMOT_PEERS)


def load_for(name: str) -> None:
    """Import the library that runs peer `name` (nothing for occtrack's own models), or raise
    naming the extra that brings it."""
    if name in BOXMOT_PEERS:
        boxmot.load()
    elif name in PEERS:
        load()


def missing(names) -> str | None:
    """What to install for the peers among `names` whose library is absent (None: nothing)."""
    if any(n in PEERS for n in names) and not available():
        return "the peer trackers need the `trackers` package; " + INSTALL_HINT
    if any(n in BOXMOT_PEERS for n in names) and not boxmot.available():
        return "the boxmot peer trackers need the `boxmot` package; " + boxmot.INSTALL_HINT
    return None


def track_peer(name: str, det: MotTable, num_frames: int, fps: float,
               image_size: tuple[int, int] = (1920, 1080)) -> MotTable:
    """Run the peer called `name` (a key of PEERS or BOXMOT_PEERS) on a sequence's
    detections; `image_size` is the frame's (width, height), which boxmot's trackers ask for."""
    if name in PEERS:
        return PEERS[name](det, num_frames, fps)
    if name in BOXMOT_PEERS:
        return BOXMOT_PEERS[name](det, num_frames, fps, image_size)
    raise OcctrackError(f"unknown peer tracker {name!r}; choose from {', '.join(ALL_PEERS)}")


__all__ = ["ALL_PEERS", "BOXMOT_PEERS", "INSTALL_HINT", "PEERS", "available", "botsort",
           "bytetrack", "cbiou", "load", "load_for", "missing", "ocsort", "sort", "track_peer"]
