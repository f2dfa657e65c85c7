"""HOTA of point tracks (`occtrack.metrics.hota_points`): TrackEval's HOTA with the similarity
max(0, 1 - d / threshold), checked on cases whose value is known in closed form."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.metrics.hota_points import PointTracks, point_hota

pytest.importorskip("trackeval")

ALPHAS = np.arange(0.05, 0.99, 0.05)  # HOTA's 19 localisation levels


def _one(truth_id, truth_xy, track_id, track_xy):
    return (np.array([truth_id]), np.array([truth_xy], float), np.array([track_id]),
            np.array([track_xy], float))


def test_a_perfect_track_scores_one_and_an_identity_switch_halves_assa():
    perfect = [_one(5, (t, 0.0), 7, (t, 0.0)) for t in range(10)]
    assert point_hota(perfect, 1.0).hota == pytest.approx(1.0)
    # two tracks, each on the person half the time: every step a true positive (DetA 1), each
    # with TPA 5, FNA 5, FPA 0, so AssA 1/2 and HOTA sqrt(1/2) at every alpha
    switched = [_one(5, (t, 0.0), 7 if t < 5 else 9, (t, 0.0)) for t in range(10)]
    h = point_hota(switched, 1.0)
    assert (h.deta, h.assa) == pytest.approx((1.0, 0.5))
    assert h.hota == pytest.approx(np.sqrt(0.5))


def test_a_track_off_by_a_distance_counts_at_the_alphas_its_similarity_reaches():
    # similarity 1 - 0.3 / 1 = 0.7: a match at alpha 0.05 .. 0.70 (14 of 19), none above
    steps = [_one(1, (0.0, 0.0), 2, (0.0, 0.3)) for _ in range(4)]
    h = point_hota(steps, 1.0)
    share = np.count_nonzero(ALPHAS <= 0.7 + 1e-9) / len(ALPHAS)
    assert share == 14 / 19
    assert (h.hota, h.deta, h.assa) == pytest.approx((share, share, share))
    # twice the threshold, half the distance in its units: similarity 0.85, 17 of 19
    assert point_hota(steps, 2.0).hota == pytest.approx(17 / 19)


def test_misses_and_false_tracks_lower_deta_as_the_counts_say():
    # 4 steps, the person tracked in 2 (exactly), a false track far away in all 4:
    # DetA = TP / (TP + FN + FP) = 2 / (2 + 2 + 4)
    tracks = PointTracks()
    for t in range(4):
        ids, xy = ([3, 8], [(0.0, 0.0), (50.0, 0.0)]) if t < 2 else ([8], [(50.0, 0.0)])
        tracks.add([1], [(0.0, 0.0)], ids, xy)
    assert tracks.score(1.0).deta == pytest.approx(2 / 8)


def test_threshold_must_be_positive():
    with pytest.raises(ValueError, match="threshold"):
        point_hota([], 0.0)
