"""The controller of the authors' program (SPEC §9 rows 11-14, profile
authors-code), with sizes computed by hand from the program's formulas.

500 hexagons of circumradius 0.25 m cover 500 * 1.5 sqrt(3) 0.25^2 = 81.19 m^2,
the goal's area; robots are 0.5 m across.
"""

import math

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.controller import CONTRACTING, DILATING, HOLDING, Controller, first_cycle_steps
from sandbox.model.family import make_goal
from sandbox.shapes import geometry, shape_vertices

GOAL_AREA = 500 * 1.5 * math.sqrt(3) * 0.25**2
CENTRE = 32.5

# The five-point star of shapes/star.txt: outer radius 5, inner 2.5.
STAR_OUTER, STAR_INNER = 5.0, 2.5
STAR_AREA = 10 * 0.5 * STAR_OUTER * STAR_INNER * math.sin(math.radians(36))
# The star's inradius (distance from the centre to the outline, as the program's
# getDistFromPoint measures it) is its inner radius: from the centre, the foot of
# the perpendicular to the line of an edge falls beyond the edge's inner end.
STAR_INRADIUS = STAR_INNER


def program(shape="circle", **changes) -> Controller:
    cfg = Config(**changes)
    return Controller(cfg, make_goal(cfg, shape_vertices(shape)))


def lit_updates(c: Controller, updates: int) -> list[tuple[str, bool, float]]:
    """(phase, is circle, inradius) of the outline lit at each of the next updates."""
    seen = []
    for _ in range(updates * c.config.update_every):
        if c.advance():
            seen.append((c.phase, c.is_circle, inradius_of_lit_outline(c)))
    return seen


def inradius_of_lit_outline(c: Controller) -> float:
    return float(geometry.distance_to_outline(c.goal.centre[None, :], c.outline)[0])


def test_circle_sizes():
    c = program()
    radius = math.sqrt(GOAL_AREA / math.pi)  # 5.0836 m
    assert c.goal.radius == pytest.approx(radius)
    assert c.min_radius == pytest.approx(radius + 0.5)  # the program's RADMIN
    assert c.max_radius == pytest.approx(24.0)  # 0.75 of half the arena
    assert c.goal.centre.tolist() == [CENTRE, CENTRE]


def test_square_sizes():
    """Minimum: the goal square's inradius (half its side) plus a robot diameter.
    Maximum: shapes/square.txt (the authors' file: side 8, area 64) grown by 1.05
    until it covers half the arena (2048 m^2): 64 * 1.05^72 >= 2048 first at k = 36."""
    c = program("square")
    assert c.min_radius == pytest.approx(math.sqrt(GOAL_AREA) / 2 + 0.5)  # 5.005 m
    assert 64 * 1.05 ** 70 < 2048 <= 64 * 1.05 ** 72
    assert c.max_radius == pytest.approx(4 * 1.05**36)  # 23.17 m
    assert inradius_of_lit_outline(c) == pytest.approx(c.max_radius)


def test_star_sizes():
    """Minimum: the star's inradius at the goal's area plus a robot diameter.
    Maximum: grown from the file's size (tip at 5 m) until a tip reaches the
    wall, 32 m from the centre: 5 * 1.05^k >= 32 first at k = 39, so the
    largest star's tips reach past the arena, as in the program."""
    c = program("star")
    goal_inradius = STAR_INRADIUS * math.sqrt(GOAL_AREA / STAR_AREA)
    assert c.min_radius == pytest.approx(goal_inradius + 0.5)  # 4.22 m
    assert 5 * 1.05**38 < 32 <= 5 * 1.05**39
    assert STAR_AREA * 1.05 ** 78 < 2048  # the area limit is not what stops it
    assert c.max_radius == pytest.approx(STAR_INRADIUS * 1.05**39)  # 16.76 m
    tip = np.abs(c.outline - CENTRE).max()
    assert tip == pytest.approx(5 * 1.05**39) and tip > 32


def test_flared_square_is_what_is_scaled():
    """Flare 1.75 on a square: corners pushed out 1.75x (90 * 1.75 / 90), edge
    midpoints kept. With half-side a the flared outline has area 7 a^2, so at the
    goal's area a = sqrt(81.19 / 7) = 3.41 m; its inradius is a, the distance to
    the (now reflex) midpoints."""
    c = program("square", flare=1.75)
    a = math.sqrt(GOAL_AREA / 7)
    inradius = a
    assert c.min_radius == pytest.approx(inradius + 0.5)
    # The outline at its smallest: midpoints at a * s, corners at 1.75 a * s.
    s = (inradius + 0.5) / inradius
    at_min = CENTRE + s * c.shape.vertices
    rel = np.abs(at_min - CENTRE)
    assert sorted(set(np.round(rel.max(axis=1), 6))) == pytest.approx([a * s, 1.75 * a * s])
    # The midpoints (3.91 m out) fall inside the goal square (half-side 4.51 m).
    assert a * s < math.sqrt(GOAL_AREA) / 2
    # The goal itself stays the plain square.
    assert len(c.goal.vertices) == 4


def test_flare_pushes_reflex_corners_too():
    """The program's angle is the unsigned angle between a corner's edges, so an
    L-shape's reflex (270 degree) corner is pushed out like a right angle."""
    from sandbox.model.outlines import program_flare

    ell = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float) - [0.75, 0.75]
    out = program_flare(ell, 1.75)
    assert np.allclose(out[6], 1.75 * ell[3])  # the reflex corner (1, 1)
    assert np.allclose(out[7], 0.5 * (ell[3] + ell[4]))  # a midpoint, unflared


def test_program_schedule_circle():
    """Each update lights the current radius, then multiplies it by 0.975; the
    first radius below the smallest is lit for one update, then grown back by
    0.6 m (the program's delta); dilating multiplies by 2 - 0.975 = 1.025; the
    first radius above the largest is not lit."""
    c = program()
    radii = [24.0 * 0.975**k for k in range(80)]
    k_min = next(k for k, r in enumerate(radii) if r < c.min_radius)
    seen = lit_updates(c, 200)
    lit = [r for _, _, r in seen]
    # Contraction: 24 * 0.975^k, for k = 1 .. k_min (k = 0 was lit at the start).
    assert lit[: k_min] == pytest.approx(radii[1 : k_min + 1], rel=1e-3)  # outline polygon of a circle
    assert seen[k_min - 1][0] == HOLDING
    assert lit[k_min - 1] < c.min_radius
    # After the hold: grown back by 0.6 m, then by 1.025 per update.
    assert lit[k_min] == pytest.approx(radii[k_min] + 0.6, rel=1e-3)
    assert lit[k_min + 1] == pytest.approx((radii[k_min] + 0.6) * 1.025, rel=1e-3)
    assert seen[k_min][0] == DILATING
    # Turning at the top: the largest lit radius is the last below 24 m.
    top = max(lit)
    assert top <= 24.0 < top * 1.025 * (1 + 1e-3)


def test_hold_is_one_update_at_the_first_size_below_the_smallest():
    c = program("square")
    held = 0
    while c.cycle == 0:
        c.advance()
        if c.phase == HOLDING:
            held += 1
            assert inradius_of_lit_outline(c) < c.min_radius
            assert inradius_of_lit_outline(c) >= c.min_radius * 0.975 * (1 - 1e-9)
    assert held == 100  # world steps: one controller update
    assert c.phase == CONTRACTING


def test_switch_to_circle_while_dilating_only():
    """Star + switch: the first contraction is the star; while dilating, once the
    star's inradius passes 8 m (0.25 x half the arena) a circle of that radius
    is lit; it grows to 24 m, contracts, and below 8 m the frozen star returns."""
    c = program("star", switch=0.25)
    seen = lit_updates(c, 400)
    phases = [p for p, _, _ in seen]
    first_dilation = phases.index(DILATING)
    assert not any(circle for _, circle, _ in seen[:first_dilation])  # the first contraction is the star
    switch_at = next(i for i, (_, circle, _) in enumerate(seen) if circle)
    last_star, first_circle = seen[switch_at - 1][2], seen[switch_at][2]
    assert seen[switch_at][0] == DILATING
    assert last_star <= 8.0 < first_circle
    # The circle has the inradius of the star it replaces (the star went one more step).
    assert first_circle == pytest.approx(last_star * 1.025, rel=1e-3)
    circle_radii = [r for _, circle, r in seen[switch_at:] if circle]
    assert max(circle_radii) <= 24.0 + 1e-6
    back = next(i for i in range(switch_at, len(seen)) if not seen[i][1])
    assert seen[back][0] == CONTRACTING
    assert seen[back - 1][2] >= 8.0 > seen[back - 1][2] * 0.975 * (1 - 1e-3)
    assert seen[back][2] == pytest.approx(first_circle, rel=1e-3)  # the frozen star


def test_no_switch_for_a_circle_goal():
    c = program(switch=0.25)
    assert not any(c.circle_radius is not None for _ in range(20000) if c.advance() or True)


def test_no_corners_uses_the_flared_outline_vertices():
    """With the program's flare the square's edge midpoints become reflex, so
    no-corners darkens the lights near the four flared tips only."""
    c = program("square", flare=1.75, no_corners=0.5)
    assert len(c.corners) == 4
    assert np.allclose(np.abs(c.corners - CENTRE), np.abs(c.corners - CENTRE)[0])


def test_no_corners_count_is_at_least_the_fraction():
    """The program turns lights off while (turned off) / lit < c: for 161 lit
    lights and c = 0.5 that is 81, where rounding gives 80 (round half to even)."""
    from sandbox.model.band import no_corners_count

    assert no_corners_count(0.5, 161, "at-least") == 81
    assert no_corners_count(0.5, 161, "round") == 80
    assert no_corners_count(0.5, 160, "at-least") == 80
    assert no_corners_count(0.25, 10, "at-least") == 3
    assert no_corners_count(1.0, 10, "at-least") == 10


def test_first_cycle_length_of_the_circle():
    """58 updates down from 24 m by x0.975 to the first radius below the smallest
    (goal radius + 0.5 m); 56 lit radii on the way back up (+0.6 m, then x1.025,
    while at most 24 m); the 115th update finds the radius above 24 m and starts
    cycle 1. 115 updates of 100 steps."""
    cfg = Config()
    c = program()
    radius, down = 24.0, 0
    while radius >= c.min_radius:
        radius, down = radius * 0.975, down + 1
    radius, up = radius + 0.6, 0
    while radius <= 24.0:
        radius, up = radius * 1.025, up + 1
    assert (down, up) == (58, 56)
    assert first_cycle_steps(cfg, shape_vertices("circle")) == (down + up + 1) * 100 == 11_500


def test_a_strategy_that_would_change_nothing_says_so():
    from sandbox.model.notes import strategy_effect_note

    square, star = shape_vertices("square"), shape_vertices("star")
    # 90 x 1.0 = 90 is not above the square's 90-degree corners; 90 x 1.1 = 99 is.
    assert "sharpest corner is 90 degrees (flare acts above 1.00)" in strategy_effect_note("flare", 1.0, square)
    assert strategy_effect_note("flare", 1.1, square) == ""
    # The star's tips: the inner vertices sit at 2.5 m, 36 degrees either side of a 5 m tip, so half the
    # tip angle is atan(2.5 sin 36 / (5 - 2.5 cos 36)) = 26.27 degrees: tips of 52.5 degrees, flare from 0.58.
    assert strategy_effect_note("flare", 0.6, star) == ""
    assert "sharpest corner is 53 degrees (flare acts above 0.58)" in strategy_effect_note("flare", 0.57, star)
    assert "circle goal" in strategy_effect_note("switch", 0.25, None)
    assert strategy_effect_note("switch", 0.25, star) == "" and strategy_effect_note("flare", 0.0, square) == ""
    assert "flare changes only the largest size" in strategy_effect_note("flare", 1.75, square, chase=2.0)
