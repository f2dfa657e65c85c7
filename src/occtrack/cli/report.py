"""`occtrack report RESULTS.json -o report.html`: one static HTML page of a benchmark run."""

from __future__ import annotations

import argparse
import sys

NAME = "report"
HELP = "one static HTML page of a benchmark run: tables, per-frame plots and a frame viewer"
DESCRIPTION = """\
Make one self-contained HTML page from the JSON of `occtrack benchmark DIR --json FILE`: the
combined and mean tables and, for each sequence, its table (HOTA, IDF1, MOTA, DetA, AssA, LocA,
FP, FN, IDSW, frames/s of every tracker), plots of each frame's GOSPA and of the number of
objects (ground truth and each tracker), and a frame viewer: a slider over the frames that
draws the ground truth and a chosen tracker's boxes (coasting boxes dashed, ids in colour).
The page needs no server and fetches nothing: open it in any browser, mail it, archive it.

The plots need the JSON made with --per-frame, the viewer with --keep-boxes; without them the
page says so and shows the tables. RESULTS.json "-" reads standard input. The output is
written whole or not at all. Needs only the core install (the benchmark that
makes the JSON needs the eval extra).

examples:
  occtrack benchmark $OCCTRACK_DATA --json run.json --keep-boxes --quiet
  occtrack report run.json -o report.html --show measurement-wise
  occtrack benchmark MOT17-04-FRCNN --trackers none,measurement-wise --json - --keep-boxes \\
      | occtrack report - -o mot17-04.html"""


def _count(n: int, what: str) -> str:
    return f"{n} {what}" + ("" if n == 1 else "s")


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("results", metavar="RESULTS.json",
                        help="the JSON of occtrack benchmark --json (- reads standard input)")
    parser.add_argument("-o", "--output", metavar="FILE", required=True,
                        help="the HTML page to write (- writes it to standard output)")
    parser.add_argument("--title", metavar="TEXT", help="the page's title (default: "
                        "occtrack benchmark and the sequences' names)")
    parser.add_argument("--show", metavar="TRACKER", help="the tracker the frame viewers open "
                        "with (default: the first)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing page")
    parser.add_argument("--quiet", action="store_true", help="no summary line")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from occtrack.io.atomic import atomic_write, check_output
    from occtrack.viz.report import build_page, load_report

    check_output(args.output, args.force, inputs=[args.results])
    report = load_report(args.results)
    source = "standard input" if args.results == "-" else Path(args.results).name
    page = build_page(report, source=source, title=args.title, show=args.show)
    with atomic_write(args.output, args.force) as fh:
        fh.write(page)
    if not args.quiet:
        entries = report["sequences"].values()
        plots = sum(bool(entry.get("per_frame")) for entry in entries)
        viewers = sum(bool((entry.get("boxes") or {}).get("trackers")) for entry in entries)
        where = "standard output" if args.output == "-" else args.output
        note = ("" if viewers == len(entries) else
                "; for plots and the frame viewer make the JSON with occtrack benchmark DIR "
                "--json FILE --keep-boxes")
        if report.get("layout") == "kitti":
            note = f" ({', '.join(report['classes'])} apart; KITTI runs keep no boxes)"
        size = len(page.encode())
        size_text = f"{size / 1e6:.1f} MB" if size >= 1e6 else f"{size / 1e3:.0f} kB"
        print(f"{where}: {_count(len(entries), 'sequence')}, "
              f"{_count(len(report['trackers']), 'tracker')}, {plots} with plots, {viewers} "
              f"with a frame viewer, {size_text}{note}",
              file=sys.stderr if args.output == "-" else sys.stdout)
    return 0
