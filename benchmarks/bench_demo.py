"""The demo's street on five seeds: does each occlusion model keep more identities through full
occlusions than none, with at least its IDF1 and MOTA? (issue 26)

    python benchmarks/bench_demo.py [--seeds 0 1 2 3 4] [--people 12] [--frames 1800]
                                    [--set NAME=VALUE ...]

Each seed is `occtrack demo --seed S` (default settings; the scores are the demo's, see
`occtrack.experiments.demo`); the last lines sum the kept occlusions and the ID switches over
the seeds and count the seeds on which each model is at least `none`'s IDF1 and MOTA. `--set`
changes a TrackerConfig setting for every model (a TOML value: `--set
detectability_ratio=0.7356`), to try a change against the demo's question.
"""

from __future__ import annotations

import argparse

from occtrack._compat import tomllib
from occtrack.experiments.demo import run_demo
from occtrack.scenarios.street import Street
from occtrack.tracker import OCCLUSION_NAMES, TrackerConfig


def setting(text: str) -> tuple[str, object]:
    """NAME=VALUE, the value read as TOML (a number, a string in quotes, a list)."""
    name, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"{text!r} is not NAME=VALUE")
    try:
        return name.strip(), tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError as err:
        raise argparse.ArgumentTypeError(f"{text!r}: the value is not TOML ({err})") from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--people", type=int, default=12)
    parser.add_argument("--frames", type=int, default=1800)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        type=setting, help="a TrackerConfig setting for every model")
    args = parser.parse_args()
    settings = dict(args.set)
    try:  # refuse a bad name or value before the runs
        TrackerConfig(**settings)
    except (TypeError, ValueError) as err:
        parser.error(f"--set: {err}")

    street = Street(people=args.people, frames=args.frames)
    said = ", ".join(f"{k} = {v}" for k, v in settings.items()) or "default settings"
    print(f"street: {args.people} people in view, {args.frames} frames at 30 fps, {said}; "
          f"seeds {' '.join(map(str, args.seeds))}\n")
    print(f"{'seed':<6}{'occlusion':<18}{'MOTA':>7}{'IDF1':>7}{'ID sw':>7}{'kept':>9}"
          f"{'false':>7}{'ECE':>7}{'steps/s':>9}")
    rows = {name: [] for name in OCCLUSION_NAMES}
    for seed in args.seeds:
        scores = run_demo(street, seed, settings=settings)["scores"]
        for name, s in scores.items():
            rows[name].append(s)
            kept = f"{s['kept']}/{s['occlusions']}"
            print(f"{seed:<6}{name:<18}{s['mota']:>7.3f}{s['idf1']:>7.3f}"
                  f"{s['id_switches']:>7d}{kept:>9}{s['false_boxes']:>7d}{s['ece']:>7.3f}"
                  f"{s['steps_per_second']:>9.0f}")
    print("\nover the seeds")
    base = rows["none"]
    for name, runs in rows.items():
        kept = sum(s["kept"] for s in runs)
        spells = sum(s["occlusions"] for s in runs)
        more = sum(s["kept"] > b["kept"] for s, b in zip(runs, base, strict=True))
        idf1 = sum(s["idf1"] >= b["idf1"] for s, b in zip(runs, base, strict=True))
        mota = sum(s["mota"] >= b["mota"] for s, b in zip(runs, base, strict=True))
        mean = {k: sum(s[k] for s in runs) / len(runs) for k in ("mota", "idf1", "ece")}
        line = (f"{name:<18}kept {kept}/{spells}, ID switches "
                f"{sum(s['id_switches'] for s in runs)}, false boxes "
                f"{sum(s['false_boxes'] for s in runs)}, mean MOTA {mean['mota']:.3f} IDF1 "
                f"{mean['idf1']:.3f} ECE {mean['ece']:.3f}")
        if name != "none":
            line += (f"; seeds keeping more than none {more}/{len(runs)}, IDF1 >= none "
                     f"{idf1}/{len(runs)}, MOTA >= none {mota}/{len(runs)}")
        print(line)


if __name__ == "__main__":
    main()
