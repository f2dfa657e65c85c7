"""Paper Figure 1: the four-square model (priors, measurement model) and the outcomes A-E."""

from __future__ import annotations

from pathlib import Path

from occtrack.io.atomic import check_output
from occtrack.scenarios.foursquare import BL, BR, OUTCOMES, TL, TR, FourSquare, table
from occtrack.viz.output import save

# (column, row) of each cell, row 1 on top
XY = {TL: (0, 1), TR: (1, 1), BL: (0, 0), BR: (1, 0)}


def _grid(ax, title: str) -> None:
    import matplotlib.patches as mpatches

    for x, y in XY.values():
        ax.add_patch(mpatches.Rectangle((x, y), 1, 1, fill=False, lw=1.5, ec="0.2"))
    ax.set_xlim(-0.05, 2.05)
    ax.set_ylim(-0.05, 2.05)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title, fontsize=10)


def draw_foursquare(example: FourSquare, path: Path, overwrite: bool = False) -> None:
    check_output(path, overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.patches as mpatches
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 7, figsize=(15, 2.9),
                             gridspec_kw={"width_ratios": [1.25, 1.25, 1, 1, 1, 1, 1]})
    ax = axes[0]
    _grid(ax, "objects")
    half = "1/2"
    for cell in (TL, TR):
        x, y = XY[cell]
        ax.text(x + 0.5, y + 0.5, f"top\n{example.p_top} x {half}", ha="center", va="center",
                fontsize=8, color="tab:blue")
    for cell in (BL, BR):
        x, y = XY[cell]
        ax.text(x + 0.5, y + 0.5, f"bottom\n1 x {half}", ha="center", va="center", fontsize=8,
                color="tab:blue")
    ax.annotate("", xy=(0.5, 1.15), xytext=(0.5, 0.85),
                arrowprops={"arrowstyle": "->", "color": "0.5"})
    ax.text(1.0, -0.02, "sensor below: the bottom row hides the top row\nin the same column",
            ha="center", va="top", fontsize=7, color="0.3")

    ax = axes[1]
    _grid(ax, "measurement model")
    ax.add_patch(mpatches.Circle((0.5, 0.5), 0.18, color="tab:blue"))
    miss = 1 - example.p_correct - example.p_wrong
    ax.text(0.5, 0.15, f"own {example.p_correct}", ha="center", fontsize=8, color="tab:red")
    ax.text(1.5, 0.5, f"other\n{example.p_wrong}", ha="center", va="center", fontsize=8,
            color="tab:red")
    ax.text(1.0, 1.5, f"none: {miss}", ha="center", va="center", fontsize=8)

    result = table(example)
    for ax, (name, cells) in zip(axes[2:], OUTCOMES.items(), strict=True):
        _grid(ax, f"outcome {name}")
        impossible = [model for model, row in result.items() if row[name] is None]
        if impossible:
            ax.text(1, -0.02, "impossible under\n" + ", ".join(impossible), ha="center",
                    va="top", fontsize=7, color="tab:purple")
        for cell in cells:
            x, y = XY[cell]
            ax.add_patch(mpatches.Rectangle((x + 0.15, y + 0.15), 0.7, 0.7, fill=False,
                                            ec="tab:red", lw=2.5))
        if not cells:
            ax.text(1, 2.0, "no measurement", ha="center", va="bottom", fontsize=7, color="0.4")
    fig.suptitle("Four-square example (paper section II): priors, measurement model, "
                 "and outcomes (red boxes: measurements)", fontsize=11)
    fig.tight_layout()
    save(fig, path, overwrite, dpi=110)
