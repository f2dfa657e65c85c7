"""Occlusion terms at their edges: the existence floor, a single occluder, unnormalised
component weights, empty inputs, and the sparse (overlapping pairs) form of `visible` against
the full table with weights, skips and sure occlusions."""

from __future__ import annotations

import warnings
from functools import reduce
from operator import mul

import numpy as np
import pytest

from box_states import context, edges, states
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry, combine
from occtrack.occlusion.box_measurementwise import MeasurementWise
from occtrack.occlusion.box_objectwise import ObjectWiseExpectedValue
from occtrack.spatial import DENSE_PAIRS

A = edges(0, 10, 0, 10)
BEHIND = edges(5, 15, 0, 20)  # half covers A with a far lower bottom: p(A hidden) = 1


def test_an_object_at_the_existence_floor_does_not_occlude():
    """Only objects with r above min_existence occlude; r equal to it is not above."""
    ctx = context(states(A, BEHIND), [0, 1], [0.9, 0.1], np.zeros((0, 2, 2)))
    np.testing.assert_array_equal(ObjectWiseExpectedValue().terms(ctx).visible, [1.0, 1.0])
    ctx = context(states(A, BEHIND), [0, 1], [0.9, 0.1 + 1e-12], np.zeros((0, 2, 2)))
    visible = ObjectWiseExpectedValue().terms(ctx).visible
    np.testing.assert_allclose(visible, [1 - (0.1 + 1e-12), 1.0], rtol=1e-12)
    ctx = context(states(A, BEHIND), [0, 1], [0.9, 0.3], np.zeros((0, 2, 2)))
    np.testing.assert_allclose(ObjectWiseExpectedValue(min_existence=0.3).terms(ctx).visible,
                               [1.0, 1.0])


def test_a_single_occluder_counts():
    """Object 1 (r = 0.6) is the only occluder (object 0 is below the floor): it hides
    object 0 and the Poisson component behind it, and never itself."""
    ctx = context(states(A, BEHIND, A), [0, 1, -1], [0.05, 0.6], np.zeros((0, 2, 2)))
    terms = ObjectWiseExpectedValue().terms(ctx)
    np.testing.assert_allclose(terms.visible, [0.4, 1.0, 0.4], rtol=1e-12)
    np.testing.assert_array_equal(terms.hidden, [0.0, 0.0, 0.0])
    one = context(states(A), [-1], [0.6], np.zeros((0, 2, 2)))  # occluder with no component
    np.testing.assert_array_equal(ObjectWiseExpectedValue().terms(one).visible, [1.0])


def test_mean_boxes_are_weighted_averages_whatever_the_weights_sum_to():
    """Object 1's mean box is the weighted average of its components' boxes, so scaling its
    weights (here to sum 0.4 or 3) changes nothing."""
    comps = [A, edges(4, 14, 0, 16), edges(6, 16, 0, 24)]  # object 1: mean (5, 15, 0, 20)
    terms = []
    for scale in (1.0, 0.4, 3.0):
        ctx = context(states(*comps), [0, 1, 1], [0.9, 0.5], np.zeros((0, 2, 2)),
                      np.array([1.0, 0.5 * scale, 0.5 * scale]))
        terms.append(ObjectWiseExpectedValue().terms(ctx).visible)
    np.testing.assert_allclose(terms[0][0], 0.5, rtol=1e-12)  # like BEHIND: p = 1
    np.testing.assert_allclose(terms[1], terms[0], rtol=1e-12)
    np.testing.assert_allclose(terms[2], terms[0], rtol=1e-12)


def test_empty_inputs_keep_one_term_per_component_and_measurement():
    z = np.array([A, BEHIND])
    none = np.zeros((0, 2, 3))
    mw = MeasurementWise().terms(context(none, np.zeros(0, int), [0.9], z))
    assert mw.visible.shape == (0,) and mw.hidden.shape == (0,)
    np.testing.assert_allclose(mw.seen_hidden, [1.0, 0.0])
    nothing_seen = MeasurementWise().terms(context(states(A), [0], [0.9], np.zeros((0, 2, 2))))
    assert nothing_seen.seen_hidden.shape == (0,)
    np.testing.assert_array_equal(nothing_seen.hidden, [0.0])
    ow = ObjectWiseExpectedValue().terms(context(none, np.zeros(0, int), [0.9], z))
    assert ow.visible.shape == (0,) and ow.hidden.shape == (0,)


def test_combine_reads_the_last_axis():
    p = np.array([[[0.5, 0.5], [0.2, 0.0]], [[1.0, 0.0], [0.0, 0.0]]])
    np.testing.assert_allclose(combine(p), [[0.75, 0.2], [1.0, 0.0]])


def crowd(rng, count):
    """`count` boxes in a small area, so many overlap; some exactly as A and BEHIND."""
    x0 = rng.uniform(0, 300, count)
    y0 = rng.uniform(0, 200, count)
    w = rng.uniform(10, 40, count)
    h = rng.uniform(20, 80, count)
    boxes = np.stack([np.stack([x0, x0 + w], -1), np.stack([y0, y0 + h], -1)], axis=1)
    boxes[0], boxes[1] = A, BEHIND
    return boxes


@pytest.mark.parametrize("with_weights", [False, True])
@pytest.mark.parametrize("with_skip", [False, True])
def test_sparse_visible_equals_the_full_table(with_weights, with_skip):
    """Above DENSE_PAIRS pairs `visible` combines the overlapping pairs only; it gives the
    full table's numbers, with occluder weights, with a skipped occluder per box, and with
    a sure occlusion (p = 1: box 0 behind box 1) without a divide-by-zero warning."""
    rng = np.random.default_rng(7)
    hidden, occluders = crowd(rng, 80), crowd(rng, 70)
    assert len(hidden) * len(occluders) > DENSE_PAIRS
    weights = rng.uniform(0.2, 1.0, 70) if with_weights else None
    if with_weights:
        weights[1] = 1.0
    skip = rng.integers(-1, 70, 80) if with_skip else None
    if with_skip:
        skip[0] = 5
    geometry = BoxOcclusionGeometry()
    full = geometry.visible(hidden, occluders, weights, skip, sparse=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sparse = geometry.visible(hidden, occluders, weights, skip)
    np.testing.assert_allclose(sparse, full, rtol=1e-12, atol=1e-15)
    assert full[0] == 0.0 and sparse[0] == 0.0
    assert (full < 1).sum() > 20  # many occluded boxes: the comparison covers something
    p = geometry(hidden, occluders)
    if weights is not None:
        p = p * weights
    if skip is not None:
        p[skip[:, None] == np.arange(70)] = 0.0
    np.testing.assert_allclose(full, np.prod(1 - p, axis=1), rtol=1e-12)


def in_order(factors):
    """prod over the last axis, multiplied left to right as the compiled full table does."""
    return np.array([reduce(mul, row.tolist(), 1.0) for row in factors])


def test_single_precision_boxes_are_computed_in_double():
    """float32 boxes give the numbers of the same boxes in float64 (float32 arithmetic would
    round overlaps and heights differently), in the table and in both forms of `visible`."""
    rng = np.random.default_rng(5)
    hidden, occluders = crowd(rng, 80).astype(np.float32), crowd(rng, 70).astype(np.float32)
    geometry = BoxOcclusionGeometry()
    wide = hidden.astype(float), occluders.astype(float)
    table = geometry(*wide)
    assert (table > 0).sum() > 100
    assert np.array_equal(geometry(hidden, occluders), table)
    for sparse in (False, True):
        assert np.array_equal(geometry.visible(hidden, occluders, sparse=sparse),
                              geometry.visible(*wide, sparse=sparse))


@pytest.mark.parametrize("sparse", [False, True])
def test_without_occluders_every_box_is_visible(sparse):
    geometry = BoxOcclusionGeometry()
    nothing = np.zeros((0, 2, 2))
    assert geometry.visible(np.array([A, BEHIND]), nothing, sparse=sparse).tolist() == [1.0, 1.0]
    assert geometry.visible(nothing, np.array([A]), sparse=sparse).shape == (0,)


@pytest.mark.parametrize("settings,message", [
    (dict(gain=0.0), "occlusion gain must be positive"),
    (dict(gain=-1.0), "occlusion gain must be positive"),
    (dict(ramp_zero=0.2, ramp_one=0.2), "occlusion ramp must rise: ramp_one > ramp_zero"),
    (dict(ramp_zero=0.3, ramp_one=0.2), "occlusion ramp must rise: ramp_one > ramp_zero"),
])
def test_geometry_settings_are_checked(settings, message):
    with pytest.raises(ValueError) as err:
        BoxOcclusionGeometry(**settings)
    assert str(err.value) == message


def test_a_small_gain_and_a_steep_ramp_are_valid():
    geometry = BoxOcclusionGeometry(gain=0.5, ramp_zero=0.0, ramp_one=1e-9)
    p = geometry(A[None], BEHIND[None])  # half covered: 0.5 * 0.5; bottom far lower
    np.testing.assert_allclose(p, [[0.25]], rtol=1e-12)


def test_boxes_apart_on_both_axes_never_hide_each_other():
    """Negative overlaps on both axes must not multiply into a positive area."""
    p = BoxOcclusionGeometry()(A[None], edges(20, 30, 20, 40)[None])
    assert p[0, 0] == 0.0


def test_sub_pixel_boxes_keep_their_own_size():
    """Box sizes are floored at 1e-9 only against division by zero: a 0.5 px box half
    covered is half covered (cover 0.3 here, times the gain 2), and the bottom gap is read in
    the occluder's own 0.5 px height (0.4 of it, past the ramp's top)."""
    a = edges(0.0, 0.5, 0.0, 0.5)
    b = edges(0.25, 0.75, 0.2, 0.7)
    p = BoxOcclusionGeometry()(a[None], b[None])
    np.testing.assert_allclose(p, [[0.6]], rtol=1e-12)
    b_low = edges(0.25, 0.75, 0.05, 0.55)  # gap 0.1: (0.1 + 0.1) / 0.35 of the ramp
    overlap = 0.25 * 0.45
    np.testing.assert_allclose(BoxOcclusionGeometry()(a[None], b_low[None]),
                               [[min(2 * overlap / 0.25, 1) * 0.2 / 0.35]], rtol=1e-12)


def test_models_by_name_keep_the_geometry_and_floor_given():
    from occtrack.occlusion.boxes import box_occlusion

    geometry = BoxOcclusionGeometry(gain=3.0)
    assert box_occlusion("measurement-wise", geometry).geometry is geometry
    model = box_occlusion("object-wise", geometry, min_existence=0.4)
    assert model.geometry is geometry and model.min_existence == 0.4
    default = box_occlusion("object-wise")
    assert default.min_existence == 0.1 and default.geometry == BoxOcclusionGeometry()
    with pytest.raises(ValueError) as err:
        box_occlusion("grid")
    assert str(err.value) == ("unknown occlusion model 'grid'; choose from none, object-wise, "
                              "measurement-wise")


def test_without_gating_the_models_build_the_full_tables():
    """gating False: the terms are the full K x N table's numbers to the last bit (the
    checking mode); gating True: the overlapping pairs' numbers, equal up to rounding."""
    rng = np.random.default_rng(11)
    comps, z = crowd(rng, 130), crowd(rng, 70)
    means = states(*comps)
    owner = np.repeat(np.arange(65), 2)  # 130 x 65 mean boxes: above DENSE_PAIRS too
    existence = rng.uniform(0.2, 1.0, 65)
    geometry = BoxOcclusionGeometry()
    for gating in (False, True):
        ctx = context(means, owner, existence, z)
        ctx = type(ctx)(**{**ctx.__dict__, "gating": gating})
        boxes = ctx.measurement_model.predicted_edges(means)
        mw = MeasurementWise().terms(ctx)
        hidden = 1 - np.prod(1 - geometry(boxes, z), axis=-1)
        p = geometry(z, z)
        np.fill_diagonal(p, 0.0)
        seen = 1 - np.prod(1 - p, axis=-1)
        ow = ObjectWiseExpectedValue().terms(ctx).visible
        if not gating:
            # the full table multiplied occluder by occluder, to the last bit
            assert np.array_equal(mw.hidden, 1 - in_order(1 - geometry(boxes, z)))
            assert np.array_equal(mw.seen_hidden, 1 - in_order(1 - p))
            assert np.array_equal(MeasurementWise().seen_hidden(z, sparse=False),
                                  1 - in_order(1 - p))
            mean = (boxes[0::2] + boxes[1::2]) / 2  # each object's two components, weights 1
            q = geometry(boxes, mean) * existence
            q[owner[:, None] == np.arange(65)] = 0.0  # never by itself
            assert np.array_equal(ow, in_order(1 - q))
            np.testing.assert_allclose(ow, np.prod(1 - q, axis=-1), rtol=1e-14)
            full = ow
        else:
            np.testing.assert_allclose(mw.hidden, hidden, rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(mw.seen_hidden, seen, rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(ow, full, rtol=1e-12, atol=1e-15)
    assert (hidden > 0).sum() > 20 and (seen > 0).sum() > 10 and (full < 1).sum() > 10
