"""Which outline family a goal takes, and why (``Config.outline``); :func:`make_goal`, the way in to a
goal: the user's polygon fitted (:mod:`sandbox.model.goal`) and its family decided.

* ``scaled`` (the paper): the goal scaled about the assembly centre. It
  needs the centre deep inside the goal: its smallest size keeps the centre
  a robot diameter inside the outline, so for a goal whose centre lies near
  an edge (an L, a crescent) it is enormous, or past the arena.
* ``offset``: the goal grown by a distance (:mod:`sandbox.model.offset`);
  it builds any simple polygon. Its goal is also kept inside the wall that
  stops boxes (:func:`sandbox.model.goal.inside_construction`).
* ``auto`` (default): scaled when the centre lies deep inside the goal, its
  distance to the edge at least a third of its distance to the farthest
  vertex (the circle 1, the square 0.71, the star and the triangle 0.5, the
  house 0.64), and the smallest scaled outline fits the arena; offset
  otherwise (the T 0.31, the arrow 0.29, the L 0.02, the crescent 0). So the
  paper's cases, and every shape the authors' program builds well, run as
  the program does. An offset goal with notches lights them while the band
  closes in (``Config.notches``, :mod:`sandbox.model.notches`), and the
  reason says so.

An explicit ``scaled`` that cannot fit a goal does not refuse it: the offset
outline runs it, and the reason says so.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from sandbox.model import gather, notches, offset, outlines
from sandbox.model.config import Config
from sandbox.model.goal import Goal, fit_goal, inside_construction
from sandbox.shapes import geometry

#: auto takes scaled when the centre's distance to the edge is at least this share of its distance
#: to the farthest vertex.
DEEP_INSIDE = 1.0 / 3.0


def centre_depth(goal: Goal) -> float:
    """How deep the assembly centre lies in the goal: its distance to the edge over its distance to
    the farthest vertex (1 for a circle, 0 on or outside the edge)."""
    if goal.vertices is None:
        return 1.0
    centre = goal.centre[None, :]
    if not geometry.points_in_polygon(centre, goal.vertices)[0]:
        return 0.0
    to_edge = float(geometry.distance_to_outline(centre, goal.vertices)[0])
    return to_edge / float(np.hypot(*(goal.vertices - goal.centre).T).max())


def scaled_overreach(config: Config, goal: Goal) -> str:
    """Where the smallest scaled outline reaches past the arena ('' when it fits)."""
    sizing = outlines.ScaledSizing.of(config, goal, config.flare)
    box = outlines.overreach(config, sizing.polygon(sizing.smallest))
    return "" if box is None else outlines.describe_box(box)


def choose(config: Config, goal: Goal) -> tuple[str, str]:
    """The family (``scaled`` or ``offset``) and, in words, why."""
    asked = config.outline
    if asked == "offset":
        return "offset", "asked for (outline = offset)"
    if goal.vertices is None:
        return "scaled", ("asked for (outline = scaled)" if asked == "scaled"
                          else "a circle: the paper's ring, which the offset outline would light the same")
    depth = centre_depth(goal)
    if asked == "scaled":
        if depth <= 0.0:
            return "offset", ("scaled was asked for, but the centre lies on the goal's edge or outside it, where "
                              "scaling about it cannot bring the band to the goal: the offset outline runs this "
                              "goal instead")
        past = scaled_overreach(config, goal)
        if past:
            return "offset", (f"scaled was asked for, but its smallest outline would span {past}, past the "
                              f"arena: the offset outline runs this goal instead")
        return "scaled", "asked for (outline = scaled)"
    if depth < DEEP_INSIDE:
        return "offset", (f"auto: the centre lies near the goal's edge (its distance to the edge is {depth:.2f} of "
                          f"its distance to the farthest vertex, below {DEEP_INSIDE:.2f}), so scaling about it "
                          f"cannot reach every part; the band follows the goal's edge at a distance instead")
    past = scaled_overreach(config, goal)
    if past:
        return "offset", (f"auto: the smallest scaled outline would span {past}, past the arena; the band "
                          f"follows the goal's edge at a distance instead")
    return "scaled", (f"auto: the centre lies deep inside the goal (its distance to the edge is {depth:.2f} of its "
                      f"distance to the farthest vertex, at least {DEEP_INSIDE:.2f}), as the paper's shapes do")


def make_goal(config: Config, vertices: np.ndarray | None) -> Goal:
    """Fit the user's polygon (or a circle) to the assembly centre and the boxes' total area, and
    decide the outline family it takes (:func:`settle`, on the fitted goal: the way in to a goal
    for the rest of the model).

    The fitted outline is simplified to a twentieth of a light pitch: far
    finer than a light can show, and a 10,000-vertex file then costs what a
    hand-drawn one does (every light and every box is measured against it).
    One that still has more vertices than the outlines afford is simplified
    further, within at most a quarter of a pitch, and says so; if that is not
    enough it is refused (:func:`sandbox.model.goal.affordable_outline`)."""
    return settle(config, fit_goal(config, vertices))


def settle(config: Config, goal: Goal) -> Goal:
    """The goal with its outline family decided; an offset goal moved inside the construction wall."""
    family, reason = choose(config, goal)
    if family == "offset" and goal.vertices is not None:
        shift = inside_construction(config, goal.vertices)
        if shift.any():
            goal = dataclasses.replace(goal, vertices=goal.vertices + shift,
                                       moved=(float(shift[0]), float(shift[1])))
        reason += notches_said(config, goal.vertices)
    return dataclasses.replace(goal, family=family, family_reason=reason)


def notches_said(config: Config, vertices: np.ndarray) -> str:
    """What the offset outline does with the goal's notches, in words ('' for none, notches = plain or
    chase on)."""
    lit = notches.lit_notches(config, vertices, config.chase)
    if not lit:
        return ""
    what = "a notch" if len(lit) == 1 else f"{len(lit)} notches"
    return (f". The goal has {what} (gaps narrower than {2 * notches.CLOSING_RADIUS:g} m): each is lit while the "
            f"band closes in, and the band moves at {notches.PACE:.1f} of its pace within "
            f"{notches.SLOW_WITHIN:g} m of the goal, so the robots clear them before the band presses the boxes "
            f"into them; beside thin parts, tips and corners the band holds farther out, so the robots do not ride "
            f"onto them (notches = lit; chase, when on, lights its own band)" + gathering_said(config, vertices, lit))


def gathering_said(config: Config, vertices: np.ndarray, lit: tuple) -> str:
    """What the dilating band does about the sides the notches starve, in words ('' when it gathers
    nowhere)."""
    sides = offset.gather_sides(config, vertices, lit)
    if not sides:
        return ""
    faced = gather.all_faced(gather.mouth_directions(vertices, lit))
    return (f". The notches' mouths face {gather.said(faced)} of the goal: the robots they let out go "
            f"there, and none come back to {gather.said(sides)}. While the band dilates beyond {gather.BEYOND:g} m "
            f"only its lights beyond {gather.said(sides)} stay lit, so the robots gather there (gather = auto)")
