# ruff: noqa: E501  (the summaries are prose, one string a subcommand)
"""Write docs/cli.md from occtrack's own argparse parser: a section a subcommand (and a
`reproduce` / `simulate` scene), its usage line and a table of its arguments as its `--help`
gives them. Run it when an option changes:

    python docs/gen_cli.py docs/cli.md

(tests/test_docs.py checks that every option of every `--help` is on the page.)
"""

import argparse
import sys

from occtrack.cli import build_parser

SUMMARY = {
    "benchmark": "Tracks every sequence folder under DIR (or a KITTI tracking folder) with occtrack's three occlusion models and the box-only peers, scores them (TrackEval) and prints a table per sequence, the combined and the mean table. Each (sequence, tracker) run is a Dask task (`--workers`, `--scheduler`, `--sequential`). See [Benchmarks against the peers](benchmarks.md).",
    "bev": "Tracks a KITTI file's 3D boxes on the ground up to one frame and draws that frame from above: the sensor and its field of view, the detections, the true boxes (`--gt`), the tracks and those held while hidden with the shadows that hide them. Needs the `viz` extra. See [KITTI in 3D, from above](kitti-3d.md).",
    "calibrate": "Measures the detector as the tracker models it (detection probability by visibility, its memory, false boxes by score, edge noise) on labelled data, and writes it as a settings file for `occtrack track --config`. See [Calibration and sweeps](calibration-sweeps.md).",
    "demo": "Tracks a built-in street (people and detector measured on MOT17) under none, object-wise and measurement-wise occlusion and prints what occlusion buys; `--figure` draws one full occlusion. See [Choosing an occlusion model](occlusion-models.md#the-demo-street).",
    "eval": "Scores a result file against ground truth: MOTA, MOTP, IDF1, HOTA, MT/ML, FP, FN, ID switches, GOSPA, under the `mot17`, `paper` or `kitti` protocol; `--calibration` adds the reliability table of the confidence column. See [Getting started](getting-started.md#track-and-score-a-mot17-sequence) and [The confidence](confidence.md).",
    "eval-scans": "Scores a tracks file (`occtrack track-scans`) against the leg-tracker benchmark's annotated people (`bag_time,id,x,y,z`) by the benchmark's rules: CLEAR MOT at 0.75 m, each annotation against the last scan at or before it; valid matches, ID switches, misses, false positives, MOTP, MOTA with and without false positives. See [Lidar scans](lidar.md).",
    "foursquare": "Exact posteriors of the paper's four-square example (Table I) under the three occlusion models. See [The paper's experiments](paper.md).",
    "lidar": "The separable lidar beam likelihood that measurement-wise occlusion derives, beside its value from simulated beams. See [The paper's experiments](paper.md).",
    "render": "Draws tracks on the frames they were made from, to a video, a picture or a folder of pictures; a detection file is tracked first. Needs the `viz` extra. See [Benchmarks](benchmarks.md#seeing-the-tracks-on-your-frames).",
    "report": "One static HTML page of a benchmark run (`occtrack benchmark --json`): tables, reliability diagrams, per-frame plots and a frame viewer. See [Benchmarks](benchmarks.md#a-page-for-a-benchmark-run).",
    "reproduce": "Reruns one of the paper's tables, ours beside the paper's values, or the lidar study. Each table is a sub-subcommand with its own options. See [The paper's experiments](paper.md).",
    "simulate": "A simulated scene: the paper's highway tracked and scored, or people walking past a lidar written as scan files. See [The paper's experiments](paper.md) and [Lidar scans](lidar.md).",
    "simulate-detections": "Seeded Faster-RCNN-like detections from a MOTChallenge ground-truth file (occlusion-dependent misses, edge noise, false boxes, NMS).",
    "sweep": "Trackers x settings x seeds from a TOML spec, on Dask, into one Parquet table. See [Calibration and sweeps](calibration-sweeps.md).",
    "track": "Tracks a MOTChallenge or KITTI detection file and writes a result file (`frame,id,left,top,width,height,confidence,-1,-1,-1`, or KITTI's format). See [Getting started](getting-started.md) and [Tracking in your own loop](api.md#a-settings-file).",
    "track-scans": "Tracks people through a 2-D lidar scan file (`--poses` for a moving sensor) and writes `time,id,x,y,vx,vy,existence,confidence,occluded`. See [Lidar scans](lidar.md).",
}

def cell(text):
    return " ".join(text.split()).replace("|", "\\|")

def table(parser):
    fmt = parser._get_formatter()
    rows = []
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            continue
        h = cell(fmt._expand_help(a)) if a.help else ""
        if a.option_strings:
            metavar = fmt._format_args(a, a.dest.upper()) if a.nargs != 0 else ""
            name = ", ".join(f"`{o} {metavar}`" if metavar else f"`{o}`" for o in a.option_strings)
        else:
            name = f"`{fmt._format_args(a, a.dest)}`"
        rows.append(f"| {name} | {h} |")
    return ["| argument | what it does |", "|---|---|", *rows]

def usage(parser):
    return ["```text", parser.format_usage().strip(), "```"]

out = ["# Command line", "",
       "Every subcommand has its own `--help`, which says more than this page (file formats, the",
       "JSON written, the protocols). This page lists each subcommand's arguments as its `--help`",
       "gives them (it is generated from occtrack's own parser, and a test checks it against",
       "`--help`). Exit status, atomic outputs and bad input: [Reliability](reliability.md).",
       "Options common to the whole program go before the subcommand:", "",
       "| argument | what it does |", "|---|---|",
       "| `--version` | show program's version number and exit |",
       "| `--debug` | show the traceback of a failure instead of a one-line message (`occtrack --debug track ...`) |",
       ""]
p = build_parser("*")
sub = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)][0]
for name in sorted(sub.choices):
    sp = sub.choices[name]
    out += [f"## occtrack {name}", "", SUMMARY[name], ""]
    out += usage(sp) + [""] + table(sp) + [""]
    nested = [a for a in sp._actions if isinstance(a, argparse._SubParsersAction)]
    if nested:
        helps = {c.dest: c.help for c in nested[0]._choices_actions}
        for sname, ssp in nested[0].choices.items():
            out += [f"### occtrack {name} {sname}", "", cell(helps.get(sname, "")) + ".", ""]
            out += usage(ssp) + [""] + table(ssp) + [""]
open(sys.argv[1], "w").write("\n".join(out).rstrip() + "\n")
