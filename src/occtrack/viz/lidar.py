"""The beam likelihood of paper section V over the whole beam, derived and simulated."""

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


def draw_scan_tracks(path: str | Path, picture, overwrite: bool = False) -> None:
    """One scan (`occtrack.experiments.scan_tracking.occlusion_picture`), a panel per occlusion
    model: the returns (dots), the people (circles; the fully occluded ones filled orange) and
    the tracks (blue, with their ids; dashed where held hidden)."""
    path = check_new(path, overwrite)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    models = list(picture.tracks)
    fig, axes = plt.subplots(len(models), 1, figsize=(11, 3.6 * len(models)), squeeze=False)
    for ax, model in zip(axes[:, 0], models, strict=True):
        positions, ids, hidden = picture.tracks[model]
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
        ax.set_xlim(-18.5, 18.5)
        ax.set_ylim(-7.5, 7.5)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    fig.suptitle(f"t = {picture.time:.1f} s: people grey (fully occluded: orange), returns "
                 f"dots, tracks blue (dashed: held while hidden)", fontsize=10)
    fig.tight_layout()
    save(fig, path, overwrite, dpi=100)
