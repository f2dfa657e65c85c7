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
