"""`occtrack lidar`: the separable-likelihood beam model of paper section V, derived from
measurement-wise occlusion, checked against simulated beams and drawn."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from occtrack.cli.arguments import positive_int, seed_int
from occtrack.errors import OcctrackError

if TYPE_CHECKING:

    pass

NAME = "lidar"
HELP = "the occlusion-tolerant lidar beam likelihood that measurement-wise occlusion derives"
DESCRIPTION = """\
A scanning range sensor reports the nearest return on each beam. Treating that as
measurement-wise occlusion (a return hides everything farther along its beam), an object at
range x changes the beam's likelihood by the ratio

    L(z | x) = P_D N(z; x, sigma^2) / kappa + 1 - P_D Phi((z - x) / sigma)

(paper section V): high where the return meets the object, about 1 - P_D just beyond it (the
beam passed where the object would be) and about 1 well short of it (the object is hidden).
This prints L at a few ranges beside its value estimated from simulated beams (seeded), and
--figure draws both over the whole beam."""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--range", type=float, default=20.0, dest="x",
                        help="the object's range on the beam, m (default 20)")
    parser.add_argument("--p-d", type=float, default=0.9, help="detection probability (0.9)")
    parser.add_argument("--sigma", type=float, default=0.3, help="range noise std, m (0.3)")
    parser.add_argument("--clutter-rate", type=float, default=0.2,
                        help="expected clutter returns per beam (0.2)")
    parser.add_argument("--max-range", type=float, default=50.0, help="sensor range, m (50)")
    parser.add_argument("--samples", type=positive_int, default=400_000,
                        help="simulated beams per case (400000)")
    parser.add_argument("--seed", type=seed_int, default=0, help="simulation seed (0)")
    parser.add_argument("--figure", metavar="PNG", type=Path, help="draw L(z | x) over the beam")
    parser.add_argument("--force", action="store_true", help="overwrite an existing figure")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from occtrack.models.beam import BeamModel, regime
    from occtrack.scenarios.lidar import binned_ratio, empirical_ratio, probe_bins

    try:
        model = BeamModel(args.p_d, args.sigma, args.clutter_rate, args.max_range)
    except ValueError as err:
        raise OcctrackError(str(err)) from None
    if not 0 < args.x < args.max_range or args.samples < 1000:
        raise OcctrackError("--range must lie inside (0, --max-range) and --samples be >= 1000")
    rng = np.random.default_rng(args.seed)
    x, s = args.x, args.sigma
    probes, half, edges = probe_bins(x, s)
    ratio, se = empirical_ratio(model, x, edges, args.samples, rng)
    derived = binned_ratio(probes, half, x, model)
    print(f"Beam likelihood ratio L(z | x) for an object at x = {x:g} m (P_D {model.p_d}, "
          f"sigma {s} m, {model.clutter_rate} clutter returns per beam):")
    print(f"  {'z (m)':>8}  {'regime':<7}  {'L (derived)':>12}  {'L (simulated)':>18}")
    for k, z in enumerate(probes):
        print(f"  {z:8.2f}  {regime(x, z, model)!s:<7}  {derived[k]:12.3f}  "
              f"{ratio[2 * k]:10.3f} +- {se[2 * k]:.3f}")
    print(f"  no return: L = 1 - P_D = {1 - model.p_d:.3f}")
    if args.figure is not None:
        from occtrack.viz.lidar import draw_beam_likelihood

        draw_beam_likelihood(args.figure, model, x, rng, args.samples, args.force)
    return 0
