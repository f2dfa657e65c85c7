"""GOSPA's parts pinned to hand-computed numbers: IoU of boxes, set shapes, the sum over
frames part by part, and the refusals' messages."""

from __future__ import annotations

import numpy as np
import pytest

from occtrack.metrics.gospa import Gospa, gospa, gospa_from_distances, iou


def test_iou_by_hand():
    a = np.array([[0.0, 0.0, 10.0, 20.0]])
    b = np.array([[5.0, 10.0, 10.0, 20.0], [20.0, 0.0, 5.0, 5.0], [0.0, 0.0, 10.0, 20.0],
                  [2.0, 4.0, 4.0, 6.0], [0.0, 25.0, 10.0, 10.0]])
    inter = np.array([5 * 10, 0, 200, 24, 0])
    union = np.array([200 + 200 - 50, 200 + 25, 200, 200, 300])
    np.testing.assert_allclose(iou(a, b), [inter / union], rtol=1e-13)
    np.testing.assert_array_equal(iou(np.zeros((1, 4)), np.zeros((1, 4))), [[0.0]])
    g = gospa(a, b[:1], "iou", c=1.0)
    assert (g.matched, g.localisation) == (1, pytest.approx(1 - 50 / 350))


@pytest.mark.parametrize("truth,shape", [([], (0, 0)), (np.zeros((0, 3)), (0, 3)),
                                         ([1.0, 2.0, 3.0], (3, 1)), ([[1.0, 2.0]], (1, 2))])
def test_sets_of_any_shape(truth, shape):
    g = gospa(truth, truth, c=4.0, p=2.0)
    assert g.total == 0.0 and g.matched == shape[0]
    g = gospa(truth, np.zeros((0, 1)), c=4.0, p=2.0)
    assert (g.n_missed, g.missed, g.false) == (shape[0], 8.0 * shape[0], 0.0)


def test_one_dimensional_points_by_hand():
    g = gospa([0.0, 10.0], [1.0, 3.0, 50.0], c=5.0, p=2.0)
    # 0 - 1 matched (1), 10 - 3 too far (7 >= 5): 10 missed, 3 and 50 false
    assert (g.matched, g.n_missed, g.n_false) == (1, 1, 2)
    assert (g.localisation, g.missed, g.false) == (1.0, 12.5, 25.0)
    assert g.total == pytest.approx(np.sqrt(38.5), rel=1e-13)


def test_sum_adds_each_part_to_its_own():
    a = Gospa(1.0, 2.0, 3.0, 4.0, 5, 6, 7)
    b = Gospa(10.0, 20.0, 30.0, 40.0, 50, 60, 70)
    assert a + b == Gospa(11.0, 22.0, 33.0, 44.0, 55, 66, 77)


@pytest.mark.parametrize("distances,c,p,message", [
    (np.zeros(3), 1.0, 1.0, "distances must be a 2-D (true x estimated) matrix"),
    (np.array([[0.0, np.nan]]), 1.0, 1.0, "distances contain NaN"),
    (np.zeros((1, 1)), 0.0, 1.0, "GOSPA needs c > 0 and p >= 1"),
    (np.zeros((1, 1)), 1.0, 0.5, "GOSPA needs c > 0 and p >= 1"),
])
def test_refusals_say_why(distances, c, p, message):
    with pytest.raises(ValueError) as err:
        gospa_from_distances(distances, c, p)
    assert str(err.value) == message


def test_unknown_distance_lists_the_known_ones():
    with pytest.raises(ValueError) as err:
        gospa([[0.0]], [[0.0]], "manhattan")
    assert str(err.value) == ("unknown distance 'manhattan'; choose from ['euclidean', 'iou'] "
                              "or pass a callable")


def test_a_pair_at_exactly_c_is_a_miss_and_a_false_object():
    g = gospa_from_distances([[2.0]], c=2.0, p=1.0)
    assert (g.matched, g.n_missed, g.n_false, g.localisation, g.total) == (0, 1, 1, 0.0, 2.0)
    g = gospa_from_distances([[np.inf, 1.0]], c=2.0)
    assert (g.matched, g.localisation, g.false) == (1, 1.0, 1.0)


def test_a_callable_distance_and_the_default_cut_off():
    def manhattan(a, b):
        return np.abs(a[:, None, :] - b[None, :, :]).sum(-1)

    g = gospa([[0.0, 0.0]], [[1.0, 2.0]], manhattan, c=5.0)
    assert (g.matched, g.localisation) == (1, 3.0)
    g = gospa([[0.0]], [[0.75]])  # c = 1, p = 1 by default
    assert (g.matched, g.localisation, g.total) == (1, 0.75, 0.75)
    g = gospa([[0.0]], [[1.5]])
    assert (g.matched, g.total) == (0, 1.0)


def test_iou_of_integer_and_sub_unit_boxes():
    """Integer boxes are numbers like any other; normalised boxes (area below 1) have an IoU
    too; left and top are read from their own columns."""
    g = gospa([[0, 0, 10, 20]], [[5, 10, 10, 20]], "iou", c=1.0)
    assert g.localisation == pytest.approx(1 - 50 / 350)
    small = np.array([[0.1, 0.2, 0.5, 0.5]])
    np.testing.assert_allclose(iou(small, small), [[1.0]])
    shifted = np.array([[0.3, 0.2, 0.5, 0.5]])  # left moved: 0.3 x 0.5 overlap
    np.testing.assert_allclose(iou(small, shifted), [[0.15 / 0.35]], rtol=1e-12)


def test_members_given_as_matrices_are_flattened_to_rows():
    """A set of (2, 2) edge boxes is a set of 4-vectors."""
    truth = np.zeros((2, 2, 2))
    g = gospa(truth, np.full((1, 2, 2), 0.25), c=2.0)
    assert (g.matched, g.localisation, g.n_missed) == (1, 0.5, 1)
