"""The sides a notched goal's robots are gathered back to (issue 42; ``Config.gather``).

A lit notch (:mod:`sandbox.model.notches`) draws robots in at each press
and, when the band dilates, lets them out through its mouth, so they leave
towards the side of the goal its mouth faces. When the notches' mouths face
two opposite sides (the letters H, K, X and W open up and down), every cycle
takes robots from the two sides between and none come back: a robot drives
only up a gradient, and an evenly lit band never sends it along itself. The
letter K's stem side held 30 robots in its first cycle and 6 in its sixth, and
the K built 0.720 (``docs/design-notches.md``).

So while the band dilates beyond :data:`BEYOND` of the goal, only its lights
beyond the goal's bounding box on those starved sides stay lit: the robots
on the dark part drive to the nearest lit part and ride it back in. It costs
no time (the band's sizes are the paper's schedule's), and the page shows
exactly the lights that are on.

A mouth *faces* the side of the goal's bounding box its direction points to
most, the direction being from the notch's centroid to its mouth's (the
notch's edge that is not the goal's). Only notches in line gather: two
that face opposite sides and whose pockets (the pieces of the goal's convex
hull outside it that hold them) overlap across that axis, as the H's, the
K's, the X's, the N's, the M's and the W's do. The letter S's two bays open left and
right at different heights: gathering beside its top and bottom cost it
0.011 +- 0.006 (seeds 0-3, paired), so staggered pockets gather nowhere.
Of the unfaced sides, one the mouths lean towards (:data:`LEAN`) is fed as
well: the K's lean to its right, so it gathers beside its stem alone, and
the Z's lean up and down, so it gathers nowhere. Mouths facing one side only (the E, the comb, the Y)
leave three sides unfaced: gathering there helped none of those measured,
so they gather nowhere.
"""

from __future__ import annotations

import numpy as np
import shapely

#: The bounding box's sides, each with its outward direction.
OUTWARD = {"L": (-1.0, 0.0), "R": (1.0, 0.0), "B": (0.0, -1.0), "T": (0.0, 1.0)}
#: Each side's opposite.
OPPOSITE = {"L": "R", "R": "L", "B": "T", "T": "B"}
#: An unfaced side is fed, not starved, when the mouths' leans towards it (each direction's component
#: along its outward direction, where positive) add up to at least this. The letter K's two notches open
#: up and down, each leaning 0.36 to the right, towards the open V between its arms (0.72 in all): the
#: robots they let out reach its right side too, and only the stem's side starves. The N's lean 0.38 one
#: way and 0.38 the other: gathered beside its left and right it builds 0.788 against 0.746. The Z's lean
#: 0.47 up and 0.47 down: gathered beside its top and bottom it lost 0.015 (0.024 over the last 20,000
#: steps). So the value lies between 0.38 and 0.47, measured on those two; a goal whose lean is near it
#: could go either way.
LEAN = 0.45
#: Said in words.
SIDE_NAMES = {"L": "left", "R": "right", "B": "bottom", "T": "top"}
#: While dilating beyond this distance (m) from the goal the band lights only the starved sides. It starts
#: once the robots have followed the band out of the notches; the robots then need the rest of the
#: dilation to drive round. Measured on the letter K (seeds 0-3, 100,000 steps): gathering from 2.0, 2.5
#: or 2.9 m builds it at 0.750, 0.759 and 0.753, from 3.5 m only 0.727.
BEYOND = 2.5


def mouth_directions(vertices: np.ndarray, notches: tuple[shapely.Polygon, ...]) -> list[np.ndarray]:
    """Each notch's mouth direction: the unit vector from its centroid to its mouth's (a notch whose
    edges all lie on the goal's has none: see :func:`mouths`)."""
    return [direction for direction, _ in mouths(vertices, notches)]


def mouths(vertices: np.ndarray, notches: tuple[shapely.Polygon, ...]) -> list[tuple[np.ndarray, tuple]]:
    """Each notch with a mouth: its mouth direction, from its centroid to its mouth's (the notch's edge that
    is not the goal's), and the bounding box of its pocket, the piece of the goal's convex hull outside the
    goal that holds it (a notch is only a pocket's narrow end: the letter N's lie at opposite ends of its
    stems, while its pockets, the triangles beside its diagonal, span the same width)."""
    goal = shapely.Polygon(vertices)
    if not goal.is_valid:
        goal = shapely.make_valid(goal).buffer(0)
    outside = goal.convex_hull.difference(goal)
    pockets = [p for p in getattr(outside, "geoms", [outside]) if isinstance(p, shapely.Polygon) and p.area > 0]
    found = []
    for notch in notches:
        mouth = notch.boundary.difference(goal.buffer(1e-3))
        if mouth.is_empty:
            continue
        towards = np.array(mouth.centroid.coords[0]) - np.array(notch.centroid.coords[0])
        length = float(np.hypot(*towards))
        if length > 1e-9:
            pocket = max(pockets, key=lambda p: p.intersection(notch).area, default=notch)
            found.append((towards / length, pocket.bounds))
    return found


def faced_side(direction: np.ndarray) -> str:
    """The bounding box's side a mouth direction points to most."""
    return max(OUTWARD, key=lambda side: float(np.dot(OUTWARD[side], direction)))


def all_faced(directions: list[np.ndarray]) -> str:
    """The sides any of the mouths faces, in ``LRBT`` order."""
    faced = {faced_side(d) for d in directions}
    return "".join(side for side in OUTWARD if side in faced)


def in_line(first: tuple, second: tuple, side: str) -> bool:
    """Whether two pockets (their bounding boxes, ``x0, y0, x1, y1``) whose mouths face ``side`` and its
    opposite overlap across that axis: side by side along x for the top and bottom, along y for the left and
    right."""
    low, high = (0, 2) if side in "BT" else (1, 3)
    return min(first[high], second[high]) > max(first[low], second[low])


def lean(directions: list[np.ndarray], side: str) -> float:
    """How much the mouths lean towards a side: their directions' components along its outward direction,
    where positive, added up."""
    return float(sum(max(float(np.dot(OUTWARD[side], d)), 0.0) for d in directions))


def starved_sides(directions: list[np.ndarray], bounds: list[tuple]) -> str:
    """The sides to gather beside, in ``LRBT`` order: when two notches in line (:func:`in_line`, ``bounds``
    their pockets' bounding boxes, one per direction) face opposite sides, the sides no mouth faces, less
    those the mouths lean towards (:data:`LEAN`); '' otherwise."""
    sides = [faced_side(d) for d in directions]
    opposed = any(sides[j] == OPPOSITE[sides[i]] and in_line(bounds[i], bounds[j], sides[i])
                  for i in range(len(sides)) for j in range(len(sides)))
    if not opposed:
        return ""
    faced = all_faced(directions)
    return "".join(side for side in OUTWARD if side not in faced and lean(directions, side) < LEAN)


def sides_to_gather(vertices: np.ndarray, notches: tuple[shapely.Polygon, ...]) -> str:
    """The sides a goal with these notches gathers its robots beside ('' for none)."""
    found = mouths(vertices, notches)
    return starved_sides([direction for direction, _ in found], [bounds for _, bounds in found])


def beyond(points: np.ndarray, bounds: tuple[float, float, float, float]) -> dict[str, np.ndarray]:
    """Which points lie beyond each side (``LRBT``) of a bounding box (``x0, y0, x1, y1``; a corner's points
    are beyond two)."""
    x0, y0, x1, y1 = bounds
    x, y = points[:, 0], points[:, 1]
    return {"L": x < x0, "R": x > x1, "B": y < y0, "T": y > y1}


def beyond_sides(points: np.ndarray, bounds: tuple[float, float, float, float], sides: str) -> np.ndarray:
    """Which points lie beyond any of the given sides of a bounding box (``x0, y0, x1, y1``)."""
    past = beyond(points, bounds)
    out = np.zeros(len(points), bool)
    for side in sides:
        out |= past[side]
    return out


def said(sides: str) -> str:
    """The sides in words: 'the left and right'."""
    names = [SIDE_NAMES[s] for s in sides]
    return "the " + (names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1])
