"""The pure parts of the drawing tools: templates, snapping, typed coordinates,
crossing edges (hand-computed values)."""

import numpy as np
import pytest

from sandbox.shapes import ShapeError, validate_polygon
from sandbox.shapes.drawing import (
    crossing_edges,
    edge_name,
    format_coordinates,
    parse_coordinates,
    snap,
    without_repeats,
)
from sandbox.shapes.geometry import signed_area
from sandbox.shapes.templates import CELL, placed, template_names, template_vertices

# ----------------------------------------------------------------- templates
#: Areas worked out by hand: the figures from 2 m strokes in a 6 m square, the letters in 1.5 m cells.
AREAS = {
    "L": 6 * 2 + 2 * 4,           # bottom arm, then the upright above it
    "T": 6 * 2 + 2 * 4,           # bar, stem
    "U": 6 * 6 - 2 * 4,           # square less the slot
    "C": 6 * 6 - 4 * 2,
    "plus": 6 * 6 - 4 * (2 * 2),  # square less four corner squares
    "arrow": 3 * 2 + 6 * 3 / 2,   # shaft, triangular head
    "house": 6 * 4 + 6 * 3 / 2,   # walls, roof
    "letter E": 10 * CELL ** 2,   # stem 5 cells, bars 2 + 1 + 2
    "letter F": 8 * CELL ** 2,    # stem 5, top bar 2, middle 1
    "letter H": 11 * CELL ** 2,   # stems 5 + 5, bridge 1
    "letter S": 11 * CELL ** 2,   # bars 3 + 3 + 3, joins 1 + 1
    "letter Z": 9 * CELL ** 2,    # bars 3 + 3, slanted stroke 1 wide x 3 tall
}
SIZES = {"L": (6, 6), "house": (6, 7), "letter E": (4.5, 7.5), "letter Z": (4.5, 7.5)}


def test_every_template_has_a_hand_computed_area():
    assert set(template_names()) == set(AREAS)
    assert {"L", "T", "U", "C", "plus", "arrow", "house"} <= set(template_names())


@pytest.mark.parametrize("name", sorted(AREAS))
def test_template_is_a_simple_counter_clockwise_polygon_of_its_area(name):
    vertices = template_vertices(name)
    checked = validate_polygon(vertices, name)  # simple, at least 3 points, non-zero area
    assert len(checked) == len(vertices)  # no repeated vertex to drop
    assert signed_area(vertices) == pytest.approx(AREAS[name])  # positive: counter-clockwise
    assert vertices.min(axis=0).tolist() == [0.0, 0.0]
    assert crossing_edges(vertices) == []
    assert np.all(np.abs(vertices / 0.5 - np.round(vertices / 0.5)) < 1e-12)  # on the default 0.5 m grid


@pytest.mark.parametrize("name", sorted(SIZES))
def test_template_size(name):
    vertices = template_vertices(name)
    assert np.ptp(vertices, axis=0).tolist() == list(SIZES[name])


def test_template_is_a_fresh_array():
    template_vertices("L")[0] = (99, 99)
    assert template_vertices("L")[0].tolist() == [0, 0]


def test_placed_centres_the_bounding_box_on_the_grid():
    moved = placed(template_vertices("L"), (32.0, 32.0), 0.5)
    assert moved.min(axis=0).tolist() == [29.0, 29.0] and moved.max(axis=0).tolist() == [35.0, 35.0]
    house = placed(template_vertices("house"), (32.0, 32.0), 1.0)  # 7 m tall: centre 3.5 rounds to a whole shift
    assert house.min(axis=0).tolist() == [29.0, 28.0]
    assert placed(template_vertices("house"), (32.0, 32.0)).min(axis=0).tolist() == [29.0, 28.5]


# ------------------------------------------------------------------ snapping
def test_snap_to_the_nearest_grid_node():
    assert snap((1.26, -0.24), 0.5) == (1.5, 0.0)
    assert snap((1.24, 0.76), 0.5) == (1.0, 1.0)
    assert snap((0.31, 7.0), 0.1) == (0.3, 7.0)  # not 0.30000000000000004
    assert snap((3.3, 4.6), 2.0) == (4.0, 4.0)
    assert snap((-0.1, -0.2), 0.5) == (0.0, 0.0) and str(snap((-0.1, 0), 0.5)[0]) == "0.0"  # no -0.0


def test_snap_off_keeps_the_point():
    assert snap((1.26, 2.71), 0) == (1.26, 2.71)


def test_without_repeats_drops_doubles_and_the_closing_point():
    assert without_repeats([(0, 0), (1, 0), (1, 0), (1, 1), (0, 0)]) == [(0, 0), (1, 0), (1, 1)]
    assert without_repeats([]) == []


# --------------------------------------------------------------- coordinates
L_POINTS = [(0.0, 0.0), (6.0, 0.0), (6.0, 2.0), (2.0, 2.0), (2.0, 6.0), (0.0, 6.0)]


@pytest.mark.parametrize("text", [
    "0 0\n6 0\n6 2\n2 2\n2 6\n0 6",
    "0,0\n6,0\n6,2\n2,2\n2,6\n0,6\n",
    "0, 0\n  6, 0\n\n6, 2\n2, 2\n2, 6\n0, 6",
    "0,0; 6,0; 6,2; 2,2; 2,6; 0,6",
    "(0, 0); (6, 0); (6, 2); (2, 2); (2, 6); (0, 6)",
    "[[0, 0], [6, 0], [6, 2], [2, 2], [2, 6], [0, 6]]",
    "# my L\n0 0\n6 0\n6 2\n2 2\n2 6\n0 6",
    "0e0 0\n6.0 0\n6 2.\n2 2\n2 6\n0 6",
])
def test_every_coordinate_form_reads_the_same_l(text):
    assert parse_coordinates(text) == L_POINTS


def test_negative_and_fractional_coordinates():
    assert parse_coordinates("-1.5 2.25; 3 -4") == [(-1.5, 2.25), (3.0, -4.0)]


@pytest.mark.parametrize("text, fragments", [
    ("", ["nothing to read"]),
    ("0 0\n6\n6 2", ["pair 2", "'6' is not two numbers"]),
    ("0 0; 1 2 3", ["pair 2", "'1 2 3' is not two numbers"]),
    ("0 0\nsix 0", ["pair 2", "'six' is not a number"]),
    ("0 0\nnan 1", ["pair 2", "not a finite number"]),
    ("[[0, 0], [1, 2", ["not a JSON list", "line 1"]),
    ("[[0, 0], [1, 2, 3]]", ["pair 2", "[1, 2, 3] is not an [x, y] pair"]),
    ('[[0, 0], ["a", 1]]', ["pair 2", "'a' is not a number"]),
])
def test_malformed_coordinates_say_where_in_one_line(text, fragments):
    with pytest.raises(ShapeError) as info:
        parse_coordinates(text)
    message = str(info.value)
    assert "\n" not in message and message.startswith("coordinates"), message
    for fragment in fragments:
        assert fragment in message, message


def test_format_coordinates_round_trips():
    text = format_coordinates([(0.0, 0.5), (6.25, -2.0), (1e-3, 3.0)])
    assert text == "0 0.5\n6.25 -2\n0.001 3"
    assert parse_coordinates(text) == [(0.0, 0.5), (6.25, -2.0), (0.001, 3.0)]


# ------------------------------------------------------------------ crossings
def test_a_simple_outline_has_no_crossing_edges():
    assert crossing_edges(L_POINTS) == []
    assert crossing_edges([(0, 0), (1, 0)]) == []  # not an outline yet


def test_bowtie_crosses_on_edges_1_2_and_3_4():
    bowtie = [(0, 0), (4, 4), (4, 0), (0, 4)]  # 1-2 and 3-4 cross at (2, 2)
    assert crossing_edges(bowtie) == [(0, 2)]
    assert [edge_name(i, 4) for i in (0, 2)] == ["1-2", "3-4"]
    with pytest.raises(ShapeError, match="vertices 1-2 and 3-4"):  # the floor's numbers are the message's
        validate_polygon(bowtie, "drawn shape")


def test_closing_edge_can_cross():
    # 1 (0,0) 2 (4,0) 3 (4,4) 4 (2,-2): edge 3-4 crosses 1-2 at (8/3, 0); the closing edge 4-1 only meets 1-2 at 1.
    assert crossing_edges([(0, 0), (4, 0), (4, 4), (2, -2)]) == [(0, 2)]
    # 1 (0,0) 2 (4,0) 3 (4,4) 4 (5,2): the closing edge 4-1 crosses 2-3 at (4, 1.6).
    assert crossing_edges([(0, 0), (4, 0), (4, 4), (5, 2)]) == [(1, 3)]
    assert edge_name(3, 4) == "4-1"


def test_touching_counts_and_a_shared_corner_does_not():
    # Vertex 4 (2, 0) lies on edge 1-2: edges 3-4 and 4-5 touch it (a T-junction).
    t_junction = [(0, 0), (4, 0), (4, 4), (2, 0), (0, 4)]
    assert crossing_edges(t_junction) == [(0, 2), (0, 3)]
    # 2-3 doubles back along its neighbour 1-2 (an overlap, not just the corner), and 3-4 starts on 1-2.
    assert crossing_edges([(0, 0), (4, 0), (2, 0), (2, 3)]) == [(0, 1), (0, 2)]
