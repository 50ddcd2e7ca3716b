"""What the model tells the user before a run: the outline a goal takes and
why, a goal that does not fit the arena or reaches past the wall that stops
boxes, and a strategy that will change nothing on a goal."""

from __future__ import annotations

import numpy as np

from sandbox.model import outlines
from sandbox.model.budget import MAX_GOAL_VERTICES
from sandbox.model.config import STRATEGIES, Config
from sandbox.model.goal import Goal
from sandbox.model.outlines import Sizing
from sandbox.shapes import geometry
from sandbox.shapes.errors import ShapeError

STRATEGY_LABELS = {s.name: s.label for s in STRATEGIES}


def goal_notes(config: Config, goal: Goal, sizing: Sizing) -> list[str]:
    """What to say about a goal before it runs (see :func:`goal_fit_notes`), its outline family
    first when it is not the paper's: which one, why, and where the goal was moved. A goal simplified to
    what the outlines afford says so before all."""
    notes = [f"the goal was {goal.simplified} (the outlines afford {MAX_GOAL_VERTICES:,})"] if goal.simplified else []
    if goal.family == "offset":
        notes.append(f"the band follows the goal's edge at a distance (outline: offset): {goal.family_reason}")
    if any(goal.moved):
        dx, dy = goal.moved
        notes.append(f"the goal was moved {_shift_words(dx, dy)} so that it lies inside the wall that stops the "
                     f"boxes")
    past = past_construction(config, goal)
    if past:
        notes.append(f"part of the goal lies past the wall that stops the boxes ({past}): boxes cannot fill it "
                     f"(outline = offset moves such a goal inside)")
    return notes + goal_fit_notes(config, sizing)


def past_construction(config: Config, goal: Goal) -> str:
    """How far the goal reaches past the construction wall, in words ('' when it does not)."""
    if goal.vertices is None:
        return ""
    low_wall = config.centre - config.construction_size / 2.0
    high_wall = config.centre + config.construction_size / 2.0
    (x0, y0), (x1, y1) = goal.vertices.min(axis=0), goal.vertices.max(axis=0)
    sides = {"left": low_wall - x0, "right": x1 - high_wall, "bottom": low_wall - y0, "top": y1 - high_wall}
    over = [f"{amount:.2f} m at the {side}" for side, amount in sides.items() if amount > 1e-6]
    return ", ".join(over)


def _shift_words(dx: float, dy: float) -> str:
    parts = []
    if abs(dx) > 1e-6:
        parts.append(f"{abs(dx):.2f} m {'right' if dx > 0 else 'left'}")
    if abs(dy) > 1e-6:
        parts.append(f"{abs(dy):.2f} m {'up' if dy > 0 else 'down'}")
    return " and ".join(parts)


def goal_fit_notes(config: Config, sizing: Sizing, smallest: np.ndarray | None = None,
                   largest: np.ndarray | None = None) -> list[str]:
    """Refuse a goal whose smallest outline does not fit the arena (ShapeError);
    return a note when only its largest does not. ``smallest`` and ``largest``: the
    outlines, if the caller has them already (growing a goal of many vertices costs)."""
    box = outlines.overreach(config, sizing.polygon(sizing.smallest) if smallest is None else smallest)
    if box is not None:
        raise ShapeError(f"the goal does not fit the arena: its smallest outline spans {outlines.describe_box(box)} "
                         f"in a {config.arena_size:g} m arena (use a rounder shape, fewer boxes or a "
                         "bigger arena)")
    box = outlines.overreach(config, sizing.polygon(sizing.largest) if largest is None else largest)
    if box is None:
        return []
    x0, x1, y0, y1 = box
    beyond = max(-x0, -y0, x1 - config.arena_size, y1 - config.arena_size)
    return [f"at its largest the band reaches {beyond:.1f} m past the {config.arena_size:g} m arena's walls, "
            f"where there are no lights: it is cut short there"]


#: The strategies that do nothing with the offset outline, and why (the advisor leaves them out there too).
OFFSET_INERT = {s.name: s.offset_inert for s in STRATEGIES if s.offset_inert}


def inert_strategies(family: str) -> dict[str, str]:
    """The strategies that do nothing, whatever their amount, on an outline of this family ('scaled' or
    'offset'), each with why (a clause); the page greys them out."""
    return dict(OFFSET_INERT) if family == "offset" else {}


def inert_note(name: str, family: str) -> str:
    """Why strategy ``name`` does nothing on this outline family, in a sentence ('' when it does something)."""
    why = inert_strategies(family).get(name)
    return f"{STRATEGY_LABELS[name]} does nothing with the {family} outline: {why}." if why else ""


def strategy_effect_note(name: str, amount: float, goal_vertices: np.ndarray | None, chase: float = 0.0,
                         family: str = "scaled") -> str:
    """Why a strategy at this amount will change nothing on this goal ('' when it will).

    A circle goal has no corners to flare or darken and is already a circle;
    flare moves a convex corner of angle a only when 90 x amount > a, so on a
    square it starts above 1 and on the star's 52.5-degree tips above 0.58.
    With chase on, the lit outline is the goal grown, so flare changes only
    how far it grows."""
    if amount <= 0:
        return ""
    inert = inert_note(name, family)
    if inert:
        return inert
    if name == "flare" and chase > 0 and goal_vertices is not None:
        return ("With chase on, the band follows the goal grown by the same distance all round, not a flared "
                "outline: flare changes only the largest size it grows to.")
    if goal_vertices is None:
        return {"flare": "Flare does nothing on a circle goal: it has no corners to push out.",
                "switch": "Switch to circle does nothing on a circle goal: it is a circle already.",
                "no_corners": "No corners does nothing on a circle goal: it has no corners."}.get(name, "")
    if name == "flare":
        angles = geometry.interior_angles(np.asarray(goal_vertices, dtype=float))
        convex = angles[angles < 180.0]
        if len(convex) and not (90.0 * amount > convex).any():
            sharpest = float(convex.min())
            return (f"Flare {amount:g} does nothing on this goal: flare moves a corner only when 90 x amount "
                    f"exceeds its angle, and the sharpest corner is {sharpest:.0f} degrees "
                    f"(flare acts above {sharpest / 90.0:.2f}).")
    return ""
