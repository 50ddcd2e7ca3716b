"""A goal's notches, and the lights that hold them clear (issue 42; ``Config.notches``).

The offset band enters a notch only once it is closer to the goal than half
the notch's width; from then on its level set there is a ridge along the
notch's axis that lights all at once. The boxes the band brings in fill the
notch, which lies outside the goal, and they are the boxes missing at the
ends of the prongs (``docs/design-notches.md``).

A **notch** here is what closing the goal by a disc of radius
:data:`CLOSING_RADIUS` adds to it (a gap narrower than twice that), in pieces
of at least :data:`SMALLEST_AREA`. With ``notches = "lit"`` every light inside
a notch is lit while the band contracts (and holds) within :data:`REACH` of
the notch's deepest light, ``k``; it goes dark while the band dilates, so the
robots in it follow the band out instead of pushing the prongs' boxes outward
unopposed. The robots gather in the lit notch and push its boxes into the
prongs before the band presses the rest; within :data:`SLOW_WITHIN` of the
goal the band also moves at :data:`PACE` of its speed, which gives them the
time to get there. Neither alone helps the letter H (seeds 0-3, 100,000
steps: 0.712 and 0.714 against the plain band's 0.705); together they build
it at 0.77. Slowed only near the goal, the band builds as well and sooner
(the H at 30,000 steps: 0.747 against 0.730 slowed everywhere).

Both are the open loop's: chase lights its own band, at the paper's pace
(with the slower pace it lost 0.04 on the H).
"""

from __future__ import annotations

import numpy as np
import shapely

from sandbox.model.config import Config

#: Closing the goal by a disc this wide (m) fills gaps narrower than twice it: the notches.
CLOSING_RADIUS = 1.5
#: Pieces of the closing smaller than this (m^2) are a corner's sliver, not a notch.
SMALLEST_AREA = 0.5
#: A notch is lit while the band contracts within this distance (m) of its deepest light.
REACH = 2.0
#: On a notched goal each of the band's steps within :data:`SLOW_WITHIN` of it is the schedule's factor
#: raised to this: the band moves at about 0.4 of its speed there (0.975 becomes 0.99).
PACE = 0.397
#: The band moves at :data:`PACE` only this close to the goal (m): no notch's light is farther from the
#: goal than the closing radius, so no notch is lit farther out than this, and the robots are already
#: slowed when one lights. Farther out it keeps the paper's pace: a cycle of the letter H (between 0.5 and
#: 5.1 m) takes about a sixth less time than slowed everywhere.
SLOW_WITHIN = CLOSING_RADIUS + REACH

#: Never lit as part of a notch.
NEVER = -np.inf


def notch_polygons(vertices: np.ndarray) -> list[shapely.Polygon]:
    """The goal's notches: what closing it by a disc of :data:`CLOSING_RADIUS` adds, in pieces of at least
    :data:`SMALLEST_AREA`."""
    goal = shapely.Polygon(vertices)
    if not goal.is_valid:
        goal = shapely.make_valid(goal).buffer(0)
    closed = goal.buffer(CLOSING_RADIUS, quad_segs=8).buffer(-CLOSING_RADIUS, quad_segs=8)
    added = closed.difference(goal.buffer(1e-6))
    parts = getattr(added, "geoms", [added])
    return [p for p in parts if isinstance(p, shapely.Polygon) and p.area >= SMALLEST_AREA]


def lit_notches(config: Config, vertices: np.ndarray | None, chase: float) -> tuple[shapely.Polygon, ...]:
    """The notches the open loop lights: none for a circle, with ``notches = plain``, or with ``chase`` on
    (it lights its own band)."""
    if config.notches != "lit" or chase > 0 or vertices is None:
        return ()
    return tuple(notch_polygons(vertices))


def notch_reach(centres: np.ndarray, notches: tuple[shapely.Polygon, ...], distances: np.ndarray) -> np.ndarray:
    """For each light (``centres`` flat, ``distances`` their signed distances to the goal): the band's
    size at or below which it is lit as part of a notch, ``k +`` :data:`REACH` with ``k`` the largest
    distance of the notch's lights to the goal; :data:`NEVER` outside every notch."""
    reach = np.full(len(centres), NEVER)
    for notch in notches:
        inside = shapely.contains_xy(notch, centres[:, 0], centres[:, 1]) & (distances > 0.0)
        if inside.any():
            reach[inside] = float(distances[inside].max()) + REACH
    return reach
