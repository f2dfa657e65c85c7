"""Plots of whole runs: a metric per frame for several trackers."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occtrack.viz.frame import check_new
from occtrack.viz.output import save


def plot_gospa_per_frame(path: str | Path, series: dict[str, np.ndarray], title: str,
                         window: int = 30, overwrite: bool = False) -> None:
    """Per-frame GOSPA of each tracker, raw (faint) and as a moving mean over `window` frames."""
    path = check_new(path, overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4))
    kernel = np.ones(window) / window
    for (name, values), color in zip(series.items(), ("tab:gray", "tab:red", "tab:blue",
                                                      "tab:green"), strict=False):
        frames = np.arange(1, len(values) + 1)
        ax.plot(frames, values, color=color, alpha=0.15, lw=0.6)
        if len(values) >= window:
            ax.plot(frames[window // 2: window // 2 + len(values) - window + 1],
                    np.convolve(values, kernel, mode="valid"), color=color, lw=1.6,
                    label=f"{name} (total {values.sum():.0f})")
    ax.set_xlabel("frame")
    ax.set_ylabel("GOSPA (c = 1, 1 - IoU)")
    ax.set_title(title, fontsize=11)
    ax.legend(fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, path, overwrite, dpi=100)
