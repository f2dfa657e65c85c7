"""Box-only peer trackers, run the way a user would run them, to be scored beside occtrack.

occtrack claims that occlusion reasoning keeps identities that plain trackers lose; that claim
is only worth what it beats. The peers here are the ones a user would otherwise pick: SORT,
ByteTrack, OC-SORT, BoT-SORT and C-BIoU as Roboflow's `trackers` package (2.6.1) implements
them. Each runs with the library's defaults (only the frame rate set) on every frame, fed the
detection file as `supervision` Detections, and reports the detection box each confirmed track
took in that frame. BoT-SORT's camera-motion compensation needs the images and is skipped
without them, as the library does when it gets no frame.

`trackers` is an optional extra: `pip install "occtrack[peers]"`.
"""

from __future__ import annotations

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
    track_peer,
)

__all__ = ["INSTALL_HINT", "PEERS", "available", "botsort", "bytetrack", "cbiou", "load",
           "ocsort", "sort", "track_peer"]
