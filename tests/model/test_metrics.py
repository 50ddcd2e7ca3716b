"""Success metrics (SPEC §6) on hand-placed boxes."""

import numpy as np
import pytest

from sandbox.model import metrics
from sandbox.model.config import Config
from sandbox.model.family import make_goal


def square_goal():
    cfg = Config(profile="paper-text", boxes=100)  # total area 100 * 0.2165 = 21.65 m^2
    side = np.sqrt(cfg.boxes * cfg.box_area)
    goal = make_goal(cfg, np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float))
    return goal, side


def test_fraction_and_distance_by_hand():
    goal, side = square_goal()
    h = side / 2
    boxes = np.array([
        [32, 32],             # centre: inside
        [32 + h - 0.01, 32],  # just inside
        [32 + h + 1.0, 32],   # 1 m right of the edge
        [32, 32 - h - 2.0],   # 2 m below
        [32 + h + 3, 32 + h + 4],  # 5 m from the corner
    ], dtype=float)
    inside = goal.contains(boxes)
    assert inside.tolist() == [True, True, False, False, False]
    assert metrics.fraction_in_goal(inside) == pytest.approx(0.4)
    assert metrics.mean_outside_distance(boxes, goal, inside) == pytest.approx((1 + 2 + 5) / 3)


def test_all_inside_gives_zero_distance():
    goal, _ = square_goal()
    boxes = np.full((5, 2), 32.0)
    inside = goal.contains(boxes)
    assert metrics.fraction_in_goal(inside) == 1.0
    assert metrics.mean_outside_distance(boxes, goal, inside) == 0.0


def test_circle_goal_distance():
    cfg = Config(boxes=100)  # the authors' program: centred on the light at (32.5, 32.5)
    goal = make_goal(cfg, None)
    c = 32.5
    # 100 hexagons of circumradius 0.25: 100 * 1.5 sqrt(3) 0.25^2 = 16.238 m^2, radius sqrt(16.238 / pi).
    assert goal.radius == pytest.approx(np.sqrt(100 * 1.5 * np.sqrt(3) * 0.0625 / np.pi))
    boxes = np.array([[c + goal.radius + 2.0, c], [c, c]])
    inside = goal.contains(boxes)
    assert inside.tolist() == [False, True]
    assert metrics.mean_outside_distance(boxes, goal, inside) == pytest.approx(2.0)


def test_escaped_boxes():
    boxes = np.array([[32.0, 32.0], [40.5, 32.0], [23.0, 23.0]])
    assert metrics.escaped(boxes, 32.0, 16.0).tolist() == [False, True, True]
