"""Measuring success (SPEC §6) on arrays of box centres."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from .controller import Goal


@dataclass(frozen=True)
class Sample:
    """Both success metrics and a few health counts at one step."""

    step: int
    fraction_in_goal: float
    mean_outside_distance: float
    boxes_escaped: int
    charged_robots: int
    cycle: int
    phase: str

    def to_dict(self) -> dict:
        return asdict(self)


#: Column names of a metrics sample, in order (CSV traces, sweeps, the app).
SAMPLE_FIELDS = [f.name for f in fields(Sample)]


def fraction_in_goal(in_goal: np.ndarray) -> float:
    """Share of boxes whose centre is inside the goal (1.0 when there are no boxes)."""
    return float(in_goal.mean()) if len(in_goal) else 1.0


def mean_outside_distance(box_positions: np.ndarray, goal: Goal, in_goal: np.ndarray) -> float:
    """Mean distance of boxes outside the goal to its nearest point (0 if none are)."""
    outside = box_positions[~in_goal]
    if len(outside) == 0:
        return 0.0
    return float(goal.distance(outside).mean())


def escaped(box_positions: np.ndarray, centre: float, construction_size: float) -> np.ndarray:
    """Boxes whose centre lies outside the construction wall, centred on
    (centre, centre) (must never happen)."""
    return np.any(np.abs(box_positions - centre) > construction_size / 2.0, axis=1)
