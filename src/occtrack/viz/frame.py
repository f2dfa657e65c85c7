"""Image frames drawn as boxes on a blank canvas of the image size: ground truth (grey),
detections (dashed magenta) and tracks (blue, with their labels), one panel per tracker side by
side. No video is needed, so MOT17 pictures can be drawn from the text files alone."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occtrack.errors import OcctrackError
from occtrack.io.atomic import check_output
from occtrack.viz.output import save


def check_new(path: str | Path, overwrite: bool) -> Path:
    """The path of a figure about to be written, checked before the work that draws it:
    refuses to replace a file unless asked."""
    checked = check_output(path, overwrite)
    if checked is None:
        raise OcctrackError("a picture cannot go to standard output; give a file name")
    return checked


def _panel(ax, image_size, window, truth, detections, track_ids, track_boxes, title) -> None:
    from matplotlib.patches import Rectangle

    W, H = image_size
    ax.add_patch(Rectangle((0, 0), W, H, facecolor="#f4f4f4", edgecolor="black", lw=0.8))
    for box in truth:
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="0.6", lw=0.8))
    for box in detections:
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="#d6249f", lw=1.2,
                               ls="--"))
    for label, box in zip(track_ids, track_boxes, strict=True):
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="#1f4fd1", lw=1.6))
        if window[0] <= box[0] <= window[2] and window[1] <= box[1] - 4 <= window[3]:
            ax.text(box[0], box[1] - 4, str(int(label)), color="#1f4fd1", fontsize=8,
                    va="bottom", ha="left", clip_on=True)
    ax.set_xlim(window[0], window[2])
    ax.set_ylim(window[3], window[1])
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title, fontsize=10)


def draw_panels(path: str | Path, image_size: tuple[float, float], panels: list[dict],
                window: tuple[float, float, float, float] | None = None,
                caption: str = "", overwrite: bool = True) -> None:
    """Save panels side by side as a PNG; each panel is a dict with truth, detections,
    track_ids, track_boxes ((n, 4) left, top, width, height) and title. `window` (left, top,
    right, bottom) crops every panel to one part of the image. Callers check the path with
    `check_new` before the work, hence `overwrite` defaults to True here."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    window = window or (0.0, 0.0, *image_size)
    aspect = (window[3] - window[1]) / (window[2] - window[0])
    fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 6 * aspect + 0.8),
                             squeeze=False)
    for ax, panel in zip(axes[0], panels, strict=True):
        _panel(ax, image_size, window, **{k: panel.get(k, np.zeros((0, 4))) for k in
                                  ("truth", "detections", "track_boxes")},
               track_ids=panel.get("track_ids", np.zeros(0)), title=panel.get("title", ""))
    if caption:
        fig.text(0.5, 0.02, caption, ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.05 if caption else 0, 1, 1))
    save(fig, path, overwrite, dpi=110)
