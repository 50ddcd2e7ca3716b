"""The offset outline family (sandbox/model/offset.py) and the choice of family
(sandbox/model/family.py), on values computed by hand. (The distance tests
were first written for the prototype light program of the offset outline.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.family import DEEP_INSIDE, centre_depth, choose, make_goal
from sandbox.model.goal import Goal, fit_goal
from sandbox.model.lights import light_centres
from sandbox.model.offset import OffsetSizing, covering_distance, signed_distance, wall_distance
from sandbox.model.phases import CONTRACTING, DILATING, HOLDING
from sandbox.model.simulation import Simulation
from sandbox.shapes import shape_vertices

#: The square [9, 11] x [9, 11], centre (10, 10).
SQUARE = Goal(np.array([10.0, 10.0]), 4.0, np.array([[9.0, 9.0], [11.0, 9.0], [11.0, 11.0], [9.0, 11.0]]))
#: An L: [0, 4] x [0, 1] and [0, 1] x [0, 4]; its inner (reflex) corner is (1, 1).
L_SHAPE = Goal(np.array([1.5, 1.5]), 7.0,
               np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0], [1.0, 4.0], [0.0, 4.0]]))
#: The circle of radius 2 about (5, 5).
CIRCLE = Goal(np.array([5.0, 5.0]), math.pi * 4.0, None)


# -- the distance field ---------------------------------------------------------------------------
def test_signed_distance_to_a_square_goal():
    points = np.array([[13.0, 10.0], [13.0, 13.0], [10.0, 10.0], [10.5, 10.0], [11.0, 10.2], [8.0, 10.0]])
    assert signed_distance(points, SQUARE) == pytest.approx([2.0, math.sqrt(8.0), -1.0, -0.5, 0.0, 1.0])


def test_signed_distance_in_an_l_notch_is_the_distance_to_the_nearer_arm():
    points = np.array([[2.0, 2.0], [1.5, 1.5], [3.0, 3.0], [3.0, 1.5], [5.0, 2.0], [0.5, 0.5]])
    assert signed_distance(points, L_SHAPE) == pytest.approx([1.0, 0.5, 2.0, 0.5, math.sqrt(2.0), -0.5])


def test_signed_distance_to_a_circle_goal_is_exact():
    points = np.array([[10.0, 5.0], [5.0, 5.0], [5.0 + 3.0 / math.sqrt(2), 5.0 + 3.0 / math.sqrt(2)]])
    assert signed_distance(points, CIRCLE) == pytest.approx([3.0, -2.0, 1.0])


def test_covering_distance_of_a_square_goal_is_its_distance_to_the_far_corner():
    # The square of half-side 3 about (10, 10): its corner (13, 13) is sqrt(8) from the goal's (11, 11).
    assert covering_distance(SQUARE, np.array([10.0, 10.0]), 3.0) == pytest.approx(math.sqrt(8.0))
    assert covering_distance(SQUARE, np.array([10.0, 10.0]), 0.5) == 0.0  # inside the goal


def test_wall_distance_is_the_room_to_the_nearest_wall_less_the_clearance():
    assert wall_distance(SQUARE, 20.0, 1.0) == pytest.approx(8.0)  # 9 m to the walls at 0 and 20
    shifted = Goal(np.array([6.0, 10.0]), 4.0, SQUARE.vertices - [4.0, 0.0])  # [5, 7] x [9, 11]
    assert wall_distance(shifted, 20.0, 1.0) == pytest.approx(4.0)
    assert wall_distance(CIRCLE, 20.0, 0.5) == pytest.approx(2.5)  # the circle reaches 3 from the wall


# -- the family's sizes and band --------------------------------------------------------------------
def test_the_band_follows_an_l_into_its_inner_corner():
    g = np.arange(-3.5, 8.0, 1.0)
    gx, gy = np.meshgrid(g, g, indexing="ij")
    centres = np.stack([gx.ravel(), gy.ravel()], axis=-1)
    sizing = OffsetSizing(L_SHAPE, 0.5, 5.0, 3.0, math.sqrt(7.0 / math.pi), 24.0)
    lit = {(float(x), float(y)) for x, y in centres[sizing.lit(centres, 1.0, 0.5)]}
    assert {(1.5, 1.5), (2.5, 1.5), (2.5, 2.5)} <= lit  # distances 0.5, 0.5 and 1.5 in the notch
    assert (3.5, 3.5) not in lit and (0.5, 0.5) not in lit  # 2.5 out; inside the L


def test_a_circle_goals_band_is_the_papers_ring_at_radius_r_plus_d():
    cfg = Config(outline="offset")
    goal = make_goal(cfg, None)
    sizing = OffsetSizing.of(cfg, goal)
    centres = light_centres(cfg).reshape(-1, 2)
    ring = np.abs(np.hypot(*(centres - goal.centre).T) - (goal.radius + 3.3)) <= cfg.band + 1e-9
    assert (sizing.lit(centres, 3.3, cfg.band) == ring).all()


def test_the_sizes_of_the_default_circle():
    cfg = Config(outline="offset")
    goal = make_goal(cfg, None)
    sizing = OffsetSizing.of(cfg, goal)
    assert sizing.smallest == pytest.approx(0.5)  # one robot diameter
    # The spawn square's corner is 16 sqrt(2) from the centre: the first contraction starts a pitch beyond.
    assert sizing.largest == pytest.approx(16.0 * math.sqrt(2.0) - goal.radius + 1.0)
    # Dilations turn a pitch beyond the construction area's corner, 8 sqrt(2) from the centre.
    assert sizing.turn == pytest.approx(8.0 * math.sqrt(2.0) - goal.radius + 1.0)


def test_a_size_steps_as_the_papers_ring_does():
    sizing = OffsetSizing(SQUARE, 0.5, 20.0, 10.0, 5.0, 24.0)
    assert sizing.step(15.0, 0.975) == pytest.approx(20.0 * 0.975 - 5.0)
    assert sizing.step_back(15.0, 0.975) == pytest.approx(20.0 / 0.975 - 5.0)
    assert sizing.radius(15.0) == sizing.radius_beyond(15.0) == pytest.approx(20.0)
    assert sizing.distance(15.0) == 15.0 and sizing.widen(15.0, 0.6) == pytest.approx(15.6)
    grown = sizing.polygon(1.0)  # the square [8, 12]^2 with rounded corners
    assert grown[:, 0].min() == pytest.approx(8.0) and grown[:, 1].max() == pytest.approx(12.0)


def test_the_controller_contracts_holds_and_turns_at_the_construction_area():
    cfg = Config(outline="offset", size_schedule="clamped", hold_steps=100)
    goal = make_goal(cfg, shape_vertices("l-shape"))
    ctrl = Controller(cfg, goal)
    sizing, seen = ctrl.sizing, []
    assert ctrl.scale == pytest.approx(sizing.largest) and sizing.turn < sizing.largest
    for _ in range(60_000):
        ctrl.advance()
        seen.append((ctrl.phase, ctrl.scale))
        if ctrl.cycle == 2:
            break
    holds = [scale for phase, scale in seen if phase == HOLDING]
    assert holds and min(holds) == pytest.approx(sizing.smallest)
    first_hold = next(i for i, (phase, _) in enumerate(seen) if phase == HOLDING)
    assert any(phase == DILATING for phase, _ in seen[first_hold:])
    widest = max(scale for _, scale in seen[first_hold:])
    assert widest == pytest.approx(sizing.turn)  # never back out to the spawn square
    assert seen[-1][0] == CONTRACTING


def test_the_lit_band_stays_within_its_width_of_d():
    cfg = Config(robots=12, boxes=20, update_every=10, hold_steps=10, shape="l-shape", size_schedule="clamped")
    sim = Simulation(cfg)
    assert sim.goal.family == "offset"
    sim.step(300)
    lit = sim.light_intensities.reshape(-1) > 0
    distance = signed_distance(light_centres(cfg).reshape(-1, 2)[lit], sim.goal)
    assert lit.any() and np.abs(distance - sim.controller.scale).max() <= cfg.band + 1e-9


# -- which family --------------------------------------------------------------------------------
def test_the_centres_depth_in_a_square_and_an_l():
    """The square [9, 11]^2 about its centre: 1 to the edge, sqrt(2) to a corner. The L's centroid
    (1.5, 1.5)... lies in its notch, outside it: depth 0."""
    assert centre_depth(SQUARE) == pytest.approx(1.0 / math.sqrt(2.0))
    assert centre_depth(L_SHAPE) == 0.0 and centre_depth(CIRCLE) == 1.0


@pytest.mark.parametrize("shape, family", [
    ("circle", "scaled"), ("square", "scaled"), ("star", "scaled"), ("triangle", "scaled"), ("house", "scaled"),
    ("rectangle", "scaled"), ("l-shape", "offset"), ("crescent", "offset"), ("t-shape", "offset"),
    ("arrow", "offset")])
def test_auto_takes_scaled_where_the_centre_lies_deep_inside(shape, family):
    goal = make_goal(Config(), shape_vertices(shape))
    assert goal.family == family
    assert (centre_depth(goal) >= DEEP_INSIDE) == (family == "scaled")


def test_an_explicit_choice_wins_and_scaled_that_cannot_fit_falls_back_to_offset():
    crescent = shape_vertices("crescent")
    assert make_goal(Config(outline="offset"), shape_vertices("square")).family == "offset"
    assert make_goal(Config(outline="scaled"), shape_vertices("l-shape")).family == "scaled"
    family, why = choose(Config(outline="scaled"), fit_goal(Config(), crescent))
    assert family == "offset" and why.startswith("scaled was asked for, but its smallest outline would span")


def test_an_offset_goal_is_moved_inside_the_wall_and_says_so():
    goal = make_goal(Config(), shape_vertices("crescent"))
    assert goal.moved[0] < 0 and goal.vertices[:, 0].max() <= 40.5 - 0.25 + 1e-9  # the wall at 40.5
    notes = Simulation(Config(robots=12, boxes=500, shape="crescent")).controller.notes
    assert any("outline: offset" in n for n in notes) and any("was moved 0.46 m left" in n for n in notes)
