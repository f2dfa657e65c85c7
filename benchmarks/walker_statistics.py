"""How people move in a MOT17 ground truth: the demo street's motion (`occtrack.config.street.
StreetMotion`) is measured here on MOT17-04, the one sequence of the three with a still camera.

    python benchmarks/walker_statistics.py $OCCTRACK_DATA/MOT17-04-FRCNN/gt/gt.txt [--fps 30]

Pedestrians (class 1, consider flag 1) tracked without a gap for at least 2 s; the feet (box
bottom centre) and the height smoothed over 1 s; speed = the feet's speed over the height, in
box heights a second. A person walks above 0.12 h/s and stands below 0.05 h/s (hysteresis in
between: a smoothed speed wanders near one threshold). Printed: the share of people who stand
throughout, the walking speed's median and quartiles (and its log-std, from the quartiles),
stops per second of walking, the mean length of the stops that end within the sequence, and
the share of those after which the person walks back (heading turned more than 90 degrees).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.ndimage import uniform_filter1d

from occtrack.io.mot import read_mot

WALK, STAND = 0.12, 0.05


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("gt")
    parser.add_argument("--fps", type=float, default=30.0)
    args = parser.parse_args()
    fps = args.fps
    gt = read_mot(args.gt, "gt")
    mask = (gt.cls == 1) & (gt.score != 0)
    people = standers = stops_total = 0
    walk_s = stand_s = 0.0
    speeds, stops, turned = [], [], []
    half = int(fps // 2)
    for person in np.unique(gt.id[mask]):
        rows = np.flatnonzero(mask & (gt.id == person))
        rows = rows[np.argsort(gt.frame[rows])]
        if len(rows) < 2 * fps or (np.diff(gt.frame[rows]) != 1).any():
            continue
        b = gt.box[rows]
        fx, fy, h = (uniform_filter1d(v, 2 * half + 1, mode="nearest")
                     for v in (b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3], b[:, 3]))
        vx = (np.gradient(fx) * fps / h)[half:-half]
        vy = (np.gradient(fy) * fps / h)[half:-half]
        speed = np.hypot(vx, vy)
        people += 1
        walking = np.zeros(len(speed), bool)
        state = speed[0] > (WALK + STAND) / 2
        for t, v in enumerate(speed):
            state = (v > STAND) if state else (v > WALK)
            walking[t] = state
        standers += not walking.any()
        walk_s += walking.sum() / fps
        stand_s += (~walking).sum() / fps
        speeds.append(speed[walking])
        change = np.flatnonzero(np.diff(walking.astype(int)))
        for j, c in enumerate(change):
            if walking[c]:  # walking -> standing
                stops_total += 1
                if j + 1 < len(change):
                    end = change[j + 1] + 1
                    stops.append((end - 1 - c) / fps)
                    turned.append(vx[c] * vx[end] + vy[c] * vy[end] < 0)
    walk = np.concatenate(speeds)
    q1, median, q3 = np.percentile(walk, [25, 50, 75])
    print(f"{args.gt}: {people} pedestrians tracked for 2 s or more")
    print(f"standing throughout: {standers} ({standers / people:.2f})")
    print(f"walking speed, box heights / s: median {median:.2f}, quartiles {q1:.2f} {q3:.2f} "
          f"(log-std {np.log(q3 / q1) / 1.349:.2f})")
    print(f"stops: {stops_total} in {walk_s:.0f} s of walking ({stops_total / walk_s:.3f} a s); "
          f"{len(stops)} ended in view, mean {np.mean(stops):.2f} s; walked back after "
          f"{np.mean(turned):.2f} of them")
    print(f"time standing: {stand_s:.0f} s of {walk_s + stand_s:.0f}")


if __name__ == "__main__":
    main()
