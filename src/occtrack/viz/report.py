"""One static HTML page for a benchmark run (`occtrack report`).

The page is a single file that needs no server and fetches nothing: the tables are HTML, the
per-frame plots are SVG drawn here, and the frame viewer is a few lines of JavaScript that draw
the boxes on a canvas from the data embedded in the page. Its input is the JSON that
`occtrack benchmark DIR --json FILE` writes (`occtrack.experiments.benchmark`); the plots need
it made with `--per-frame` and the viewer with `--keep-boxes`, and without them the page says
so and shows the tables alone.
"""

from __future__ import annotations

import html
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from occtrack import __version__
from occtrack.errors import OcctrackError

__all__ = ["COLUMNS", "build_page", "check_report", "class_views", "load_report",
           "start_frame"]

# key, title, format, which way is better, what it is
COLUMNS = (
    ("hota", "HOTA", ".3f", "high", "Higher Order Tracking Accuracy: the geometric mean of "
     "DetA and AssA, averaged over 19 IoU thresholds 0.05 to 0.95"),
    ("idf1", "IDF1", ".3f", "high", "identity F1: the share of boxes matched to the right "
     "identity, over truth and reported boxes"),
    ("mota", "MOTA", ".3f", "high", "multiple-object tracking accuracy: 1 - (FN + FP + IDSW) "
     "/ true boxes (IoU >= 0.5)"),
    ("deta", "DetA", ".3f", "high", "detection accuracy (HOTA's detection part)"),
    ("assa", "AssA", ".3f", "high", "association accuracy (HOTA's association part)"),
    ("loca", "LocA", ".3f", "high", "localisation accuracy: mean IoU of matched boxes"),
    ("fp", "FP", "d", "low", "false positives: reported boxes matched to no true box"),
    ("fn", "FN", "d", "low", "false negatives: true boxes matched to no reported box"),
    ("id_switches", "IDSW", "d", "low", "identity switches"),
    ("ece", "ECE", ".3f", "low", "expected calibration error of the confidence column: "
     "the boxes' mean gap between the confidence a box reports and the share of such boxes "
     "right (matched at IoU >= 0.5), over 10 confidence bins"),
    ("frames_per_second", "frames/s", ".0f", "high",
     "frames per second of the tracker call alone (scoring not counted)"),
)
MEAN_KEYS = ("hota", "idf1", "mota", "deta", "assa", "loca", "ece")
PALETTE = ("#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
           "#17becf", "#bcbd22", "#7f7f7f")
TRUTH_COLOR = "#111111"
HOW_TO = ("occtrack benchmark DIR --json FILE --keep-boxes (plots and viewer) or --per-frame "
          "(plots)")

_CHART_W, _CHART_H = 960, 230
_DIAGRAM = 300  # the reliability diagram's side
_DIAGRAM_TITLE = ("Reliability: per confidence bin (tenths), the share of boxes right (matched "
                  "one to one at IoU >= 0.5) against the confidence they report; on the "
                  "diagonal a box said to be 90 % likely is right 90 % of the time")
_LEFT, _RIGHT, _TOP, _BOTTOM = 52, 14, 12, 34


# ---------------------------------------------------------------------------------------------
# input


def _fail(path: str, what: str) -> OcctrackError:
    return OcctrackError(f"not an occtrack benchmark JSON file: {what}; make one with "
                         f"occtrack benchmark DIR --json FILE", path)


def load_report(path: str | os.PathLike) -> dict:
    """Read and check the JSON of `occtrack benchmark --json` ("-": standard input)."""
    name = str(path)
    try:
        if name == "-":
            text = sys.stdin.read()
        else:
            text = Path(path).read_text(encoding="utf-8")
    except IsADirectoryError:
        raise OcctrackError("is a folder; give the JSON file of occtrack benchmark --json",
                            name) from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise _fail(name, f"invalid JSON ({err.msg}, line {err.lineno} column {err.colno})"
                    ) from None
    check_report(data, name)
    return data


def _need(condition: bool, path: str, what: str) -> None:
    if not condition:
        raise _fail(path, what)


def class_views(report: dict, path: str = "<report>") -> list[tuple[str, dict]]:
    """The report as (class, report of that class) pairs, each of the MOTChallenge shape: a
    KITTI report (`occtrack.experiments.benchmark_kitti`) gives one a class that has a scored
    true box in some sequence, holding those sequences; any other report is one view ("")."""
    if not (isinstance(report, dict) and report.get("layout") == "kitti"):
        return [("", report)]
    for key in ("classes", "trackers", "sequences", "combined", "mean"):
        _need(key in report, path, f"no {key!r} key")
    views = []
    try:
        for cls in report["classes"]:
            sequences = {}
            for name, entry in report["sequences"].items():
                part = entry["classes"][cls]
                if part["truth"]:
                    sequences[name] = {"frames": entry["frames"], "fps": entry["fps"],
                                       "image_size": entry["image_size"],
                                       "trackers": part["trackers"],
                                       "calibration": part["calibration"]}
            if sequences:
                views.append((cls, {
                    "protocol": report.get("protocol"), "trackers": report["trackers"],
                    "sequences": sequences, "combined_over": len(report["sequences"]),
                    "combined": {"method": report["combined"].get("method", ""),
                                 **report["combined"]["classes"][cls]},
                    "mean": {"method": report["mean"].get("method", ""),
                             **report["mean"]["classes"][cls]}}))
    except (KeyError, TypeError, AttributeError) as err:
        raise _fail(path, f"a KITTI report without {err}") from None
    _need(bool(views), path, "no class has a scored true box in any sequence")
    return views


def check_report(data: object, path: str = "<report>") -> None:
    """Raise OcctrackError, naming `path` and what is wrong, unless `data` has the shape
    `occtrack benchmark --help` gives (the per-frame lists and boxes are optional; a KITTI
    report is checked class by class)."""
    _need(isinstance(data, dict), path, "the top level is not an object")
    assert isinstance(data, dict)
    if data.get("layout") == "kitti":
        for _, view in class_views(data, path):
            check_report(view, path)
        return
    for key in ("trackers", "sequences", "combined", "mean"):
        _need(key in data, path, f"no {key!r} key")
    trackers = data["trackers"]
    _need(isinstance(trackers, list) and all(isinstance(t, str) for t in trackers), path,
          "'trackers' is not a list of names")
    _need(isinstance(data["sequences"], dict) and bool(data["sequences"]), path,
          "'sequences' is not an object of sequences")
    for name, entry in data["sequences"].items():
        where = f"sequence {name!r}"
        _need(isinstance(entry, dict), path, f"{where} is not an object")
        for key in ("frames", "fps", "image_size", "trackers"):
            _need(key in entry, path, f"{where} has no {key!r}")
        frames = entry["frames"]
        _need(isinstance(frames, int) and frames >= 0, path, f"{where}: bad 'frames'")
        size = entry["image_size"]
        _need(isinstance(size, list) and len(size) == 2
              and all(isinstance(v, int | float) and v > 0 for v in size), path,
              f"{where}: 'image_size' is not [width, height]")
        _need(isinstance(entry["trackers"], dict), path, f"{where}: 'trackers' is not an object")
        counts = entry.get("per_frame")
        if counts is not None:
            _need(isinstance(counts, dict) and len(counts.get("truth", ())) == frames, path,
                  f"{where}: 'per_frame' has no 'truth' list of {frames} frames")
            for tracker, lists in counts.get("trackers", {}).items():
                for key in ("gospa", "missed", "false", "estimates"):
                    _need(isinstance(lists, dict) and len(lists.get(key, ())) == frames, path,
                          f"{where}: per_frame of {tracker!r} has no {key!r} list of "
                          f"{frames} frames")
        _check_calibration(entry.get("calibration"), path, where)
        boxes = entry.get("boxes")
        if boxes is not None:
            _need(isinstance(boxes, dict) and "truth" in boxes, path,
                  f"{where}: 'boxes' has no 'truth'")
            for tracker, table in [("truth", boxes["truth"]),
                                   *boxes.get("trackers", {}).items()]:
                _need(isinstance(table, dict)
                      and all(isinstance(table.get(k), list) for k in ("frame", "id", "ltwh"))
                      and len(table["frame"]) == len(table["id"]) == len(table["ltwh"]), path,
                      f"{where}: boxes of {tracker!r} are not equal lists frame, id, ltwh")
    for part in ("combined", "mean"):
        _need(isinstance(data[part], dict) and isinstance(data[part].get("trackers"), dict),
              path, f"{part!r} has no 'trackers' object")
    _check_calibration(data["combined"].get("calibration"), path, "'combined'")


def _check_calibration(tables: object, path: str, where: str) -> None:
    """The optional reliability tables, {tracker: {"ece", "boxes", "confidence", "right"}}."""
    if tables is None:
        return
    _need(isinstance(tables, dict), path, f"{where}: 'calibration' is not an object")
    assert isinstance(tables, dict)
    for tracker, table in tables.items():
        _need(isinstance(table, dict) and isinstance(table.get("boxes"), list)
              and all(isinstance(table.get(k), list) and len(table[k]) == len(table["boxes"])
                      for k in ("confidence", "right")), path,
              f"{where}: the calibration of {tracker!r} is not equal lists boxes, "
              f"confidence, right")


# ---------------------------------------------------------------------------------------------
# pieces of the page


def _esc(text: object) -> str:
    return html.escape(str(text), quote=True)


def _colors(trackers: list[str]) -> dict[str, str]:
    return {name: PALETTE[i % len(PALETTE)] for i, name in enumerate(trackers)}


def _cell(value: object, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "&ndash;"
    try:
        return format(int(value) if fmt == "d" else float(value), fmt)
    except (TypeError, ValueError):
        return _esc(value)


def _best(rows: dict[str, dict], key: str, better: str) -> float | None:
    values = [v[key] for v in rows.values() if isinstance(v.get(key), int | float)
              and math.isfinite(v[key])]
    if len(values) < 2:
        return None
    return max(values) if better == "high" else min(values)


def _table(rows: dict[str, dict], colors: dict[str, str], columns=COLUMNS,
           table_id: str = "") -> str:
    """One HTML table, a row per tracker, the best value of each column in bold."""
    head = "".join(f'<th title="{_esc(tip)}">{_esc(title)}</th>'
                   for _, title, _, _, tip in columns)
    best = {key: _best(rows, key, better) for key, _, _, better, _ in columns}
    body = []
    for name, values in rows.items():
        cells = []
        for key, _, fmt, _, _ in columns:
            value = values.get(key)
            text = _cell(value, fmt)
            mark = best[key] is not None and text == _cell(best[key], fmt)
            cells.append(f'<td class="best">{text}</td>' if mark else f"<td>{text}</td>")
        swatch = f'<span class="swatch" style="background:{colors.get(name, "#888")}"></span>'
        body.append(f'<tr><th scope="row">{swatch}{_esc(name)}</th>{"".join(cells)}</tr>')
    ident = f' id="{_esc(table_id)}"' if table_id else ""
    return (f'<table class="scores"{ident}><thead><tr><th>tracker</th>{head}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table>')


def _nice_step(span: float, count: int = 5) -> float:
    raw = max(span, 1e-9) / count
    magnitude = 10 ** math.floor(math.log10(raw))
    return next(m * magnitude for m in (1, 2, 2.5, 5, 10) if m * magnitude >= raw * 0.999)


def _moving_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Centred mean over `window` frames, over the frames there are at the ends."""
    if window <= 1 or len(values) < 2:
        return values
    kernel = np.ones(window)
    total = np.convolve(values, kernel, mode="same")
    count = np.convolve(np.ones(len(values)), kernel, mode="same")
    return total / count


def _chart(title: str, frames: int, series: list[tuple[str, str, np.ndarray, str]],
           y_label: str, seq_index: int) -> str:
    """An SVG line chart over frames 1..frames: `series` are (tracker, colour, values, kind)
    with kind "raw" (faint), "line" or "truth". A cursor marks the viewer's frame."""
    width, height = _CHART_W - _LEFT - _RIGHT, _CHART_H - _TOP - _BOTTOM
    top = max([float(np.max(v)) for _, _, v, _ in series if len(v)] + [0.0])
    step = _nice_step(top if top > 0 else 1.0, 4)
    y_max = step * max(1, math.ceil(top / step - 1e-9))
    last = max(frames, 2)

    def x(f: float) -> float:
        return _LEFT + (f - 1) / (last - 1) * width

    def y(v: float) -> float:
        return _TOP + height - v / y_max * height

    parts = [f'<svg class="chart" viewBox="0 0 {_CHART_W} {_CHART_H}" role="img" '
             f'aria-label="{_esc(title)}" data-x0="{_LEFT}" data-x1="{_LEFT + width}" '
             f'data-frames="{frames}" data-seq="{seq_index}">',
             f'<rect x="{_LEFT}" y="{_TOP}" width="{width}" height="{height}" class="plot"/>']
    tick = 0.0
    while tick <= y_max + 1e-9:
        parts.append(f'<line x1="{_LEFT}" x2="{_LEFT + width}" y1="{y(tick):.1f}" '
                     f'y2="{y(tick):.1f}" class="grid"/>'
                     f'<text x="{_LEFT - 6}" y="{y(tick) + 4:.1f}" class="tick" '
                     f'text-anchor="end">{tick:g}</text>')
        tick += step
    xstep = max(1, int(_nice_step(last - 1, 8)))
    for f in range(xstep, last + 1, xstep):
        parts.append(f'<line x1="{x(f):.1f}" x2="{x(f):.1f}" y1="{_TOP + height}" '
                     f'y2="{_TOP + height + 4}" class="axis"/>'
                     f'<text x="{x(f):.1f}" y="{_TOP + height + 17}" class="tick" '
                     f'text-anchor="middle">{f}</text>')
    parts.append(f'<text x="{_LEFT + width / 2}" y="{_CHART_H - 2}" class="label" '
                 f'text-anchor="middle">frame</text>'
                 f'<text x="12" y="{_TOP + height / 2}" class="label" text-anchor="middle" '
                 f'transform="rotate(-90 12 {_TOP + height / 2})">{_esc(y_label)}</text>')
    for name, color, values, kind in series:
        if not len(values):
            continue
        points = " ".join(f"{x(i + 1):.1f},{y(float(v)):.1f}" for i, v in enumerate(values))
        parts.append(f'<polyline class="{kind}" data-tracker="{_esc(name)}" stroke="{color}" '
                     f'points="{points}"/>')
    parts.append(f'<line class="cursor" x1="{_LEFT}" x2="{_LEFT}" y1="{_TOP}" '
                 f'y2="{_TOP + height}"/>')
    parts.append("</svg>")
    return f'<figure><figcaption>{_esc(title)}</figcaption>{"".join(parts)}</figure>'


def _reliability_diagram(tables: dict | None, colors: dict[str, str], title: str) -> str:
    """An SVG reliability diagram: per tracker and confidence bin, the share of boxes right
    against their mean confidence (a dot, its area the bin's share of the boxes); a
    calibrated tracker lies on the diagonal."""
    if not tables:
        return ""
    size, pad = _DIAGRAM, 40
    inner = size - 2 * pad + 10

    def x(v: float) -> float:
        return pad + v * inner

    def y(v: float) -> float:
        return pad - 20 + inner - v * inner

    parts = [f'<svg class="diagram" viewBox="0 0 {size + 230} {size}" role="img" '
             f'aria-label="{_esc(title)}">',
             f'<rect x="{x(0)}" y="{y(1)}" width="{inner}" height="{inner}" class="plot"/>',
             f'<line x1="{x(0)}" y1="{y(0)}" x2="{x(1)}" y2="{y(1)}" class="diagonal"/>']
    for tick in (0.0, 0.25, 0.5, 0.75, 1.0):
        parts.append(f'<text x="{x(tick):.1f}" y="{y(0) + 15:.1f}" class="tick" '
                     f'text-anchor="middle">{tick:g}</text>'
                     f'<text x="{x(0) - 5:.1f}" y="{y(tick) + 4:.1f}" class="tick" '
                     f'text-anchor="end">{tick:g}</text>')
    parts.append(f'<text x="{x(0.5):.1f}" y="{size - 4}" class="label" text-anchor="middle">'
                 f'confidence (mean in the bin)</text>'
                 f'<text x="11" y="{y(0.5):.1f}" class="label" text-anchor="middle" '
                 f'transform="rotate(-90 11 {y(0.5):.1f})">share right</text>')
    for row, (name, table) in enumerate(tables.items()):
        color = colors.get(name, "#888")
        total = max(sum(int(b or 0) for b in table["boxes"]), 1)
        points = [(c, r, b) for c, r, b in zip(table["confidence"], table["right"],
                                                  table["boxes"], strict=True)
                  if b and c is not None and r is not None]
        line = " ".join(f"{x(c):.1f},{y(r):.1f}" for c, r, _ in points)
        parts.append(f'<g data-tracker="{_esc(name)}"><polyline points="{line}" '
                     f'stroke="{color}"/>')
        for c, r, b in points:
            radius = 2.0 + 10.0 * math.sqrt(b / total)
            parts.append(f'<circle cx="{x(c):.1f}" cy="{y(r):.1f}" r="{radius:.1f}" '
                         f'fill="{color}"><title>{_esc(name)}: {b} boxes, confidence '
                         f'{c:.3f}, right {r:.3f}</title></circle>')
        ece = table.get("ece")
        label = f"{name} (ECE {ece:.3f})" if isinstance(ece, int | float) else name
        parts.append(f'<text x="{size - 10}" y="{pad - 10 + 16 * row}" class="key" '
                     f'style="fill:{color}">&#9679; {_esc(label)}</text></g>')
    parts.append("</svg>")
    return f'<figure><figcaption>{_esc(title)}</figcaption>{"".join(parts)}</figure>'


def _legend(names: list[str], colors: dict[str, str], totals: dict[str, float],
            truth: bool) -> str:
    items = []
    if truth:
        items.append(f'<span class="key"><span class="swatch" style="background:'
                     f'{TRUTH_COLOR}"></span>ground truth</span>')
    for name in names:
        total = f" (GOSPA {totals[name]:.0f})" if name in totals else ""
        items.append(f'<button type="button" class="key" data-tracker="{_esc(name)}" '
                     f'aria-pressed="true" title="show or hide {_esc(name)} in the plots">'
                     f'<span class="swatch" style="background:{colors[name]}"></span>'
                     f'{_esc(name)}{total}</button>')
    return f'<div class="legend">{"".join(items)}</div>'


def _plots(entry: dict, colors: dict[str, str], seq_index: int) -> str:
    counts = entry.get("per_frame")
    if not counts or not counts.get("trackers"):
        return (f'<p class="note">No per-frame data for this sequence: make the JSON with '
                f'{_esc(HOW_TO)}.</p>')
    frames = int(entry["frames"])
    fps = float(entry.get("fps") or 1)
    window = max(1, round(fps))
    names = [n for n in entry["trackers"] if n in counts["trackers"]]
    gospa_series, card_series, totals = [], [], {}
    for name in names:
        values = np.asarray(counts["trackers"][name]["gospa"], dtype=float)
        totals[name] = float(values.sum())
        gospa_series.append((name, colors[name], values, "raw"))
    for name in names:
        values = np.asarray(counts["trackers"][name]["gospa"], dtype=float)
        gospa_series.append((name, colors[name], _moving_mean(values, window), "line"))
        card_series.append((name, colors[name],
                            np.asarray(counts["trackers"][name]["estimates"], dtype=float),
                            "line"))
    card_series.append(("ground truth", TRUTH_COLOR,
                        np.asarray(counts["truth"], dtype=float), "truth"))
    return (_legend(names, colors, totals, truth=True)
            + _chart(f"GOSPA per frame (c = 1, 1 - IoU, alpha = 2; lower is better): faint "
                     f"each frame, solid the mean over {window} frames (1 s)", frames,
                     gospa_series, "GOSPA", seq_index)
            + _chart("Objects per frame: ground truth (black) and each tracker's reported "
                     "boxes scored", frames, card_series, "objects", seq_index))


def _viewer(entry: dict, seq_index: int, show: str | None = None) -> str:
    boxes = entry.get("boxes")
    if not boxes or not boxes.get("trackers"):
        return ('<p class="note">No boxes for this sequence, so no frame viewer: make the '
                'JSON with occtrack benchmark DIR --json FILE --keep-boxes.</p>')
    frames = int(entry["frames"])
    w, h = (float(v) for v in entry["image_size"])
    scale = 960.0 / w
    options = "".join(f'<option value="{_esc(name)}"{" selected" if name == show else ""}>'
                      f"{_esc(name)}</option>" for name in boxes["trackers"])
    return f"""<div class="viewer" data-seq="{seq_index}">
<div class="controls">
<label>tracker <select class="tracker">{options}</select></label>
<label><input type="checkbox" class="truth" checked> ground truth</label>
<button type="button" class="prev" title="previous frame">&#9664;</button>
<button type="button" class="play" title="play or pause">play</button>
<button type="button" class="next" title="next frame">&#9654;</button>
<input type="range" class="frame" min="1" max="{max(frames, 1)}" value="1" step="1"
 aria-label="frame">
<output class="frame-number">frame 1 / {frames}</output>
</div>
<canvas width="960" height="{round(h * scale)}" data-scale="{scale:.6f}"></canvas>
<p class="info"></p>
<p class="hint">Ground truth (the boxes the protocol scores) dashed black; each track in a
colour of its own with its id; a box reported without a detection (coasting) dashed, labelled
"occ" when its miss is put down to occlusion; grey dotted: a reported box the protocol leaves
out (on a distractor or of another class). Click a plot to jump to its frame.</p>
</div>"""


# ---------------------------------------------------------------------------------------------
# the page


STYLE = """
:root { color-scheme: light; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif;
       margin: 0; color: #1d1d1f; background: #fafafa; }
main { max-width: 1000px; margin: 0 auto; padding: 16px 20px 48px; }
h1 { font-size: 24px; margin: 8px 0 4px; }
h2 { font-size: 19px; margin: 28px 0 6px; border-bottom: 1px solid #ddd; padding-bottom: 3px; }
p { margin: 4px 0 8px; }
.meta { color: #555; }
nav a { margin-right: 12px; }
table.scores { border-collapse: collapse; margin: 6px 0 10px; background: #fff;
               font-variant-numeric: tabular-nums; }
table.scores th, table.scores td { padding: 3px 9px; border-bottom: 1px solid #e4e4e4; }
table.scores td { text-align: right; }
table.scores thead th { background: #f0f0f0; text-align: right; cursor: help; }
table.scores thead th:first-child, table.scores tbody th { text-align: left; }
table.scores tbody th { font-weight: 500; white-space: nowrap; }
td.best { font-weight: 700; }
.swatch { display: inline-block; width: 10px; height: 10px; border-radius: 2px;
          margin-right: 6px; vertical-align: baseline; }
.legend { margin: 8px 0 2px; }
.key { font: inherit; background: #fff; border: 1px solid #ccc; border-radius: 4px;
       padding: 1px 8px; margin: 0 6px 4px 0; display: inline-block; }
button.key { cursor: pointer; }
button.key[aria-pressed="false"] { opacity: 0.4; text-decoration: line-through; }
figure { margin: 6px 0 10px; }
figcaption { color: #444; font-size: 13px; }
svg.chart { width: 100%; height: auto; background: #fff; cursor: crosshair; }
svg.chart .plot { fill: #fff; stroke: #bbb; }
svg.diagram { width: 100%; max-width: 700px; height: auto; background: #fff; }
svg.diagram .plot { fill: #fff; stroke: #bbb; }
svg.diagram .diagonal { stroke: #999; stroke-dasharray: 4 3; }
svg.diagram .tick { font-size: 11px; fill: #555; }
svg.diagram .label { font-size: 12px; fill: #333; }
svg.diagram .key { font-size: 12px; }
svg.diagram polyline { fill: none; stroke-width: 1.2; opacity: 0.6; }
svg.diagram circle { opacity: 0.8; }
svg.chart .grid { stroke: #eee; }
svg.chart .axis { stroke: #888; }
svg.chart .tick { font-size: 11px; fill: #555; }
svg.chart .label { font-size: 12px; fill: #333; }
svg.chart polyline { fill: none; stroke-linejoin: round; }
svg.chart polyline.raw { stroke-width: 0.8; opacity: 0.22; }
svg.chart polyline.line { stroke-width: 1.6; }
svg.chart polyline.truth { stroke-width: 2.4; }
svg.chart .off { display: none; }
svg.chart .cursor { stroke: #000; stroke-width: 1; stroke-dasharray: 3 3; }
.viewer { background: #fff; border: 1px solid #ddd; border-radius: 6px; padding: 8px;
          margin: 8px 0; }
.controls { display: flex; flex-wrap: wrap; align-items: center; gap: 8px; margin-bottom: 6px; }
.controls input[type=range] { flex: 1 1 260px; }
.controls output { font-variant-numeric: tabular-nums; min-width: 9em; }
.viewer canvas { width: 100%; height: auto; display: block; background: #f2f2f2; }
.info { font-variant-numeric: tabular-nums; margin-top: 6px; }
.hint, .note { color: #666; font-size: 12.5px; }
.note { background: #fff8e0; border: 1px solid #ecd98b; padding: 6px 9px; border-radius: 4px; }
footer { color: #777; font-size: 12px; margin-top: 30px; }
"""

SCRIPT = r"""
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("occtrack-data").textContent);

  function idColor(id) {
    return "hsl(" + ((id * 137.508) % 360).toFixed(1) + ",75%,42%)";
  }

  function index(table, frames) {
    // starts[f] .. starts[f + 1] are the rows of frame f (rows are in frame order)
    var starts = new Int32Array(frames + 2), f = 1, i, n = table.frame.length;
    for (i = 0; i < n; i++) {
      while (f <= table.frame[i] && f <= frames + 1) { starts[f] = i; f++; }
    }
    for (; f <= frames + 1; f++) { starts[f] = n; }
    table.starts = starts;
    if (table.ignored && !table.ignoredSet) {
      table.ignoredSet = new Uint8Array(n);
      table.ignored.forEach(function (r) { table.ignoredSet[r] = 1; });
    }
    return table;
  }

  function setCursor(section, seqIndex, frame) {
    section.querySelectorAll('svg.chart[data-seq="' + seqIndex + '"]').forEach(function (svg) {
      var x0 = +svg.dataset.x0, x1 = +svg.dataset.x1, n = Math.max(+svg.dataset.frames, 2);
      var x = x0 + (frame - 1) / (n - 1) * (x1 - x0);
      var line = svg.querySelector(".cursor");
      line.setAttribute("x1", x.toFixed(1));
      line.setAttribute("x2", x.toFixed(1));
    });
  }

  function setupViewer(viewer) {
    var seqIndex = +viewer.dataset.seq, seq = data.sequences[seqIndex];
    var section = viewer.closest("section");
    var canvas = viewer.querySelector("canvas"), ctx = canvas.getContext("2d");
    var scale = +canvas.dataset.scale;
    var select = viewer.querySelector("select.tracker");
    var truthBox = viewer.querySelector("input.truth");
    var slider = viewer.querySelector("input.frame");
    var label = viewer.querySelector("output.frame-number");
    var info = viewer.querySelector(".info");
    var play = viewer.querySelector("button.play");
    var timer = null;
    var truth = index(seq.boxes.truth, seq.frames);
    Object.keys(seq.boxes.trackers).forEach(function (name) {
      index(seq.boxes.trackers[name], seq.frames);
    });

    function box(row, table, color, dash, width) {
      var b = table.ltwh[row];
      ctx.setLineDash(dash);
      ctx.lineWidth = width;
      ctx.strokeStyle = color;
      ctx.strokeRect(b[0] * scale, b[1] * scale, b[2] * scale, b[3] * scale);
      return b;
    }

    function draw() {
      var frame = +slider.value, name = select.value;
      var table = seq.boxes.trackers[name], r, b, n = 0, coasting = 0, occluded = 0;
      ctx.setLineDash([]);
      ctx.fillStyle = "#f2f2f2";
      ctx.fillRect(0, 0, canvas.width, canvas.height);
      ctx.strokeStyle = "#bbb";
      ctx.lineWidth = 1;
      ctx.strokeRect(0.5, 0.5, canvas.width - 1, canvas.height - 1);
      var truthCount = truth.starts[frame + 1] - truth.starts[frame];
      if (truthBox.checked) {
        for (r = truth.starts[frame]; r < truth.starts[frame + 1]; r++) {
          box(r, truth, "#111", [5, 3], 1.4);
        }
      }
      ctx.font = "bold 12px system-ui, sans-serif";
      for (r = table.starts[frame]; r < table.starts[frame + 1]; r++) {
        var id = table.id[r], state = table.state ? table.state[r] : 0;
        if (table.ignoredSet && table.ignoredSet[r]) {
          box(r, table, "#999", [2, 3], 1.2);
          continue;
        }
        n++;
        if (state > 0) { coasting++; }
        if (state === 2) { occluded++; }
        b = box(r, table, idColor(id), state > 0 ? [7, 4] : [], 2.2);
        var text = String(id) + (state === 2 ? " occ" : "");
        var tw = ctx.measureText(text).width + 6;
        ctx.setLineDash([]);
        ctx.fillStyle = idColor(id);
        var top = b[1] * scale >= 15 ? b[1] * scale - 15 : b[1] * scale;
        ctx.fillRect(b[0] * scale, top, tw, 15);
        ctx.fillStyle = "#fff";
        ctx.fillText(text, b[0] * scale + 3, top + 12);
      }
      label.textContent = "frame " + frame + " / " + seq.frames;
      var parts = ["frame " + frame + ": " + truthCount + " true objects", name + " " + n +
                   " boxes scored" + (table.state ? " (" + coasting + " coasting, " +
                   occluded + " put down to occlusion)" : "")];
      var pf = seq.per_frame && seq.per_frame.trackers[name];
      if (pf) {
        parts.push("GOSPA " + pf.gospa[frame - 1].toFixed(2) + " (" + pf.missed[frame - 1] +
                   " missed, " + pf.false[frame - 1] + " false)");
      }
      info.textContent = parts.join("; ");
      canvas.dataset.drawn = String(n + (truthBox.checked ? truthCount : 0));
      setCursor(section, seqIndex, frame);
    }

    function go(frame) {
      slider.value = String(Math.min(Math.max(frame, 1), seq.frames));
      draw();
    }

    function stop() {
      if (timer !== null) { clearInterval(timer); timer = null; play.textContent = "play"; }
    }

    slider.addEventListener("input", draw);
    select.addEventListener("change", draw);
    truthBox.addEventListener("change", draw);
    viewer.querySelector("button.prev").addEventListener("click", function () {
      stop(); go(+slider.value - 1);
    });
    viewer.querySelector("button.next").addEventListener("click", function () {
      stop(); go(+slider.value + 1);
    });
    play.addEventListener("click", function () {
      if (timer !== null) { stop(); return; }
      if (+slider.value >= seq.frames) { go(1); }
      play.textContent = "pause";
      timer = setInterval(function () {
        if (+slider.value >= seq.frames) { stop(); return; }
        go(+slider.value + 1);
      }, 1000 / Math.min(Math.max(seq.fps || 10, 1), 30));
    });
    section.querySelectorAll('svg.chart[data-seq="' + seqIndex + '"]').forEach(function (svg) {
      svg.addEventListener("click", function (event) {
        var rect = svg.getBoundingClientRect(), box = svg.viewBox.baseVal;
        var x = (event.clientX - rect.left) / rect.width * box.width;
        var x0 = +svg.dataset.x0, x1 = +svg.dataset.x1, n = Math.max(+svg.dataset.frames, 2);
        stop();
        go(Math.round(1 + (x - x0) / (x1 - x0) * (n - 1)));
      });
    });
    go(seq.start || 1);
  }

  document.querySelectorAll("section").forEach(function (section) {
    section.querySelectorAll("button.key[data-tracker]").forEach(function (button) {
      button.addEventListener("click", function () {
        var on = button.getAttribute("aria-pressed") !== "true";
        button.setAttribute("aria-pressed", on ? "true" : "false");
        section.querySelectorAll('svg.chart [data-tracker]').forEach(function (line) {
          if (line.dataset.tracker === button.dataset.tracker) {
            line.classList.toggle("off", !on);
          }
        });
      });
    });
  });
  document.querySelectorAll(".viewer").forEach(setupViewer);
  document.body.dataset.ready = "yes";
})();
"""


def _embedded(views: list[tuple[str, dict]]) -> str:
    """What the viewer needs, as JSON safe inside a <script> element (the sequences of every
    view, in page order)."""
    sequences = []
    for _, report in views:
        for entry in report["sequences"].values():
            item = {"frames": entry["frames"], "fps": entry.get("fps"),
                    "image_size": entry["image_size"]}
            if entry.get("boxes") and entry["boxes"].get("trackers"):
                item["boxes"] = entry["boxes"]
                if entry.get("per_frame"):
                    item["per_frame"] = entry["per_frame"]
                    item["start"] = start_frame(entry)
            sequences.append(item)
    text = json.dumps({"sequences": sequences}, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def start_frame(entry: dict) -> int:
    """The frame the viewer opens at: where the trackers' GOSPA differ most over a second
    (the highest GOSPA with one tracker), the first second left out, when trackers start up;
    1 without per-frame data."""
    counts = (entry.get("per_frame") or {}).get("trackers") or {}
    frames = int(entry["frames"])
    if not counts or not frames:
        return 1
    gospa = np.array([values["gospa"] for values in counts.values()], dtype=float)
    spread = gospa.max(axis=0) - gospa.min(axis=0) if len(gospa) > 1 else gospa[0]
    window = max(1, round(float(entry.get("fps") or 1)))
    spread = _moving_mean(spread, window)
    skip = window if frames > 2 * window else 0
    return int(np.argmax(spread[skip:])) + skip + 1


def _sequence_title(name: str, entry: dict) -> str:
    w, h = entry["image_size"]
    return f"{name} ({w:g}x{h:g}, {entry['fps']} fps, {entry['frames']} frames)"


def _anchor(index: int) -> str:
    return f"seq-{index + 1}"


PROTOCOL_TEXT = {
    "mot17": "TrackEval: MotChallenge2DBox preprocessing, IoU &ge; 0.5",
    "kitti": "TrackEval: Kitti2DBox preprocessing, IoU &ge; 0.5, each class scored apart",
}


def build_page(report: dict, source: str = "", title: str | None = None,
               show: str | None = None) -> str:
    """The HTML page of a benchmark report (the dict `occtrack benchmark --json` writes).
    `show` is the tracker the frame viewers open with (default: the first). A KITTI report
    gets one part a class."""
    check_report(report, source or "<report>")
    views = class_views(report, source or "<report>")
    trackers = list(report["trackers"])
    for _, view in views:
        for entry in view["sequences"].values():
            trackers += [name for name in entry["trackers"] if name not in trackers]
    if show is not None and show not in trackers:
        raise OcctrackError(f"no tracker {show!r} in this report; choose from "
                            + ", ".join(trackers), source or None)
    colors = _colors(trackers)
    names = list(report["sequences"])
    count = len(names)
    title = title or ("occtrack benchmark: " + ", ".join(names[:4])
                      + (f" and {count - 4} more" if count > 4 else ""))
    protocol = report.get("protocol", "?")
    body = [
        f"<h1>{_esc(title)}</h1>",
        f'<p class="meta">Protocol {_esc(protocol)} ({PROTOCOL_TEXT.get(protocol, "")}); '
        f"HOTA, DetA, AssA and LocA are means over the 19 localisation thresholds; frames/s "
        f"is the tracker call alone. {count} sequence{'s' if count != 1 else ''}, "
        f"{len(trackers)} trackers{', from ' + _esc(source) if source else ''}. The best "
        f"value of each column is in bold; hover over a column's name for what it is.</p>",
    ]
    index = 0
    for cls, view in views:
        part, index = _view_body(view, cls, colors, show, index)
        body += part
    body.append(f'<footer>Made by occtrack {_esc(__version__)} (occtrack report'
                f'{" " + _esc(source) if source else ""}); one file, no network access.'
                f"</footer>")
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<title>{_esc(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>\n"
            + "\n".join(body)
            + "\n</main>\n"
            f'<script type="application/json" id="occtrack-data">{_embedded(views)}</script>\n'
            f"<script>{SCRIPT}</script>\n</body>\n</html>\n")


def _ground_table(part: dict, colors: dict[str, str], columns, table_id: str) -> list[str]:
    """A 3D KITTI run's scores on the ground plane (`--protocol kitti-bev`), where the part has
    them; a peer (2D boxes only) shows dashes."""
    ground = part.get("ground")
    if not ground:
        return []
    trackers = {name: values or {} for name, values in ground.get("trackers", {}).items()}
    return ["<h3>On the ground plane (centres within 2 m)</h3>",
            _table(trackers, colors, columns, table_id=table_id)]


def _view_body(report: dict, cls: str, colors: dict[str, str], show: str | None,
               start: int) -> tuple[list[str], int]:
    """The page's part for one view (all of a MOTChallenge report, one class of a KITTI
    one): the navigation, the combined and mean tables, then a section a sequence, numbered
    from `start`; and the next sequence number."""
    sequences = list(report["sequences"].items())
    count = len(sequences)
    pooled_over = report.get("combined_over", count)  # KITTI: sequences without the class too
    prefix = f"{cls}-" if cls else ""
    label = f"{cls}: " if cls else ""
    nav = " ".join(f'<a href="#{prefix}{_anchor(start + i)}">{_esc(name)}</a>'
                   for i, (name, _) in enumerate(sequences))
    combined = report["combined"]
    mean = report["mean"]
    mean_columns = [c for c in COLUMNS if c[0] in MEAN_KEYS]
    body = ([f'<h2 class="class">{_esc(cls)}</h2>'] if cls else []) + [
        f"<nav>{_esc(label)}Sequences: {nav} <a href=\"#{prefix}combined\">combined</a></nav>",
        f'<section id="{prefix}combined">',
        f"<h2>{_esc(label)}Combined over {pooled_over} sequence"
        f"{'s' if pooled_over != 1 else ''}</h2>",
        f'<p class="meta">{_esc(combined.get("method", ""))}.</p>',
        _table(combined["trackers"], colors, table_id=f"{prefix}combined-table"),
        *_ground_table(combined, colors, COLUMNS[:-1], f"{prefix}combined-ground"),
        _reliability_diagram(combined.get("calibration"), colors, _DIAGRAM_TITLE
                             + f" (the boxes of all {pooled_over} pooled)"),
        f"<h2>{_esc(label)}Mean over {count} sequence{'s' if count != 1 else ''}</h2>",
        f'<p class="meta">{_esc(mean.get("method", ""))}.</p>',
        _table(mean["trackers"], colors, mean_columns, table_id=f"{prefix}mean-table"),
        *_ground_table(mean, colors, mean_columns, f"{prefix}mean-ground"),
        "</section>",
    ]
    for i, (name, entry) in enumerate(sequences):
        body += [f'<section id="{prefix}{_anchor(start + i)}">',
                 f"<h2>{_esc(label)}{_esc(_sequence_title(name, entry))}</h2>",
                 _table(entry["trackers"], colors),
                 _reliability_diagram(entry.get("calibration"), colors, _DIAGRAM_TITLE)]
        if not cls:  # a KITTI run keeps no per-frame data or boxes
            body += [_plots(entry, colors, start + i), _viewer(entry, start + i, show)]
        body.append("</section>")
    return body, start + count
