"""Peak memory of `occtrack track` on a detection file of hundreds of megabytes (issue 38).

    python benchmarks/memory_long_file.py [--megabytes 500] [--data DIR] [--keep FILE]

Builds a long sequence by repeating MOT17-04's FRCNN detections (from --data, OCCTRACK_DATA or
../shared/data/mot17; 28,406 rows over 1,050 frames, 0.9 MB) one copy after another, each
copy's frames shifted past the last, until the file holds --megabytes; then runs
`occtrack track FILE -o RESULT --image-size 1920x1080 --fps 30 --quiet` in a child process
and reports its peak resident memory (the child's ru_maxrss), the file's size and rows, and
the bytes of memory a row of input. The tracker's state is bounded by the scene (MOT17-04's
crowd), the reader keeps 80 bytes a row (its arrays, allocated once at the counted length),
and the result is written frame by frame; before issue 38 the same 524 MB file peaked at
7.9 GiB while it was parsed. Slow: about 40 minutes for 500 MB on one free core (most of it
tracking 590,000 frames). Prints one line a stage and the figure last.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SEQUENCE = "MOT17-04-FRCNN"
FRAMES = 1050


def data_folder(given: Path | None) -> Path:
    for folder in (given, os.environ.get("OCCTRACK_DATA"), ROOT.parent / "shared/data/mot17"):
        if folder and (Path(folder) / SEQUENCE / "det" / "det.txt").is_file():
            return Path(folder)
    sys.exit(f"{SEQUENCE}/det/det.txt not found: pass --data DIR (the MOT17 folder) or set "
             f"OCCTRACK_DATA")


def build(source: Path, target: Path, megabytes: float) -> tuple[int, int, int]:
    """Write copies of `source` with frames shifted until `target` holds `megabytes` MB;
    returns its bytes, rows and frames."""
    rows = [line.split(",", 1) for line in source.read_text().splitlines() if line.strip()]
    size = copies = count = 0
    with open(target, "w") as fh:
        while size < megabytes * 1e6:
            shift = copies * FRAMES
            text = "".join(f"{int(f) + shift},{rest}\n" for f, rest in rows)
            fh.write(text)
            size += len(text)
            count += len(rows)
            copies += 1
    return size, count, copies * FRAMES


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--megabytes", type=float, default=500.0,
                        help="size of the detection file (default 500)")
    parser.add_argument("--data", type=Path, help="the MOT17 folder")
    parser.add_argument("--keep", type=Path, metavar="FILE",
                        help="build the file here and keep it (default: a temporary folder)")
    args = parser.parse_args()
    source = data_folder(args.data) / SEQUENCE / "det" / "det.txt"
    with tempfile.TemporaryDirectory(prefix="occtrack-memory-") as tmp:
        det = args.keep or Path(tmp) / "det.txt"
        start = time.monotonic()
        size, rows, frames = build(source, det, args.megabytes)
        print(f"built {det}: {size / 1e6:.0f} MB, {rows:,} rows, {frames:,} frames "
              f"({time.monotonic() - start:.0f} s)", flush=True)
        start = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "occtrack", "track", str(det), "-o",
                               str(Path(tmp) / "result.txt"), "--image-size", "1920x1080",
                               "--fps", "30", "--quiet"], capture_output=True, text=True)
        seconds = time.monotonic() - start
        if done.returncode:
            print(f"occtrack track failed ({done.returncode}): {done.stderr.strip()}")
            return 1
        peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024  # KiB on Linux
        result = Path(tmp) / "result.txt"
        print(f"tracked in {seconds / 60:.1f} min; result {result.stat().st_size / 1e6:.0f} MB")
    print(f"peak memory {peak / 2**30:.2f} GiB for a {size / 1e6:.0f} MB file of {rows:,} rows "
          f"({peak / rows:.0f} bytes a row; {peak / size:.1f} times the file)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
