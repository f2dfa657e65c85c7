"""Box occlusion geometry and the object-wise and measurement-wise models, exact values."""

from __future__ import annotations

import numpy as np
import pytest

from box_states import context, edges, states
from occtrack.occlusion.base import NoOcclusion
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry, combine
from occtrack.occlusion.box_measurementwise import MeasurementWise
from occtrack.occlusion.box_objectwise import ObjectWiseExpectedValue
from occtrack.occlusion.boxes import BOX_OCCLUSION_MODELS, box_occlusion

A = edges(0, 10, 0, 10)


@pytest.mark.parametrize("occluder,expected", [
    (edges(5, 15, 0, 20), 1.0),                         # half covered (x2, clipped), far lower
    (edges(8, 18, 0, 12), 0.4 * (1 / 6 + 0.1) / 0.35),  # 20 % covered, bottom 1/6 lower
    (edges(0, 10, 0, 10), 0.1 / 0.35),                  # same box: bottom gap 0
    (edges(0, 10, -10, 8), 0.0),                        # bottom higher: farther away
    (edges(20, 30, 0, 20), 0.0),                        # no overlap
])
def test_pairwise_occlusion_probability(occluder, expected):
    p = BoxOcclusionGeometry()(A[None], occluder[None])
    assert p.shape == (1, 1)
    assert p[0, 0] == pytest.approx(expected, abs=1e-12)


def test_occluders_combine_as_independent():
    np.testing.assert_allclose(combine(np.array([[0.5, 0.5], [0.2, 0.0]])), [0.75, 0.2])


def test_measurement_wise_hidden_term_from_visible_detections():
    means = states(A, edges(50, 60, 0, 10))
    detections = np.array([edges(5, 15, 0, 20), edges(8, 18, 0, 12)])
    terms = MeasurementWise().terms(context(means, [0, -1], [1.0], detections))
    p2 = 0.4 * (1 / 6 + 0.1) / 0.35
    np.testing.assert_allclose(terms.visible, [1.0, 1.0])
    np.testing.assert_allclose(terms.hidden, [1 - (1 - 1.0) * (1 - p2), 0.0], atol=1e-12)
    empty = MeasurementWise().terms(context(means, [0, -1], [1.0], np.zeros((0, 2, 2))))
    np.testing.assert_array_equal(empty.hidden, [0.0, 0.0])


def test_measurement_wise_seen_hidden_uses_the_other_detections_only():
    """h_j: how surely the other detections would have hidden detection j, combined as
    independent occluders. A detection never hides itself (its own bottom gap of 0 would give
    0.1 / 0.35 on the ramp)."""
    detections = np.array([A, edges(5, 15, 0, 20), edges(12, 22, 0, 12), edges(20, 30, 0, 13),
                           edges(50, 60, 0, 10)])
    h = MeasurementWise().seen_hidden(detections)
    third_by_second = 2 * (3 * 12) / (10 * 12)  # bottom 8 px lower: ramp at 1
    third_by_fourth = 2 * (2 * 12) / (10 * 12) * (1 / 13 + 0.1) / 0.35
    fourth_by_third = 2 * (2 * 12) / (10 * 13) * (-1 / 12 + 0.1) / 0.35
    np.testing.assert_allclose(h, [
        1.0,  # A: half covered by the second, whose bottom is far lower
        0.0,  # the second: every other bottom is higher
        1 - (1 - third_by_second) * (1 - third_by_fourth),
        fourth_by_third,
        0.0,  # overlaps nothing
    ], atol=1e-12)
    terms = MeasurementWise().terms(context(states(A), [0], [1.0], detections))
    np.testing.assert_allclose(terms.seen_hidden, h)
    np.testing.assert_array_equal(MeasurementWise().seen_hidden(detections[:1]), [0.0])


def test_object_wise_uses_other_objects_mean_boxes_weighted_by_existence():
    """Object 0 (two components) sits behind object 1 (r = 0.6); object 2 (r = 0.05) is
    below the 0.1 existence floor; the Poisson component (owner -1) is hidden by all."""
    comps = [A, edges(0, 10, 0, 10), edges(5, 15, 0, 20), edges(3, 13, 0, 20), A]
    owner = [0, 0, 1, 2, -1]
    weights = np.array([0.5, 0.5, 1.0, 1.0, 1.0])
    terms = ObjectWiseExpectedValue().terms(
        context(states(*comps), owner, [0.9, 0.6, 0.05], np.zeros((0, 2, 2)), weights))
    same_bottom = 0.1 / 0.35  # ramp at a bottom gap of 0
    np.testing.assert_allclose(terms.visible, [
        1 - 0.6 * 1.0,  # object 0 half covered by object 1, whose bottom is lower
        1 - 0.6 * 1.0,
        1.0,  # object 1: object 0's bottom is higher, object 2 is too weak to count
        1 - 0.6 * same_bottom,  # object 2: 80 % covered by object 1, same bottom
        (1 - 0.6) * (1 - 0.9 * same_bottom),  # Poisson: by objects 1 and 0
    ])
    np.testing.assert_array_equal(terms.hidden, np.zeros(5))


def test_an_object_never_occludes_itself():
    terms = ObjectWiseExpectedValue().terms(
        context(states(A, A), [0, 0], [1.0], np.zeros((0, 2, 2)), np.array([0.5, 0.5])))
    np.testing.assert_array_equal(terms.visible, [1.0, 1.0])


def test_models_chosen_by_name():
    assert set(BOX_OCCLUSION_MODELS) == {"none", "object-wise", "measurement-wise"}
    assert isinstance(box_occlusion("none"), NoOcclusion)
    assert box_occlusion("measurement-wise").name == "measurement-wise"
    assert box_occlusion("object-wise", min_existence=0.3).min_existence == 0.3
    with pytest.raises(ValueError, match="unknown occlusion model 'grid'"):
        box_occlusion("grid")


@pytest.mark.parametrize("K,M", [(0, 3), (7, 5), (40, 60), (200, 30)])
def test_hidden_by_seen_is_the_two_visibility_products(K, M):
    """Measurement-wise occlusion's q and h in one call are 1 - `visible` of the boxes behind
    the seen ones and of each seen box behind the others, to the bit: dense and sparse
    sizes (over DENSE_PAIRS pairs the two products are taken apart)."""
    rng = np.random.default_rng(K + M)

    def boxes(n):
        x, y = rng.uniform(0, 600, n), rng.uniform(0, 400, n)
        w, h = rng.uniform(10, 60, n), rng.uniform(30, 150, n)
        return np.stack([np.stack([x, x + w], -1), np.stack([y, y + h], -1)], 1)

    g = BoxOcclusionGeometry()
    b, z = boxes(K), boxes(M)
    for sparse in (True, False):
        q, h = g.hidden_by_seen(b, z, sparse=sparse)
        assert np.array_equal(q, 1.0 - g.visible(b, z, sparse=sparse))
        assert np.array_equal(h, 1.0 - g.visible(z, z, skip=np.arange(M), sparse=sparse))
    assert h.shape == (M,) and q.shape == (K,)
    assert (h > 0).any() or M < 5  # (some seen boxes do hide others)
