"""One place, one object (`occtrack.models.footprints`): the exact overlap of two rotated
footprints, and the boxes dropped as a higher-scored box's duplicate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occtrack.models.footprints import duplicates, footprints, intersection_area


def box(x, z, w=2.0, length=4.0, ry=0.0):
    """A KITTI box (h w l x y z rotation_y) on the ground at (x, z)."""
    return np.array([1.5, w, length, x, 1.6, z, ry])


def overlap(a, b):
    return float(intersection_area(footprints(a[None]), footprints(b[None]))[0])


def test_footprints_are_the_rotated_rectangles_counter_clockwise():
    f = footprints(np.stack([box(1.0, 10.0), box(0.0, 0.0, ry=0.7)]))
    np.testing.assert_allclose(f[0], [[-1, 11], [-1, 9], [3, 9], [3, 11]])
    x, z = f[..., 0], f[..., 1]
    signed = 0.5 * (x * np.roll(z, -1, axis=1) - np.roll(x, -1, axis=1) * z).sum(axis=1)
    np.testing.assert_allclose(signed, [8.0, 8.0])  # counter-clockwise, area w l


def test_exact_areas_of_known_overlaps():
    assert overlap(box(0, 0), box(0, 0)) == pytest.approx(8.0)  # identical: its own area
    assert overlap(box(0, 0), box(1, 0.5)) == pytest.approx(3 * 1.5)
    assert overlap(box(0, 0), box(0, 0, w=0.6, length=0.8)) == pytest.approx(0.48)  # inside
    assert overlap(box(0, 0), box(10, 0)) == 0.0
    assert overlap(box(0, 0), box(0, 2)) == 0.0  # touching along an edge, either way round
    assert overlap(box(0, 2), box(0, 0)) == 0.0
    # a unit square and the same turned 45 degrees: a regular octagon, 2 (sqrt 2 - 1)
    square = box(0, 0, w=1.0, length=1.0)
    turned = box(0, 0, w=1.0, length=1.0, ry=math.pi / 4)
    assert overlap(square, turned) == pytest.approx(2 * (math.sqrt(2) - 1), rel=1e-12)
    assert overlap(turned, square) == pytest.approx(2 * (math.sqrt(2) - 1), rel=1e-12)


def test_random_overlaps_agree_with_monte_carlo_within_four_standard_errors():
    rng = np.random.default_rng(5)
    n = 200_000
    for _ in range(20):
        a = box(*rng.uniform(-1, 1, 2), *rng.uniform(0.5, 2.5, 2), rng.uniform(-3, 3))
        b = box(*rng.uniform(-1, 1, 2), *rng.uniform(0.5, 2.5, 2), rng.uniform(-3, 3))
        fa, fb = footprints(a[None])[0], footprints(b[None])[0]
        low, high = fa.min(axis=0), fa.max(axis=0)
        points = rng.uniform(low, high, (n, 2))

        def inside(poly, points=points):
            edge = np.roll(poly, -1, axis=0) - poly
            rel = points[:, None, :] - poly[None]
            return ((edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]) >= 0
                    ).all(axis=1)

        hit = inside(fa) & inside(fb)
        box_area = float(np.prod(high - low))
        p = hit.mean()
        se = box_area * math.sqrt(max(p * (1 - p), 1 / n) / n)
        assert abs(overlap(a, b) - box_area * p) < 4 * se + 1e-9


def test_the_lower_scored_of_two_boxes_at_one_place_is_the_duplicate():
    cyclist = box(0.0, 10.0, w=0.6, length=1.8)
    walker = box(0.1, 10.2, w=0.6, length=0.8)  # inside the cyclist's footprint
    car = box(5.0, 10.0)
    drop = duplicates(np.stack([cyclist, walker, car]), np.array([0.99, 0.8, 0.9]))
    assert drop.tolist() == [False, True, False]
    drop = duplicates(np.stack([cyclist, walker, car]), np.array([0.7, 0.8, 0.9]))
    assert drop.tolist() == [True, False, False]  # the higher score stands for the object


def test_a_box_dropped_drops_nothing_itself_greedy_in_score_order():
    # a overlaps b by 3/4, b overlaps c by 3/4, a and c by 1/2 of the smaller: a keeps, b goes,
    # and c overlaps the kept a by exactly the threshold's half, so it goes too; at .6 it stays
    a, b, c = box(0, 0), box(1, 0), box(2, 0)
    boxes, scores = np.stack([a, b, c]), np.array([0.9, 0.8, 0.7])
    assert duplicates(boxes, scores).tolist() == [False, True, True]
    assert duplicates(boxes, scores, overlap=0.6).tolist() == [False, True, False]


def test_side_by_side_and_diagonal_neighbours_are_not_duplicates():
    """Two cars parked diagonally 2.2 m apart: their axis-aligned hulls overlap by most of a
    hull, their footprints not at all."""
    turn = math.pi / 4
    a, b = box(0, 0, ry=turn), box(2.2 / math.sqrt(2), 2.2 / math.sqrt(2), ry=turn)
    assert overlap(a, b) == pytest.approx(0.0, abs=1e-9)
    assert not duplicates(np.stack([a, b]), np.array([0.9, 0.8])).any()
    assert not duplicates(np.zeros((0, 7)), np.zeros(0)).any()
    assert not duplicates(a[None], np.ones(1)).any()
