"""One image frame drawn as boxes on a blank canvas of the image size: ground truth,
detections and tracks with their labels. No video is needed, so MOT17 pictures can be drawn
from the text files alone."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError


def check_new(path: str | Path, overwrite: bool) -> Path:
    path = Path(path)
    if path.exists() and not overwrite:
        raise OcctrackError("exists already; pass --force to overwrite it", str(path))
    if not path.parent.is_dir():
        raise OcctrackError("folder does not exist", str(path.parent))
    return path


def draw_frame(path: str | Path, image_size: tuple[float, float], title: str = "",
               truth: np.ndarray | None = None, detections: np.ndarray | None = None,
               track_boxes: np.ndarray | None = None, track_ids: np.ndarray | None = None,
               overwrite: bool = False) -> None:
    """Boxes are (n, 4) left, top, width, height in px; the y axis points down as in images."""
    path = check_new(path, overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    width, height = image_size
    fig, ax = plt.subplots(figsize=(12, 12 * height / width + 0.6))
    ax.add_patch(Rectangle((0, 0), width, height, fc="0.97", ec="0.6"))
    legend = []
    for boxes, style, label in (
            (truth, {"ec": "0.55", "lw": 1.0, "ls": "--"}, "ground truth"),
            (detections, {"ec": "tab:pink", "lw": 1.6}, "detections"),
            (track_boxes, {"ec": "tab:blue", "lw": 2.0}, "tracks")):
        if boxes is None:
            continue
        for l, t, w, h in np.asarray(boxes, dtype=float).reshape(-1, 4):
            ax.add_patch(Rectangle((l, t), w, h, fill=False, **style))
        legend.append(Rectangle((0, 0), 1, 1, fill=False, label=f"{label} ({len(boxes)})",
                                **style))
    if track_boxes is not None and track_ids is not None:
        for (l, t, _, _), i in zip(np.asarray(track_boxes).reshape(-1, 4), track_ids,
                                   strict=True):
            ax.text(l, t - 4, str(int(i)), color="tab:blue", fontsize=7, va="bottom")
    ax.set_xlim(0, width)
    ax.set_ylim(height, 0)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if legend:
        ax.legend(handles=legend, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_title(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
