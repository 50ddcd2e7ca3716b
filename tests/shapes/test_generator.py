"""The goal-shape generator (sandbox/shapes/generator.py): shapes made again from (family, seed), valid simple
polygons within the product's limits, each family's features present, and the width rules by hand."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from sandbox.model import budget
from sandbox.model.config import Config
from sandbox.shapes import ShapeError, generator, geometry, shape_vertices, validate_polygon
from sandbox.shapes.generator import FAMILIES, KINDS

#: Enough seeds that every kind of every family is drawn (kinds are taken in turn by seed).
SEEDS = {family: range(max(2, len(KINDS[family]))) for family in FAMILIES}


def shapes_of(family: str) -> list[generator.GeneratedShape]:
    return [generator.generate(family, seed) for seed in SEEDS[family]]


def test_the_generators_numbers_are_the_products():
    """The default goal's area and construction area, and the outlines' vertex bound, as the model has them
    (the generator sits below the model and cannot ask it)."""
    config = Config()
    assert generator.GOAL_AREA == pytest.approx(config.boxes * config.box_area, rel=1e-12)
    assert generator.CONSTRUCTION_SIZE == config.construction_size
    assert generator.MAX_VERTICES == budget.MAX_GOAL_VERTICES


@pytest.mark.parametrize("family", FAMILIES)
def test_the_same_seed_gives_the_same_vertices(family):
    first = generator.generate(family, 3)
    generator._generate.cache_clear()  # drawn again, not read from the cache
    again = generator.generate(family, 3)
    assert np.array_equal(first.vertices, again.vertices) and first.params == again.params
    assert not np.array_equal(first.vertices, generator.generate(family, 4).vertices)


@pytest.mark.parametrize("family", FAMILIES)
def test_every_family_yields_valid_simple_polygons_that_fit(family):
    for shape in shapes_of(family):
        v = shape.vertices
        polygon = Polygon(v)
        assert polygon.is_valid and polygon.exterior.is_simple and not polygon.interiors, shape.name
        assert len(np.unique(v, axis=0)) == len(v), f"{shape.name} visits a vertex twice (touches itself)"
        validate_polygon(v, shape.name)  # the product's own check: no crossing, no touching
        assert 3 <= len(v) <= generator.MAX_VERTICES
        assert polygon.area == pytest.approx(generator.GOAL_AREA, rel=0.01)
        assert (np.ptp(v, axis=0) <= generator.MAX_EXTENT).all()
        assert generator.CONSTRUCTION_SIZE - generator.MAX_EXTENT == 1.0  # a box's size clear all round
        assert geometry.signed_area(v) > 0  # counter-clockwise
        assert geometry.centroid(v) == pytest.approx([0.0, 0.0], abs=0.01)
        assert generator.problems(v, family) == []


def test_each_familys_features_are_present():
    for shape in shapes_of("convex"):
        assert (geometry.interior_angles(shape.vertices) < 180.0).all()
        assert geometry.interior_angles(shape.vertices).min() >= generator.MIN_CORNER_ANGLE
    for shape in shapes_of("rectilinear"):
        edges = np.roll(shape.vertices, -1, axis=0) - shape.vertices
        assert ((np.abs(edges) < 1e-9).any(axis=1)).all(), f"{shape.name} has an edge off the grid's axes"
    for family in ("branching", "curved"):
        for shape in shapes_of(family):  # arms, prongs, hollows: far from their hulls
            polygon = Polygon(shape.vertices)
            assert polygon.area / polygon.convex_hull.area < 0.9, shape.name
    for family in FAMILIES:
        assert {shape.kind for shape in shapes_of(family)} == (set(KINDS[family]) or {""})


def test_the_widths_by_hand():
    """A 6 m square with a 1 m wide arm 4 m long: the arm, 4 of its 40 m², is narrower than 2 m. A U whose
    slot is 1 m wide and 4 m deep: closing by 1.5 m fills the slot, 4 m² against the U's 32."""
    arm = shapely.union(shapely.box(0, 0, 6, 6), shapely.box(6, 2, 10, 3))
    assert generator.narrowest_part(arm, 2.0, square=True) == pytest.approx(4 / 40)
    assert generator.narrowest_part(arm, 0.9, square=True) == pytest.approx(0.0, abs=1e-12)
    u = shapely.box(0, 0, 6, 6).difference(shapely.box(2.5, 2, 3.5, 6))
    assert generator.narrowest_gap(u, 1.5, square=True) == pytest.approx(4 / 32)
    assert generator.narrowest_gap(u, 0.9, square=True) == pytest.approx(0.0, abs=1e-12)
    # At the goal's area the arm is 1.42 m wide: the rules refuse it.
    at_goal_area = np.asarray(arm.exterior.coords)[:-1] * (generator.GOAL_AREA / arm.area) ** 0.5
    assert "10.0% of it lies in parts narrower than 2 m" in generator.problems(at_goal_area, "rectilinear")


def test_convex_width_by_hand():
    assert generator.convex_width(np.array([[0, 0], [4, 0], [4, 2], [0, 2]], dtype=float)) == pytest.approx(2.0)
    # A right triangle with legs 3 and 4: its least width is the height on the hypotenuse, 12 / 5.
    assert generator.convex_width(np.array([[0, 0], [4, 0], [0, 3]], dtype=float)) == pytest.approx(2.4)


@pytest.mark.parametrize("family", FAMILIES)
def test_the_parameters_make_the_same_shape(family):
    shape = generator.generate(family, 1)
    assert np.array_equal(generator.from_params(family, shape.params), shape.vertices)


def test_names_round_trip_and_name_a_goal():
    shape = generator.generate("curved", 42)
    assert shape.name == "gen-curved-0042"
    assert generator.parse_name("gen-curved-0042") == ("curved", 42)
    assert generator.parse_name("GEN-Curved-42") == ("curved", 42)
    for other in ("square", "gen-nosuch-0001", "gen-curved-", "gen-curved-0042.txt", "gen-curved--1"):
        assert generator.parse_name(other) is None
    assert np.array_equal(shape_vertices("gen-curved-0042"), shape.vertices)
    with pytest.raises(ShapeError, match="not a built-in shape, an existing file or a generated shape"):
        shape_vertices("gen-nosuch-0001")


def test_a_draw_takes_the_families_in_turn_and_two_draws_share_no_shape():
    first = generator.draw(7, ("convex", "star", "curved"), generator_seed=2)
    assert [s.name for s in first] == ["gen-convex-2000", "gen-star-2000", "gen-curved-2000", "gen-convex-2001",
                                       "gen-star-2001", "gen-curved-2001", "gen-convex-2002"]
    assert not {s.name for s in generator.draw(6)} & {s.name for s in generator.draw(6, generator_seed=1)}
    assert generator.families_from_text("all") == FAMILIES
    assert generator.families_from_text("curved, star,curved") == ("curved", "star")
    with pytest.raises(ShapeError, match="unknown shape family 'blob'; the families are: all, convex"):
        generator.families_from_text("star,blob")
    with pytest.raises(ShapeError, match="a draw holds 0 to 5,000 shapes"):
        generator.draw(5001)
