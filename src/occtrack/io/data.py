"""Where the MOT17 data lives: a flag, the OCCTRACK_DATA variable, or ../shared/data/mot17.

MOT17 is licensed for research use and never copied into this repository; commands that need it
take its folder and say clearly what is missing.
"""

from __future__ import annotations

import os
from pathlib import Path

from occtrack.errors import OcctrackError

SEQUENCE = "MOT17-04-FRCNN"


def _candidates(explicit: str | os.PathLike | None) -> list[tuple[Path, str]]:
    if explicit is not None:
        return [(Path(explicit), "--data")]
    if os.environ.get("OCCTRACK_DATA"):
        return [(Path(os.environ["OCCTRACK_DATA"]), "OCCTRACK_DATA")]
    source_tree = Path(__file__).resolve().parents[3]
    return [(Path.cwd().parent / "shared" / "data" / "mot17", "../shared/data/mot17"),
            (source_tree.parent / "shared" / "data" / "mot17", "the checkout's ../shared")]


def find_sequence(data: str | os.PathLike | None = None, sequence: str = SEQUENCE) -> Path:
    """The folder of a MOT17 sequence (holding gt/gt.txt and seqinfo.ini)."""
    tried = []
    for root, origin in _candidates(data):
        for folder in (root / sequence, root):
            if (folder / "gt" / "gt.txt").is_file() and (folder / "seqinfo.ini").is_file():
                return folder
        tried.append(f"{root} ({origin})")
    raise OcctrackError(
        f"MOT17 data not found: looked for {sequence}/gt/gt.txt and {sequence}/seqinfo.ini in "
        + "; ".join(tried)
        + ". Get MOT17 from the MOTChallenge website and pass --data DIR or set OCCTRACK_DATA "
          "to the folder that holds the sequence folders.")
