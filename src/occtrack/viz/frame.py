"""Image frames drawn as boxes on a blank canvas of the image size: ground truth (grey; one
person may be picked out in orange), detections (dashed magenta) and tracks (blue, with their
labels; dotted where the track is held without a detection), panels side by side or in rows. No
video is needed, so MOT17 pictures can be drawn from the text files alone."""

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


def _panel(ax, image_size, window, truth, detections, track_ids, track_boxes, title,
           track_hidden=None, highlight=None) -> None:
    from matplotlib.patches import Rectangle

    W, H = image_size
    ax.add_patch(Rectangle((0, 0), W, H, facecolor="#f4f4f4", edgecolor="black", lw=0.8))
    for box in truth:
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="0.6", lw=0.8))
    if highlight is not None:
        ax.add_patch(Rectangle(highlight[:2], highlight[2], highlight[3], fill=True,
                               fc="#f5a623", alpha=0.35, ec="#f5a623", lw=1.6))
    for box in detections:
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="#d6249f", lw=1.2,
                               ls="--"))
    hidden = np.zeros(len(track_ids), bool) if track_hidden is None else track_hidden
    for label, box, held in zip(track_ids, track_boxes, hidden, strict=True):
        ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="#1f4fd1", lw=1.6,
                               ls=":" if held else "-"))
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
                caption: str = "", overwrite: bool = True, columns: int | None = None) -> None:
    """Save panels side by side (`columns` a row, default all) as a PNG; each panel is a dict
    with truth, detections, track_ids, track_boxes ((n, 4) left, top, width, height) and
    title, optionally track_hidden ((n,) bool: drawn dotted) and highlight (one box, filled
    orange). `window` (left, top, right, bottom) crops every panel to one part of the image.
    Callers check the path with `check_new` before the work, hence `overwrite` defaults to
    True here."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    window = window or (0.0, 0.0, *image_size)
    aspect = (window[3] - window[1]) / (window[2] - window[0])
    cols = columns or len(panels)
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6 * cols, (6 * aspect + 0.4) * rows + 0.4),
                             squeeze=False)
    for ax, panel in zip(axes.ravel(), panels, strict=False):
        _panel(ax, image_size, window, **{k: panel.get(k, np.zeros((0, 4))) for k in
                                  ("truth", "detections", "track_boxes")},
               track_ids=panel.get("track_ids", np.zeros(0)), title=panel.get("title", ""),
               track_hidden=panel.get("track_hidden"), highlight=panel.get("highlight"))
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    if caption:
        fig.text(0.5, 0.02, caption, ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.05 if caption else 0, 1, 1))
    save(fig, path, overwrite, dpi=110)
