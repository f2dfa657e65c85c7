"""One run of a highway tracker on the simulated highway, scored (a cell of Table III; also
`occtrack simulate highway` and the highway sweeps)."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from occtrack.filters.particle_tomb import HighwayTracker
from occtrack.metrics.highway import HighwayScore, ScoreAccumulator
from occtrack.scenarios.highway import simulate


def evaluate(simulation, tracker_config, sensor: str, tracker: str, steps: int, seed: int,
             on_step=None, progress=None) -> tuple[HighwayScore, float]:
    """Run `tracker` on `steps` steps of the simulation drawn with `seed` and score it.
    Returns the score and the seconds spent in the tracker alone. The tracker's random stream
    is a third child of `seed` (the traffic and the sensor use the first two).
    `on_step(t, cars, scan, estimates)` is called after every step; `progress` wraps the
    step iterator (a progress bar)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[2])
    filt = HighwayTracker(tracker_config, tracker, seed=rng)
    acc = ScoreAccumulator()
    seconds = 0.0
    reported: set[int] = set()
    frames = simulate(simulation, sensor, steps, seed)
    if progress is not None:
        frames = progress(frames)
    for t, (cars, scan) in enumerate(frames):
        start = time.perf_counter()
        estimates = filt.step(scan)
        seconds += time.perf_counter() - start
        acc.add(cars, estimates)
        reported.update(estimates.label.tolist())
        if on_step is not None:
            on_step(t, cars, scan, estimates)
    return replace(acc.result(), tracks=len(reported)), seconds
