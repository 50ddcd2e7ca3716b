"""What chase makes of the boxes it sees: how many are in the goal, how many
out of the robots' reach, and how far out a dilation must go to fetch them."""

from __future__ import annotations

import numpy as np

from sandbox.model.controller import Cycle
from sandbox.model.goal import Goal


def boxes_in_goal(goal: Goal, boxes: np.ndarray) -> int:
    return int(goal.contains(boxes).sum())


def boxes_out_of_reach(goal: Goal, boxes: np.ndarray, robot_radius: float) -> int:
    """Boxes beyond the reach of robots on the smallest outline (one robot
    diameter from the goal): farther than three robot radii from it."""
    return int((goal.distance(boxes) > 3.0 * robot_radius).sum())


def turn_radius(cycle: Cycle, seen) -> float:
    """The inradius (radius for a circle) at which the cycle's dilation turns,
    having ``seen`` the boxes (an observation, or None): as soon as the outline
    is ``chase`` metres beyond the farthest box outside the goal, and at least
    ``chase`` metres beyond the smallest outline, so the robots always back off
    and push again; never past the largest."""
    largest = cycle.max_radius
    margin = cycle.strategies["chase"]
    if margin <= 0 or seen is None:
        return largest
    boxes = seen.box_positions
    goal = cycle.goal
    stray = boxes[~goal.contains(boxes)]
    if not len(stray):
        need = 0.0
    elif cycle.circle_radius is not None or goal.is_circle:
        need = float(np.hypot(*(stray - goal.centre).T).max()) + margin
    else:  # the outline is the goal grown (see ChaseController._redraw_sculpted)
        need = cycle.sizing.radius_beyond(float(goal.distance(stray).max())) + margin
    return min(largest, max(need, cycle.min_radius + margin))
