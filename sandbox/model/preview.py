"""A goal before it is used: the polygon as the simulation will fit it (centred
and scaled to the boxes' total area) and the smallest and largest outlines
its light program will light, so a designer sees what the swarm will build
and where the band will run. Sizes come from :func:`outlines.sizing_for`,
the one place an outline family is chosen."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.model import outlines
from sandbox.model.config import Config
from sandbox.model.family import make_goal
from sandbox.model.notes import goal_fit_notes


@dataclass(frozen=True)
class GoalPreview:
    """Absolute outlines in arena coordinates (m)."""

    goal: np.ndarray
    smallest: np.ndarray
    largest: np.ndarray
    #: The fitted goal's area (m²): the boxes' total area.
    area: float
    #: What the simulation will say about the fit (the largest outline past the walls).
    notes: list[str]


def preview_goal(config: Config, vertices, flare: float) -> GoalPreview:
    """The goal ``vertices`` make under ``config`` with this flare. A goal the
    simulation would refuse (its smallest outline does not fit the arena)
    raises the same ShapeError here."""
    goal = make_goal(config, np.asarray(vertices, dtype=float))
    sizing = outlines.sizing_for(config, goal, flare)
    smallest, largest = sizing.polygon(sizing.smallest), sizing.polygon(sizing.largest)
    notes = goal_fit_notes(config, sizing, smallest, largest)
    if goal.simplified:
        notes = [f"the goal was {goal.simplified}", *notes]
    return GoalPreview(goal.outline(), smallest, largest, goal.area, notes)
