"""Pictures of the highway (in the spirit of the paper's highway snapshot).

Lanes run left to right, nearest at the bottom, with the sensor (green circle) below them at
x = 0. Black bars are the cars; blue boxes are measurements whose two ends were seen; a blue
line with a tick at each seen end is a measurement partly hidden, drawn over the whole span in
which the car could extend; red boxes are the tracker's estimates (label above); grey bands
are the parts of each lane hidden by the measurements of the nearer lanes. `draw_frame` draws
one step on an axis; `save_figure` and `save_animation` write a PNG and a GIF (matplotlib's
PillowWriter).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from occtrack.errors import OcctrackError
from occtrack.io.atomic import check_output
from occtrack.viz import output

BAR = 0.35
BOX = 0.8
EST = 1.15


def check_path(path: Path, suffixes: tuple[str, ...], overwrite: bool) -> Path:
    """A picture path that may be written: right suffix, existing folder, no clobbering."""
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise OcctrackError(f"must end in {' or '.join(suffixes)}", str(path))
    return check_output(path, overwrite) or path


def draw_frame(ax, road, cars, scan, estimates=None, model=None, title: str = "") -> None:
    """One step: road, sensor, cars, measurements, hidden parts and estimates."""
    import matplotlib.patches as mpatches

    ax.clear()
    distances = road.distances
    half = road.half_length
    reach = half + 8.0
    for k, d in enumerate(distances):
        ax.axhline(d, color="0.85", lw=0.8, zorder=0)
        arrow = "\u2192" if road.directions[k] > 0 else "\u2190"
        ax.text(-reach + 0.5, d + 0.9, f"lane {k + 1} {arrow}", fontsize=7, color="0.4")
    ax.axvspan(-reach, -half, color="0.96", zorder=0)
    ax.axvspan(half, reach, color="0.96", zorder=0)
    if model is not None:
        for k, (lo, hi) in enumerate(model.occluded_parts(scan)):
            for a, b in zip(lo, hi, strict=True):
                ax.add_patch(mpatches.Rectangle((a, distances[k] - BOX), b - a, 2 * BOX,
                                                color="0.88", lw=0, zorder=1))
    for lane, left, length in zip(cars.lane, cars.left, cars.length, strict=True):
        ax.add_patch(mpatches.Rectangle((left, distances[lane] - BAR / 2), length, BAR,
                                        color="black", zorder=3))
    blue = "#1f5fd6"
    for j in range(len(scan)):
        d = distances[scan.lane[j]]
        lo, hi = scan.left[j, 0], scan.right[j, 1]
        if not (scan.left_hidden[j] or scan.right_hidden[j]):
            ax.add_patch(mpatches.Rectangle((lo, d - BOX / 2), hi - lo, BOX, fill=False,
                                            ec=blue, lw=1.4, zorder=4))
            continue
        ax.plot([lo, hi], [d - BOX / 2, d - BOX / 2], color=blue, lw=1.4, zorder=4)
        for seen, x in ((not scan.left_hidden[j], scan.left[j, 0]),
                        (not scan.right_hidden[j], scan.right[j, 0])):
            if seen:
                ax.plot([x, x], [d - BOX / 2, d + BOX / 2], color=blue, lw=1.4, zorder=4)
        for hidden, span in ((scan.left_hidden[j], scan.left[j]),
                             (scan.right_hidden[j], scan.right[j])):
            if hidden:
                ax.plot(span, [d - BOX / 2] * 2, color=blue, lw=3.5, alpha=0.35, zorder=4,
                        solid_capstyle="butt")
    if estimates is not None:
        for label, lane, left, length in zip(estimates.label, estimates.lane, estimates.left,
                                             estimates.length, strict=True):
            d = distances[lane]
            ax.add_patch(mpatches.Rectangle((left, d - EST / 2), length, EST, fill=False,
                                            ec="#d62728", lw=1.0, zorder=5))
            ax.text(left + length / 2, d + EST / 2 + 0.1, str(label), fontsize=6,
                    color="#d62728", ha="center", va="bottom", zorder=5)
    ax.plot([0], [0], "o", color="#2ca02c", ms=9, zorder=6)
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-1.2, distances[-1] + 2.0)
    ax.set_yticks([])
    ax.set_xlabel("position along the road (m)", fontsize=8)
    ax.tick_params(labelsize=7)
    if title:
        ax.set_title(title, fontsize=9)


def _legend(fig) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(color="black", label="car"),
               Patch(fill=False, ec="#1f5fd6", label="measurement, both ends seen"),
               Line2D([], [], color="#1f5fd6", lw=1.4, label="partly hidden measurement"),
               Patch(fill=False, ec="#d62728", label="tracker estimate"),
               Patch(color="0.88", label="hidden by nearer measurements"),
               Line2D([], [], marker="o", color="#2ca02c", lw=0, label="sensor")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=7, frameon=False)


def save_figure(path: Path, road, frames: Sequence[tuple], model=None, titles=None,
                overwrite: bool = False) -> Path:
    """One panel per (cars, scan, estimates) frame, stacked, to a PNG."""
    path = check_path(path, (".png",), overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    height = 0.2 * (road.distances[-1] + 3.5)
    fig, axes = plt.subplots(len(frames), 1, figsize=(11, height * len(frames) + 0.6),
                             squeeze=False)
    for i, (cars, scan, est) in enumerate(frames):
        draw_frame(axes[i, 0], road, cars, scan, est, model, titles[i] if titles else "")
    _legend(fig)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    output.save(fig, path, overwrite, dpi=130)
    return path


def save_animation(path: Path, road, frames: Sequence[tuple], model=None, title: str = "",
                   first_step: int = 0, fps: int = 5, overwrite: bool = False) -> Path:
    """A GIF of consecutive (cars, scan, estimates) frames, at 5 steps per second by default
    (real time for the highway)."""
    path = check_path(path, (".gif",), overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    height = 0.2 * (road.distances[-1] + 3.5)
    fig, ax = plt.subplots(figsize=(10, height + 0.7))

    def update(i):
        cars, scan, est = frames[i]
        draw_frame(ax, road, cars, scan, est, model, f"{title}, step {first_step + i}".strip(", "))
        return []

    _legend(fig)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    anim = FuncAnimation(fig, update, frames=len(frames), blit=False)
    output.save_animation(anim, fig, path, overwrite, writer=PillowWriter(fps=fps), dpi=80)
    return path
