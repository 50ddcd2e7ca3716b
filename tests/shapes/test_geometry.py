"""Pure polygon geometry against hand-computed values."""

import numpy as np
import pytest

from sandbox.shapes import geometry

SQUARE = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)
L_SHAPE = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)


def test_area_and_centroid():
    assert geometry.signed_area(SQUARE) == pytest.approx(4.0)
    assert geometry.signed_area(SQUARE[::-1]) == pytest.approx(-4.0)
    assert geometry.centroid(SQUARE) == pytest.approx([1.0, 1.0])
    # L of three unit squares: centroid at (5/6, 5/6).
    assert geometry.centroid(L_SHAPE) == pytest.approx([5 / 6, 5 / 6])


@pytest.mark.parametrize("order", [1, -1])
def test_interior_angles_do_not_depend_on_vertex_order(order):
    angles = geometry.interior_angles(L_SHAPE[::order])
    expected = np.array([90, 90, 90, 270, 90, 90], dtype=float)[::order]
    assert angles == pytest.approx(expected)


def test_star_angles():
    t = np.pi / 2 + np.arange(10) * np.pi / 5
    r = np.where(np.arange(10) % 2 == 0, 5.0, 2.5)
    star = np.column_stack([r * np.cos(t), r * np.sin(t)])
    angles = geometry.interior_angles(star)
    assert (angles[0::2] < 180).all() and (angles[1::2] > 180).all()
    # Interior angles of a simple 10-gon sum to 8 * 180.
    assert angles.sum() == pytest.approx(8 * 180)


def test_fit_to_area_moves_centroid_and_scales():
    fitted = geometry.fit_to_area(L_SHAPE * 7 + 3, 12.0, np.array([32.0, 32.0]))
    assert abs(geometry.signed_area(fitted)) == pytest.approx(12.0)
    assert geometry.centroid(fitted) == pytest.approx([32.0, 32.0])


def test_flare_factors_by_hand():
    # Square: 90 degree corners -> 90 * 1.75 / 90 = 1.75.
    assert geometry.flare_factors(SQUARE - 1, 1.75) == pytest.approx([1.75] * 4)
    # Equilateral triangle: 60 degrees -> 90 * 1.75 / 60 = 2.625.
    tri = np.array([[0, 0], [1, 0], [0.5, np.sqrt(3) / 2]])
    assert geometry.flare_factors(tri, 1.75) == pytest.approx([2.625] * 3)
    # Small amounts never pull corners in: max(1, ...).
    assert geometry.flare_factors(SQUARE - 1, 0.5) == pytest.approx([1.0] * 4)
    # Reflex corner of the L gets no flare.
    assert geometry.flare_factors(L_SHAPE, 1.75)[3] == 1.0


def test_flare_inserts_midpoints_and_pushes_corners():
    rel = SQUARE - 1.0
    out, is_corner = geometry.flare(rel, 1.75)
    assert len(out) == 8 and is_corner.tolist() == [True, False] * 4
    assert out[0] == pytest.approx(rel[0] * 1.75)
    assert out[1] == pytest.approx([0.0, -1.0])  # midpoint of the first edge, unmoved


def test_distance_and_inside():
    pts = np.array([[0.5, 0.5], [1.5, 1.5], [3.0, 0.0], [1.0, -1.0]])
    assert geometry.points_in_polygon(pts, L_SHAPE).tolist() == [True, False, False, False]
    assert geometry.distance_to_outline(pts, L_SHAPE) == pytest.approx([0.5, 0.5, 1.0, 1.0])


def test_compiled_outline_distance_is_the_numpy_formula_to_the_bit():
    rng = np.random.default_rng(3)
    for n in (3, 10, 49, 96):
        vertices = rng.normal(size=(n, 2)) * 10
        points = rng.uniform(-30, 30, size=(500, 2))
        reference = geometry.distances_to_edges(points, vertices).min(axis=1)
        assert np.array_equal(geometry.distance_to_outline(points, vertices), reference)
    # By hand: the unit square's edges are 0.5 from its centre and 1 from (2, 0.5).
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    np.testing.assert_allclose(geometry.distance_to_outline(np.array([[0.5, 0.5], [2, 0.5]]), square), [0.5, 1.0])
