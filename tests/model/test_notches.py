"""A goal's notches and the lights that hold them clear (sandbox/model/notches.py, issue 42), on values
computed by hand."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sandbox.model import notches
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.family import make_goal, settle
from sandbox.model.goal import Goal
from sandbox.model.offset import OffsetSizing, signed_distance
from sandbox.shapes import shape_vertices

#: A U: the square [0, 6]^2 less the notch [2, 4] x [2, 6], 2 m wide (under the closing's 3 m) and 4 m deep.
U_VERTICES = np.array([[0, 0], [6, 0], [6, 6], [4, 6], [4, 2], [2, 2], [2, 6], [0, 6]], dtype=float)
U_GOAL = Goal(np.array([3.0, 3.0]), 28.0, U_VERTICES)
#: Lights one metre apart at the half metres, over [-3, 9]^2.
LIGHTS = np.stack(np.meshgrid(np.arange(-2.5, 9.0), np.arange(-2.5, 9.0), indexing="ij"), axis=-1).reshape(-1, 2)
#: The eight lights inside the notch: x 2.5 or 3.5, y 2.5 .. 5.5, each 0.5 from a wall or the floor.
IN_NOTCH = {(x, y) for x in (2.5, 3.5) for y in (2.5, 3.5, 4.5, 5.5)}
ROOT = Path(__file__).resolve().parents[2]
SHAPES = ROOT / "shapes"
#: The letter H of the notched set, as its file draws it.
LETTER_H = shape_vertices(str(ROOT / "static" / "shapes" / "notched" / "shapes" / "letter-H.txt"))


def lit_set(on: np.ndarray) -> set[tuple[float, float]]:
    return {(float(x), float(y)) for x, y in LIGHTS[on]}


def u_sizing(notched: bool = True) -> OffsetSizing:
    found = tuple(notches.notch_polygons(U_VERTICES)) if notched else ()
    return OffsetSizing(U_GOAL, 0.5, 12.0, 8.0, math.sqrt(28.0 / math.pi), 24.0, found,
                        notches.PACE if notched else 1.0, notches.SLOW_WITHIN)


def test_the_notch_of_a_u_is_its_gap():
    (notch,) = notches.notch_polygons(U_VERTICES)
    # 2 m x 4 m, less the mouth's dip: the closing's disc above the mouth touches the corners (2, 6) and
    # (4, 6), its centre 1.118 m above them, and cuts the segment 2.25 acos(1.118 / 1.5) - 1.118 = 0.524.
    assert notch.area == pytest.approx(8.0 - 0.524, abs=0.02)
    assert notch.bounds == pytest.approx((2.0, 2.0, 4.0, 6.0), abs=0.01)


def test_gaps_wider_than_the_closing_and_convex_goals_have_no_notch():
    wide = U_VERTICES * [2.0, 1.0]  # the gap 4 m wide: over twice the closing radius
    assert notches.notch_polygons(wide) == []
    assert notches.notch_polygons(np.array([[0, 0], [4, 0], [4, 4], [0, 4]], dtype=float)) == []


def test_a_notchs_lights_are_lit_below_its_deepest_light_plus_the_reach():
    reach = notches.notch_reach(LIGHTS, notches.notch_polygons(U_VERTICES), signed_distance(LIGHTS, U_GOAL))
    assert lit_set(np.isfinite(reach)) == IN_NOTCH
    # Every light of the notch is 0.5 m from the goal: its deepest is 0.5, so each lights at 0.5 + 2.0.
    assert reach[np.isfinite(reach)] == pytest.approx(np.full(8, 0.5 + notches.REACH))


def test_the_notch_is_lit_while_the_band_closes_in_and_dark_while_it_dilates():
    sizing = u_sizing()
    contracting = lit_set(sizing.lit(LIGHTS, 2.0, 0.5))
    assert IN_NOTCH <= contracting
    # The band itself at 2.0 lights nothing in the notch (its lights are 0.5 from the goal) ...
    assert not IN_NOTCH & lit_set(sizing.lit(LIGHTS, 2.0, 0.5, dilating=True))
    # ... nor does the notch light beyond its reach, 2.5.
    assert not IN_NOTCH & lit_set(sizing.lit(LIGHTS, 3.0, 0.5))
    # Without notches the band at 2.0 is the plain one: the lights 1.5 to 2.5 from the goal.
    plain = lit_set(u_sizing(notched=False).lit(LIGHTS, 2.0, 0.5))
    assert plain == contracting - IN_NOTCH
    assert plain == lit_set(np.abs(signed_distance(LIGHTS, U_GOAL) - 2.0) <= 0.5 + 1e-9)


def test_a_notched_goals_band_moves_at_its_pace_near_the_goal():
    r = math.sqrt(28.0 / math.pi)
    # 0.975 per update becomes 0.975^0.397 = 0.98999...: about 0.99.
    assert 0.975**notches.PACE == pytest.approx(0.99, abs=1e-4)
    # ... within 1.5 + 2.0 = 3.5 m of the goal (the farthest a notch's light can be lit), both ways:
    assert notches.SLOW_WITHIN == 3.5
    assert u_sizing().step(3.5, 0.975) == pytest.approx((3.5 + r) * 0.975**notches.PACE - r)
    assert u_sizing().step(2.0, 1.025) == pytest.approx((2.0 + r) * 1.025**notches.PACE - r)
    assert u_sizing().step_back(3.0, 0.975) == pytest.approx((3.0 + r) / 0.975**notches.PACE - r)
    # ... and at the paper's pace farther out, and on a goal without notches.
    assert u_sizing().step(3.6, 0.975) == pytest.approx((3.6 + r) * 0.975 - r)
    assert u_sizing().step_back(5.0, 0.975) == pytest.approx((5.0 + r) / 0.975 - r)
    assert u_sizing(notched=False).step(2.0, 0.975) == pytest.approx((2.0 + r) * 0.975 - r)


def test_the_default_lights_a_notched_goals_notches_and_says_so():
    # The letter H at the boxes' area: its two notches are 2.5 m wide.
    cfg = Config()
    goal = make_goal(cfg, LETTER_H)
    sizing = OffsetSizing.of(cfg, goal)
    assert len(sizing.notches) == 2 and sizing.pace == notches.PACE and sizing.slow_within == 3.5
    assert sizing.pace_at(3.5) == notches.PACE and sizing.pace_at(3.51) == 1.0
    assert "The goal has 2 notches (gaps narrower than 3 m)" in goal.family_reason
    plain_cfg = Config(notches="plain")
    plain = make_goal(plain_cfg, LETTER_H)
    assert OffsetSizing.of(plain_cfg, plain).notches == () and OffsetSizing.of(plain_cfg, plain).pace == 1.0
    assert "notch" not in plain.family_reason
    assert settle(plain_cfg, plain).family_reason == plain.family_reason


@pytest.mark.parametrize("name", sorted(p.stem for p in SHAPES.glob("*.txt")))
def test_no_shape_in_shapes_has_a_notch_so_their_default_is_as_before(name):
    """The shapes in shapes/ (and the paper's) have no gap under 3 m: `notches` changes none of them."""
    goal = make_goal(Config(), shape_vertices(name))
    assert notches.notch_polygons(goal.vertices) == []


def test_chase_lights_its_own_band_at_the_papers_pace_and_no_notch():
    chasing = Config(chase=2.0)
    goal = make_goal(chasing, LETTER_H)
    sizing = OffsetSizing.of(chasing, goal, chase=2.0)
    assert sizing.notches == () and sizing.pace == 1.0
    assert "notch" not in goal.family_reason


def test_turning_chase_on_and_off_live_drops_and_restores_the_notches():
    controller = Controller(Config(), make_goal(Config(), LETTER_H))
    assert controller.sizing.pace == notches.PACE
    for chase, pace in ((2.0, 1.0), (0.0, notches.PACE)):
        controller.set_strategies(chase=chase)
        while controller.state.pending:  # taken at the next controller update
            controller.advance()
        assert controller.sizing.pace == pace and bool(controller.sizing.notches) == (pace != 1.0)
