"""Invariance of the defaults: MOT17-04 and MOT17-11 at 640x360, at 15 and 10 fps, and with
a synthetic camera sway, each tracked by occtrack and the peers (`occtrack benchmark`).

    python benchmarks/bench_invariance.py [--data DIR] [--trackers LIST]

Needs the MOT17 data (--data, OCCTRACK_DATA or ../shared/data/mot17) and the peers extra.
"""

from __future__ import annotations

import argparse
import tempfile

from occtrack.io.data import find_sequence
from occtrack.scenarios.variants import VARIANTS, write_variant


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None)
    parser.add_argument("--trackers",
                        default="none,measurement-wise,object-wise,bytetrack,ocsort,botsort")
    parser.add_argument("--config", default=None,
                        help="a settings file for occtrack's models (occtrack benchmark's)")
    args = parser.parse_args()
    from occtrack.cli import main as occtrack

    with tempfile.TemporaryDirectory() as root:
        for name in ("MOT17-04-FRCNN", "MOT17-11-FRCNN"):
            sequence = find_sequence(args.data, name)
            for variant in VARIANTS:
                write_variant(sequence, variant, root)
        occtrack(["benchmark", root, "--trackers", args.trackers, "--quiet",
                  *(["--config", args.config] if args.config else [])])


if __name__ == "__main__":
    main()
