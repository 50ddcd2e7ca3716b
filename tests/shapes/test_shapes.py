"""Polygon files: every format, every built-in shape, every rejection (SPEC §8)."""
import math
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Polygon

import sandbox.shapes as shapes
from sandbox.model.config import Config
from sandbox.shapes import (
    ShapeError,
    builtin_shape_names,
    load_polygon,
    parse_polygon,
    polygon_to_text,
    shape_vertices,
    validate_polygon,
)
from sandbox.shapes.builtin import SHAPES_DIR

DATA = Path(__file__).parents[1] / "data"
SQUARE = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], dtype=float)
BUILTINS = ["arrow", "crescent", "house", "l-shape", "rectangle", "square", "star",
            "t-shape", "triangle"]


def rejects(text, *fragments, source="bad.txt", fmt=None):
    """Parse text expecting a ShapeError; check it is one line naming source and fragments."""
    with pytest.raises(ShapeError) as info:
        parse_polygon(text, source=source, fmt=fmt)
    message = str(info.value)
    assert "\n" not in message and message.startswith(source), message
    for fragment in fragments:
        assert fragment in message, message
    return message


# ------------------------------------------------------------------ formats

@pytest.mark.parametrize("name", ["square.txt", "square.csv", "square.geojson", "square.json",
                                  "square.wkt", "square.svg", "square-path.svg"])
def test_every_format_file_gives_the_same_square(name):
    vertices = load_polygon(DATA / name)
    assert vertices.dtype == np.float64 and vertices.shape == (4, 2)
    np.testing.assert_array_equal(vertices, SQUARE)


@pytest.mark.parametrize("name", ["square.txt", "square.geojson", "square.json",
                                  "square.wkt", "square.svg", "square-path.svg"])
def test_format_is_sniffed_from_content_for_uploads(name):
    text = (DATA / name).read_text()
    np.testing.assert_array_equal(parse_polygon(text, source="<upload>"), SQUARE)


@pytest.mark.parametrize("text", [
    '{"type": "Polygon", "coordinates": [[[-5,-5],[5,-5],[5,5],[-5,5],[-5,-5]]]}',
    '{"type": "Feature", "geometry": {"type": "Polygon", '
    '"coordinates": [[[-5,-5,0],[5,-5,0],[5,5,0],[-5,5,0],[-5,-5,0]]]}}',
    '{"type": "MultiPolygon", "coordinates": [[[[-5,-5],[5,-5],[5,5],[-5,5],[-5,-5]]]]}',
])
def test_geojson_variants(text):
    np.testing.assert_array_equal(parse_polygon(text, "x.geojson"), SQUARE)


def test_plain_text_separators_comments_and_closing_vertex():
    text = "# header\n\n-5, -5  # first\n5\t-5\n5,5\n\n-5 5\n-5 -5\n"
    np.testing.assert_array_equal(parse_polygon(text, "s.txt"), SQUARE)


def test_explicit_format_overrides_extension():
    np.testing.assert_array_equal(
        parse_polygon("POLYGON((-5 -5, 5 -5, 5 5, -5 5, -5 -5))", "s.txt", fmt="wkt"), SQUARE)


def test_svg_transforms_are_applied():
    svg = ('<svg xmlns="http://www.w3.org/2000/svg"><g transform="translate(10, 20)">'
           '<polygon transform="scale(2)" points="0,0 1,0 1,1 0,1"/></g></svg>')
    expected = [[10, -20], [12, -20], [12, -22], [10, -22]]
    np.testing.assert_allclose(parse_polygon(svg, "t.svg"), expected)


def test_svg_relative_path_with_implicit_lineto():
    svg = '<svg><path d="m 1 1 2 0 0 2 -2 0 Z"/></svg>'
    np.testing.assert_allclose(parse_polygon(svg, "p.svg"), [[1, -1], [3, -1], [3, -3], [1, -3]])


def test_consecutive_duplicates_are_dropped_silently():
    text = "-5 -5\n-5 -5\n5 -5\n5 5\n5 5\n5 5\n-5 5\n-5 -5\n"
    np.testing.assert_array_equal(parse_polygon(text, "d.txt"), SQUARE)


def test_clockwise_and_counter_clockwise_both_load_in_file_order():
    ccw = parse_polygon(polygon_to_text(SQUARE), "ccw.txt")
    cw = parse_polygon(polygon_to_text(SQUARE[::-1]), "cw.txt")
    np.testing.assert_array_equal(ccw, SQUARE)
    np.testing.assert_array_equal(cw, SQUARE[::-1])


def test_round_trip_through_plain_text():
    rng = np.random.default_rng(7)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 40))
    radii = rng.uniform(1, 3, 40)
    vertices = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)]) * math.pi
    text = polygon_to_text(vertices, comment="random star-shaped polygon\nsecond line")
    assert text.startswith("# random star-shaped polygon\n# second line\n")
    np.testing.assert_array_equal(parse_polygon(text, "rt.txt"), vertices)


# --------------------------------------------------------- built-in shapes

def test_builtin_names_start_with_circle_then_sorted_files():
    names = builtin_shape_names()
    assert names[0] == "circle"
    assert names[1:] == sorted(names[1:])
    assert set(BUILTINS) <= set(names)


@pytest.mark.parametrize("name", BUILTINS)
def test_every_builtin_shape_is_a_simple_polygon_with_area(name):
    vertices = shape_vertices(name)
    polygon = Polygon(vertices)
    assert polygon.is_valid and polygon.area > 1.0
    assert 5 <= np.ptp(vertices, axis=0).max() <= 20
    text = (SHAPES_DIR / f"{name}.txt").read_text()
    assert text.startswith("# ")


@pytest.mark.parametrize("name", ["l-shape", "t-shape", "arrow", "crescent"])
def test_concave_builtins_are_concave(name):
    polygon = Polygon(shape_vertices(name))
    assert polygon.convex_hull.area > polygon.area * 1.05


def test_star_matches_the_paper():
    star = shape_vertices("star")
    assert star.shape == (10, 2)
    radii = np.hypot(star[:, 0], star[:, 1])
    np.testing.assert_allclose(np.sort(radii), [2.5] * 5 + [5.0] * 5, atol=1e-5)
    np.testing.assert_allclose(radii[0::2], 5.0, atol=1e-5)      # outer and inner alternate
    top = star[np.argmax(star[:, 1])]
    np.testing.assert_allclose(top, [0.0, 5.0], atol=1e-9)


def test_crescent_has_about_24_vertices():
    assert 20 <= len(shape_vertices("crescent")) <= 30


def test_circle_is_made_by_the_engine():
    assert shape_vertices("circle") is None


def test_shape_vertices_accepts_a_path(tmp_path):
    path = tmp_path / "mine.txt"
    path.write_text(polygon_to_text(SQUARE))
    np.testing.assert_array_equal(shape_vertices(str(path)), SQUARE)


def test_unknown_shape_lists_the_builtins():
    with pytest.raises(ShapeError) as info:
        shape_vertices("dodecahedron")
    message = str(info.value)
    assert "\n" not in message and "dodecahedron" in message
    assert all(name in message for name in builtin_shape_names())


def test_shapes_dir_can_be_overridden(tmp_path, monkeypatch):
    (tmp_path / "blob.txt").write_text(polygon_to_text(SQUARE))
    monkeypatch.setenv("PHOTOTAXIS_SHAPES_DIR", str(tmp_path))
    assert builtin_shape_names() == ["circle", "blob"]
    np.testing.assert_array_equal(shape_vertices("blob"), SQUARE)


# --------------------------------------------------------------- rejections

def test_non_numeric_value_names_the_line():
    message = rejects("0 0\n1 0\n# comment\n1 abc\n", "line 4", "'abc' is not a number",
                      source="star.txt")
    assert message == "star.txt, line 4: 'abc' is not a number"


@pytest.mark.parametrize("bad", ["nan", "inf", "-Infinity", "1e999"])
def test_non_finite_values_are_rejected(bad):
    rejects(f"0 0\n1 0\n{bad} 1\n", "line 3", "finite")


def test_non_finite_values_in_json_are_rejected():
    rejects("[[0, 0], [1, 0], [NaN, 1]]", "vertex 3", "finite", source="v.json")


def test_wrong_coordinate_count_names_the_line():
    rejects("0 0\n1 0 7\n1 1\n", "line 2", "expected 2 numbers", "found 3")
    rejects("0 0\n1\n1 1\n", "line 2", "found 1")


def test_fewer_than_three_distinct_vertices():
    rejects("0 0\n1 1\n0 0\n1 1\n", "2 distinct vertices")
    rejects("3 3\n", "1 distinct")


def test_self_intersection_reports_location_and_edges():
    message = rejects("0 0\n2 2\n2 0\n0 2\n", "crosses itself", "(1, 1)", "lines 1-2 and 3-4",
                      source="bowtie.txt")
    assert message.startswith("bowtie.txt: ")


def test_self_intersection_in_json_names_vertices():
    rejects("[[0,0],[2,2],[2,0],[0,2]]", "crosses itself", "vertices 1-2 and 3-4",
            source="bowtie.json")


def test_self_touching_outline_is_rejected():
    rejects("0 0\n4 0\n4 4\n2 0\n0 4\n", "touches itself", "(2, 0)")


def test_zero_area_is_rejected():
    rejects("0 0\n1 1\n2 2\n3 3\n", "zero area")
    rejects("0 0\n1 0\n1 1e-12\n", "zero area")


def test_holes_are_rejected():
    ring = "[[0,0],[10,0],[10,10],[0,10],[0,0]]"
    hole = "[[2,2],[4,2],[4,4],[2,4],[2,2]]"
    rejects(f'{{"type": "Polygon", "coordinates": [{ring}, {hole}]}}', "holes are not supported",
            source="h.geojson")
    rejects("POLYGON((0 0,10 0,10 10,0 10,0 0),(2 2,4 2,4 4,2 4,2 2))",
            "holes are not supported", source="h.wkt")
    rejects('<svg><path d="M0 0 H10 V10 H0 Z M2 2 H4 V4 H2 Z"/></svg>', "more than one subpath",
            source="h.svg")


def test_more_than_one_polygon_is_rejected():
    one = '{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [[[0,0],[1,0],[0,1],[0,0]]]}}'
    rejects(f'{{"type": "FeatureCollection", "features": [{one}, {one}]}}', "2 polygons",
            source="two.geojson")
    rejects("MULTIPOLYGON(((0 0,1 0,0 1,0 0)),((5 5,6 5,5 6,5 5)))", "2 parts", source="two.wkt")
    rejects("<svg><polygon points='0,0 1,0 0,1'/><polygon points='0,0 1,0 0,1'/></svg>",
            "2 shape elements", source="two.svg")


def test_too_many_vertices_is_rejected():
    angles = np.linspace(0, 2 * np.pi, 10_001, endpoint=False)
    text = polygon_to_text(np.column_stack([np.cos(angles), np.sin(angles)]))
    rejects(text, "10,001 vertices", "at most 10,000")


def test_empty_input_is_rejected(tmp_path):
    rejects("", "empty")
    rejects("  \n\n", "empty")
    rejects("# only a comment\n", "no vertices")
    (tmp_path / "empty.txt").write_text("")
    with pytest.raises(ShapeError, match=r"^empty.txt: is empty"):
        load_polygon(tmp_path / "empty.txt")


def test_svg_curves_and_arcs_are_flattened():
    """svgelements reads curves; they become short straight pieces of the outline."""
    curvy = parse_polygon('<svg><path d="M0 0 L10 0 C10 5 5 10 0 10 Z"/></svg>', "curvy.svg")
    assert len(curvy) > 10 and Polygon(curvy).is_valid
    arc = parse_polygon('<svg><path d="M0 0 L10 0 A5 5 0 0 1 0 10 Z"/></svg>', "arc.svg")
    assert len(arc) > 10 and Polygon(arc).area > 50


def test_svg_units_and_nested_transforms():
    svg = ('<svg xmlns="http://www.w3.org/2000/svg"><g transform="rotate(90)"><g transform="translate(1 0)">'
           '<rect x="0" y="0" width="2mm" height="1mm"/></g></g></svg>')
    vertices = parse_polygon(svg, "units.svg")
    extent = np.ptp(vertices, axis=0)
    assert extent[0] == pytest.approx(extent[1] * 2, rel=1e-6) or extent[1] == pytest.approx(extent[0] * 2, rel=1e-6)


def test_svg_entities_and_doctype_are_refused():
    svg = ('<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY a "0,0 1,0 0,1">]>'
           '<svg><polygon points="&a;"/></svg>')
    rejects(svg, "ENTITY", source="evil.svg")
    rejects('<!DOCTYPE svg><svg><polygon points="0,0 1,0 0,1"/></svg>', "DOCTYPE", source="d.svg")


def test_bad_json_wkt_and_svg_syntax():
    rejects('[[0, 0], [1, 0],\n [0, 1', "not valid JSON", "line 2", source="b.json")
    rejects("POLYGON((0 0, 1 0", "not valid WKT", source="b.wkt")
    rejects("<svg><polygon", "not valid SVG", source="b.svg")
    rejects('<svg><polygon points="0,0 1,x 0,1"/></svg>', "not a list of numbers", source="b.svg")
    rejects('[[0, 0], [1, 0], [0, "a"]]', "vertex 3", "not a number", source="b.json")
    rejects('[[0, 0], [1, 0], [0]]', "vertex 3", "expected [x, y]", source="b.json")


def test_large_file_is_rejected_without_being_parsed(tmp_path, monkeypatch):
    path = tmp_path / "huge.txt"
    path.write_text("0 0\n" * 500_000)                       # 2 MB
    monkeypatch.setattr(shapes, "parse_polygon", lambda *a, **k: pytest.fail("parsed"))
    with pytest.raises(ShapeError, match=r"^huge.txt: is 2.0 MB; .*under 1 MB$"):
        load_polygon(path)


def test_large_upload_text_is_rejected():
    rejects("0 0\n" * 500_000, "too large", source="<upload>")


def test_binary_and_non_utf8_files_are_rejected(tmp_path):
    (tmp_path / "img.txt").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00")
    with pytest.raises(ShapeError, match=r"^img.txt: .*binary"):
        load_polygon(tmp_path / "img.txt")
    (tmp_path / "latin1.txt").write_bytes("0 0\n1 0\n0 1 # caf\xe9\n".encode("latin-1"))
    with pytest.raises(ShapeError, match=r"^latin1.txt: is not UTF-8"):
        load_polygon(tmp_path / "latin1.txt")


def test_missing_file_is_rejected(tmp_path):
    with pytest.raises(ShapeError, match=r"^nope.txt: "):
        load_polygon(tmp_path / "nope.txt")
    with pytest.raises(ShapeError, match="built-in shapes are: circle"):
        shape_vertices(str(tmp_path / "nope.txt"))


def test_validate_polygon_accepts_lists_and_rejects_bad_shapes():
    np.testing.assert_array_equal(validate_polygon(SQUARE.tolist(), "list"), SQUARE)
    with pytest.raises(ShapeError, match=r"^arr: .*pairs"):
        validate_polygon(np.zeros((4, 3)), "arr")
    with pytest.raises(ShapeError, match=r"^arr, vertex 2: .*finite"):
        validate_polygon([[0, 0], [np.inf, 0], [0, 1]], "arr")


def test_repeated_vertex_names_both_occurrences():
    rejects("0 0\n1 0\n0 0\n0 1\n", "line 3", "repeats line 1", source="spike.txt")
    rejects("[[0,0],[2,0],[1,1],[2,2],[0,2],[1,1]]", "vertex 6", "repeats vertex 3",
            source="eight.json")


def test_json_nested_too_deep_is_a_one_line_error(tmp_path):
    """The JSON decoder gives up with RecursionError; the user gets a sentence."""
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ShapeError) as info:
        load_polygon(deep)
    assert str(info.value).startswith("deep.json") and "\n" not in str(info.value)


def test_coordinates_too_large_are_refused(tmp_path):
    huge = tmp_path / "huge.txt"
    huge.write_text("0 0\n1e308 0\n0 1e308\n")
    with pytest.raises(ShapeError, match=r"huge.txt, line 2: .* too large"):
        load_polygon(huge)
    rejects("[[0, 0], [1e13, 0], [0, 1]]", "vertex 2", "too large", source="big.json")


def test_a_goal_larger_than_the_construction_area_is_refused_with_what_would_fit():
    """500 boxes of 0.1624 m² are 81.2 m²: a 2:1 rectangle of that area is 12.74 x 6.37 m and fits the
    16 m area; a 25:1 one is 45.05 x 1.80 m, a third of it inside at best, and fits at (16 / 45.05)² of the
    boxes, 63. A 4.2:1 one (18.5 x 4.4 m) lies 87 % inside: refused; 3.8:1 (17.6 x 4.6 m), 91 %: built."""
    from sandbox.model.family import make_goal
    from sandbox.shapes import ShapeError

    config = Config()
    make_goal(config, np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float))
    with pytest.raises(ShapeError, match=r"the goal is 45\.1 x 1\.8 m, larger than the 16 m construction area .*"
                                         r"at most 63 boxes, or a less elongated shape"):
        make_goal(config, np.array([[0, 0], [25, 0], [25, 1], [0, 1]], float))
    with pytest.raises(ShapeError, match="is 18.5 x 4.4 m"):
        make_goal(config, np.array([[0, 0], [4.2, 0], [4.2, 1], [0, 1]], float))
    make_goal(config, np.array([[0, 0], [3.8, 0], [3.8, 1], [0, 1]], float))


def test_the_least_move_puts_a_goal_inside_the_construction_wall():
    """The construction area is 24.5..40.5 m (16 m about the assembly centre, 32.5 m). A 4 x 4 m square whose
    right edge is at 40.6 m moves 0.35 m left (a box's circumradius, 0.25 m, clear of the wall); one 15.8 m
    wide has 0.1 m on each side: it is centred between the walls."""
    from sandbox.model.goal import inside_construction

    config = Config()
    square = np.array([[36.6, 30.0], [40.6, 30.0], [40.6, 34.0], [36.6, 34.0]])
    np.testing.assert_allclose(inside_construction(config, square), [-0.35, 0.0])
    wide = np.array([[24.5, 30.0], [40.3, 30.0], [40.3, 34.0], [24.5, 34.0]])
    np.testing.assert_allclose(inside_construction(config, wide), [0.1, 0.0])
    inside = square - [5.0, 0.0]
    np.testing.assert_allclose(inside_construction(config, inside), [0.0, 0.0])
