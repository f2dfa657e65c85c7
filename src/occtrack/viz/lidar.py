"""The beam likelihood of paper section V over the whole beam, derived and simulated; scans of
the walkway with their tracks, one (`draw_scan_tracks`) or an animation (`animate_scan_tracks`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occtrack.models.beam import BeamModel, likelihood_ratio
from occtrack.scenarios.lidar import empirical_ratio
from occtrack.viz.frame import check_new
from occtrack.viz.output import save


def draw_beam_likelihood(path: str | Path, model: BeamModel, x: float,
                         rng: np.random.Generator, samples: int, overwrite: bool = False) -> None:
    path = check_new(path, overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    z = np.linspace(0, min(model.max_range, 2 * x), 2000)
    edges = np.linspace(0, z[-1], 161)
    ratio, se = empirical_ratio(model, x, edges, samples, rng)
    centres = (edges[:-1] + edges[1:]) / 2
    fig, ax = plt.subplots(figsize=(9, 3.8))
    ax.plot(z, likelihood_ratio(z, x, model), color="tab:blue", lw=1.8,
            label="derived from measurement-wise occlusion")
    ax.errorbar(centres, ratio, yerr=se, fmt=".", ms=3, color="tab:red", alpha=0.7,
                label=f"simulated beams ({samples:,} with and without the object)")
    ax.axvline(x, color="0.5", ls=":", lw=1)
    ax.set_yscale("log")
    ax.set_xlabel("reported range z (m)")
    ax.set_ylabel("L(z | x)")
    ax.set_title(f"Object at {x:g} m: hidden short of it (L = 1), hit at it, passed beyond it "
                 f"(L = 1 - P_D = {1 - model.p_d:.2f})", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    save(fig, path, overwrite, dpi=100)


SCENE_LIMITS = ((-18.5, 18.5), (-7.5, 7.5))  # x, y (m): the default walkway, for one scan


def draw_scan_panel(ax, picture, model: str, limits=SCENE_LIMITS, beams: int = 0) -> None:
    """One panel of a scan (`occtrack.experiments.scan_tracking.OcclusionPicture`) under one
    occlusion model, on a cleared axis: the returns (dots; with `beams`, a faint line from the
    sensor to every `beams`-th of them), the sensor, the people (circles; the fully occluded
    ones filled orange) and the tracks (blue, with their ids; dashed where held hidden)."""
    from matplotlib.patches import Circle

    ax.clear()
    positions, ids, hidden = picture.tracks[model]
    if beams:
        ends = picture.returns[::beams]
        ax.plot(np.stack([np.full(len(ends), picture.sensor[0]), ends[:, 0]]),
                np.stack([np.full(len(ends), picture.sensor[1]), ends[:, 1]]),
                color="0.75", lw=0.5)
    ax.plot(*picture.returns.T, ".", ms=2, color="0.35", label="returns")
    ax.plot(*picture.sensor, "k^", ms=8, label="sensor")
    for centre, occluded in zip(picture.people, picture.occluded, strict=True):
        ax.add_patch(Circle(centre, picture.radius, fill=bool(occluded), lw=1,
                            facecolor="orange", edgecolor="0.4", alpha=0.9))
    for position, track, held in zip(positions, ids, hidden, strict=True):
        ax.add_patch(Circle(position, picture.radius * 1.5, fill=False, lw=1.4,
                            color="tab:blue", ls="--" if held else "-"))
        ax.annotate(str(track), position + picture.radius * 1.6, fontsize=7,
                    color="tab:blue")
    ax.set_title(f"occlusion: {model}: {len(ids)} tracks, "
                 f"{int(hidden.sum())} held hidden", fontsize=10)
    ax.set_aspect("equal")
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _scan_figure(picture, width: float = 11.0):
    """A figure `width` inches wide with a panel per occlusion model, stacked, and its axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    models = len(picture.tracks)
    fig, axes = plt.subplots(models, 1, figsize=(width, 3.6 * models), squeeze=False)
    return fig, axes[:, 0]


def _draw_scan(fig, axes, picture, limits, beams: int = 0) -> None:
    for ax, model in zip(axes, picture.tracks, strict=True):
        draw_scan_panel(ax, picture, model, limits, beams)
    fig.suptitle(f"t = {picture.time:.1f} s: people grey (fully occluded: orange), returns "
                 f"dots, tracks blue (dashed: held while hidden)", fontsize=10)


def draw_scan_tracks(path: str | Path, picture, overwrite: bool = False) -> None:
    """One scan (`occtrack.experiments.scan_tracking.occlusion_picture`), a panel per occlusion
    model (`draw_scan_panel`), on the default walkway's extent."""
    path = check_new(path, overwrite)
    fig, axes = _scan_figure(picture)
    _draw_scan(fig, axes, picture, SCENE_LIMITS)
    fig.tight_layout()
    save(fig, path, overwrite, dpi=100)


def window_limits(pictures, margin: float = 1.0) -> tuple[tuple[float, float], ...]:
    """(x, y) limits holding the sensor, the people and the tracks of every picture, `margin`
    m beyond their discs: fixed over an animation (returns beyond them, clutter, are cut)."""
    points = np.concatenate([np.vstack([p.sensor[None], p.people,
                                        *(t[0] for t in p.tracks.values())])
                             for p in pictures])
    pad = margin + 1.5 * pictures[0].radius
    lo, hi = points.min(axis=0) - pad, points.max(axis=0) + pad
    return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))


def animate_scan_tracks(path: str | Path, pictures, overwrite: bool = False, fps: float = 10.0,
                        dpi: int = 70, beams: int = 6, quiet: bool = True) -> Path:
    """A GIF of consecutive scans (`occtrack.experiments.scan_tracking.occlusion_scans`,
    `around`), a frame per scan at `fps` frames a second (10: the scene's scan rate, real
    time), each drawn as the still (`draw_scan_panel`) with a faint line for every `beams`-th
    return, the axes fixed over the animation (`window_limits`); matplotlib's PillowWriter. A
    progress bar over the frames unless `quiet`."""
    from occtrack.progress import progress
    from occtrack.viz.highway import check_path
    from occtrack.viz.output import save_animation

    path = check_path(path, (".gif",), overwrite)
    limits = window_limits(pictures)
    (x0, x1), (y0, y1) = limits
    # the panels' height (3.6 in less the titles and labels) times the extent's aspect
    fig, axes = _scan_figure(pictures[0], min(max(2.7 * (x1 - x0) / (y1 - y0) + 1.2, 4.0), 14.0))
    from matplotlib.animation import FuncAnimation, PillowWriter

    _draw_scan(fig, axes, pictures[0], limits, beams)
    fig.tight_layout()
    anim = FuncAnimation(fig, lambda i: _draw_scan(fig, axes, pictures[i], limits, beams),
                         frames=len(pictures), blit=False, cache_frame_data=False)
    ticks = progress(range(len(pictures)), len(pictures), "lidar animation", quiet)
    try:
        save_animation(anim, fig, path, overwrite, writer=PillowWriter(fps=fps), dpi=dpi,
                       progress_callback=lambda i, n: next(ticks, None))
    finally:
        ticks.close()
    return path
