"""Where a notched goal's band holds farther out, beside its thin parts and tips (sandbox/model/thin.py,
issue 42), on values computed by hand."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sandbox.model import thin
from sandbox.model.config import Config
from sandbox.model.family import make_goal, settle
from sandbox.model.lights import light_centres
from sandbox.model.offset import OffsetSizing
from sandbox.shapes import geometry, shape_vertices

ROOT = Path(__file__).resolve().parents[2]
W_FILE = str(ROOT / "static" / "shapes" / "notched" / "shapes" / "W.txt")
#: The default lights: 1 m apart, 2 m up, B = I / d^2 with the authors' program's angle factor.
GLOW = thin.Glow.of(Config())


def line_by_hand(offset: float, glow: thin.Glow = GLOW) -> float:
    """A line of 41 lights one pitch apart, at ``offset``: the program's kernel written out term by term,
    d^-k h / sqrt(h^2 + dx^4 + dy^4)."""
    total = 0.0
    for i in range(-20, 21):
        dx, dy, h = offset, i * glow.pitch, glow.height
        d = math.sqrt(dx * dx + dy * dy + h * h)
        total += d ** -glow.falloff * h / math.sqrt(h * h + dx ** 4 + dy ** 4)
    return total


def test_a_strip_lit_on_both_sides_is_brighter_on_its_axis_when_thin():
    # A stroke of the W, 1.43 m wide, with the band 0.5 m away on both sides: its axis is 1.2 m from each
    # line, the far line 2.4 m from the near one.
    by_hand = 2 * line_by_hand(1.215) / (line_by_hand(0.0) + line_by_hand(2.43))
    assert thin.axis_over_band(GLOW, 1.43, 0.5) == pytest.approx(by_hand)
    assert by_hand > 1.0  # brighter than the band: the robots ride onto the stroke
    # A part 3 m wide at the same distance is dim on its axis: the band stays the brightest line.
    assert thin.axis_over_band(GLOW, 3.0, 0.5) == pytest.approx(
        2 * line_by_hand(2.0) / (line_by_hand(0.0) + line_by_hand(4.0)))
    assert thin.axis_over_band(GLOW, 3.0, 0.5) < thin.AXIS_RATIO


def test_the_band_holds_where_the_axis_falls_to_the_ratio():
    # A part 1.4 m wide: 0.861 of the band at 0.90 m, 0.828 at 0.95 m, so the band holds at 0.95 m; 1.5 m
    # wide, at 0.90 m. Between the table's widths (every 0.1 m) the distance is interpolated.
    assert thin.axis_over_band(GLOW, 1.4, 0.90) > thin.AXIS_RATIO >= thin.axis_over_band(GLOW, 1.4, 0.95)
    assert thin.axis_over_band(GLOW, 1.5, 0.85) > thin.AXIS_RATIO >= thin.axis_over_band(GLOW, 1.5, 0.90)
    assert thin.least_distance(GLOW, np.array([1.4, 1.5, 1.43]), 0.5) == pytest.approx([0.95, 0.90, 0.935])
    # Wide parts: the smallest distance, one robot diameter, as the band without notches.
    assert thin.least_distance(GLOW, np.array([2.5, 3.0, 8.0]), 0.5) == pytest.approx([0.5, 0.5, 0.5])
    # The thinner, the farther out.
    least = thin.least_distance(GLOW, np.array([0.0, 0.5, 1.0, 1.43, 2.0]), 0.5)
    assert np.all(np.diff(least) <= 0) and least[0] > least[-2]


def test_the_local_width_is_twice_the_deepest_point_within_a_metre():
    long_strip = np.array([[0, 0], [10, 0], [10, 2], [0, 2]], dtype=float)
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], dtype=float)
    # The middle of the strip's long side: its axis, 1 m deep, is within 1 m.
    assert thin.local_widths(np.array([[5.0, 0.0]]), long_strip)[0] == pytest.approx(2.0, abs=0.1)
    # A square's side: the deepest point within 1 m is 1 m in, so 2 m, whatever the square's size.
    assert thin.local_widths(np.array([[5.0, 0.0]]), square)[0] == pytest.approx(2.0, abs=0.1)
    # Its corner: 1 m along the diagonal, 1 / sqrt(2) deep. A corner lit from two sides counts as thin.
    assert thin.local_widths(np.array([[0.0, 0.0]]), square)[0] == pytest.approx(math.sqrt(2.0), abs=0.1)


def test_the_nearest_edge_point_by_projection_agrees_with_geos():
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], dtype=float)
    points = np.array([[5.0, -2.0], [12.0, 12.0], [-1.0, 4.0], [5.0, 10.5]])
    # Below the bottom edge, beyond the top right corner, left of the left edge, above the top edge.
    expected = np.array([[5.0, 0.0], [10.0, 10.0], [0.0, 4.0], [5.0, 10.0]])
    assert geometry.nearest_on_outline(points, square) == pytest.approx(expected)
    assert thin.nearest_edge_points(points, square) == pytest.approx(expected)


def w_sizing(notches: str) -> tuple[OffsetSizing, np.ndarray]:
    config = Config(shape=W_FILE, notches=notches)
    goal = settle(config, make_goal(config, shape_vertices(W_FILE)))
    return OffsetSizing.of(config, goal), light_centres(config).reshape(-1, 2)


def test_the_ws_band_holds_out_beside_its_tips_at_the_press():
    sizing, centres = w_sizing("lit")
    plain, _ = w_sizing("plain")
    assert sizing.glow == GLOW and plain.glow is None
    at_press = sizing.lit(centres, sizing.smallest, 0.5)
    _, distances, reach, least, _ = sizing._distances["centres"]
    near = (distances > 0) & (distances < 4)
    # Measured within 1 m, no part looks wider than 2 m: the band stops 0.65 m from the goal or farther.
    assert least[near].min() == pytest.approx(0.65, abs=0.01) and np.all(least[~near] == sizing.smallest)
    # The top middle apex, an acute tip: the light above it, 0.42 m from the goal, holds the band at 1.35 m.
    above_apex = np.flatnonzero(np.all(np.isclose(centres, [32.5, 38.5]), axis=1))[0]
    assert distances[above_apex] == pytest.approx(0.42, abs=0.01) and least[above_apex] == pytest.approx(1.35, abs=0.01)
    # The plain band lights it at the press; held out, it is dark (not in a notch).
    assert plain.lit(centres, plain.smallest, 0.5)[above_apex] and reach[above_apex] == -np.inf
    assert not at_press[above_apex]
    # Every light at its own least distance (within the band's half width) is lit at the press instead.
    held = near & (np.abs(distances - least) <= 0.5)
    assert at_press[held].all()
    # Above its least distance the band is as before.
    assert np.array_equal(sizing.lit(centres, 2.0, 0.5), plain.lit(centres, 2.0, 0.5) | (2.0 <= reach))


def test_a_goal_without_notches_comes_to_the_smallest_distance_all_round():
    config = Config(shape="l-shape")
    goal = settle(config, make_goal(config, shape_vertices("l-shape")))
    sizing = OffsetSizing.of(config, goal)
    assert sizing.glow is None and not sizing.notches
    centres = light_centres(config).reshape(-1, 2)
    sizing.lit(centres, sizing.smallest, 0.5)
    assert sizing._distances["centres"][3] is None
