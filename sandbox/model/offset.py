"""The offset outline family: the band at a distance from the goal (issue 22).

The paper's outline is the goal scaled about the assembly centre. For a goal
whose centroid lies near its edge (an L, a crescent, a C) scaling cannot
work: the smallest scale that keeps the centre a robot diameter inside the
outline is enormous. Here a size is a distance ``d`` instead: a light is on
when its centre's signed distance to the goal (negative inside) is within
``band`` of ``d``, so the band is the edge of the goal grown by ``d``, one
light wide as the paper's. It follows every arm, notch and hollow of the
goal, and no centre is needed.

The geometry decides the sizes (measured on nine shapes, 2-4 seeds x
40,000-100,000 steps: ``docs/design-offset.md``; every shape at 100,000
steps: ``static/shapes/README.md``):

* **smallest** ``d``: one robot diameter, the paper's gap;
* **largest** ``d``, where the first contraction starts: the band encloses
  the robots' spawn square, one light pitch clear (robots start uncharged,
  so the band must pass every one), a pitch inside the walls at most;
* **turn** ``d``, where every dilation turns: the band encloses the
  construction area, where every box is, one pitch clear. Going back out to
  the spawn square did worse on every shape tried, with half the cycles;
* **steps**: ``d + R`` times ``scale_rate`` contracting (over it dilating),
  ``R`` the radius of the circle of the goal's area. For a circle goal the
  band is then exactly the paper's scaled ring, and elsewhere it moves as
  fast as the paper's does at the same distance from a goal of that area.

Of the paper's strategies, flare and switch have nothing to do: the band
rounds every convex corner at the same distance as the edges (the star's
tips fill), and at a large distance it is nearly a circle. The band has no
convex corners for no corners to darken. Chase grows the goal by a distance
already, and works unchanged.

A goal with notches (gaps narrower than 3 m) has them lit while the band
closes in, and the band moves slower near the goal
(:mod:`sandbox.model.notches`) and holds farther out beside the goal's thin
parts, tips and corners (:mod:`sandbox.model.thin`). Chase lights its own band, at the paper's
pace, and no notch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import shapely

from sandbox.model import gather as gathering, notches as notch_lights, thin
from sandbox.model.config import Config
from sandbox.model.goal import CIRCLE_DRAW_VERTICES, Goal
from sandbox.shapes import geometry

#: Lights exactly ``band`` from the level set are in it, whatever the rounding.
_EDGE = 1e-9
#: Points a polygon's covering distance is sampled at, this far apart (m), corners included.
_COVER_SPACING = 0.25


# -- the distance field -----------------------------------------------------------------------
def signed_distance(points: np.ndarray, goal: Goal) -> np.ndarray:
    """Signed distance of each point (..., 2) to the goal's edge: positive outside, negative inside
    (a circle goal exactly, a polygon against its vertices)."""
    p = np.asarray(points, dtype=float)
    flat = p.reshape(-1, 2)
    if goal.vertices is None:
        out = np.hypot(*(flat - goal.centre).T) - goal.radius
    else:
        out = geometry.distance_to_outline(flat, goal.vertices)
        out = np.where(geometry.points_in_polygon(flat, goal.vertices), -out, out)
    return out.reshape(p.shape[:-1])


def square_point_blocks(centre: np.ndarray, half: float, spacing: float, at_most: int):
    """Points filling the square of half-side ``half`` about ``centre`` (edges included), ``spacing``
    apart, in blocks of whole rows of at most ``at_most`` points (one row at least): a 2,000 m square
    has 64 million, 3 GB of coordinates and distances at once."""
    n = max(int(math.ceil(2.0 * half / spacing)), 1) + 1
    s = np.linspace(-half, half, n)
    centre = np.asarray(centre, dtype=float)
    rows = max(1, at_most // n)
    for first in range(0, n, rows):
        gx, gy = np.meshgrid(s[first:first + rows], s, indexing="ij")
        yield np.stack([gx.ravel(), gy.ravel()], axis=-1) + centre


#: covering_distance measures the square's points this many at a time.
_COVER_POINTS_AT_ONCE = 1 << 18


def covering_distance(goal: Goal, centre: np.ndarray, half: float) -> float:
    """The smallest ``d`` whose grown goal covers the square of half-side ``half`` about ``centre``:
    the largest distance from a point of the square to the goal, taken a block of points at a time."""
    blocks = square_point_blocks(centre, half, _COVER_SPACING, _COVER_POINTS_AT_ONCE)
    farthest = max(float(signed_distance(points, goal).max()) for points in blocks)
    return float(max(farthest, 0.0))


def wall_distance(goal: Goal, arena_size: float, clearance: float) -> float:
    """The largest ``d`` whose grown goal stays ``clearance`` inside the arena's walls
    (the grown goal's bounding box is the goal's grown by ``d``)."""
    if goal.vertices is None:
        low, high = goal.centre - goal.radius, goal.centre + goal.radius
    else:
        low, high = goal.vertices.min(axis=0), goal.vertices.max(axis=0)
    return float(min(low.min(), (arena_size - high).min()) - clearance)


def gather_sides(config: Config, vertices: np.ndarray | None, notches: tuple) -> str:
    """The sides the dilating band gathers the robots beside (:mod:`sandbox.model.gather`): '' without lit
    notches or with ``gather = off``."""
    if not notches or config.gather != "auto":
        return ""
    return gathering.sides_to_gather(vertices, notches)


# -- the family ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class OffsetSizing:
    """The goal grown by a distance: a size is ``d`` in metres (see the module docstring).
    The outline's "inradius" (what the controller's schedules compare) is ``R + d``."""

    goal: Goal
    smallest: float
    largest: float
    turn: float  # where dilations turn
    unit_radius: float  # R: the radius of the circle of the goal's area
    circle_largest: float
    #: The goal's notches (:mod:`sandbox.model.notches`), lit while the band closes in; none: the plain band.
    notches: tuple = ()
    #: Each step's factor within ``slow_within`` of the goal is raised to this: 1 the paper's pace, slower
    #: on a notched goal.
    pace: float = 1.0
    #: The band's size at or below which it moves at ``pace`` (farther out at the paper's).
    slow_within: float = math.inf
    #: The lights' glow on a notched goal, whose band holds farther out beside thin parts and tips
    #: (:mod:`sandbox.model.thin`); None: it comes to ``smallest`` all round.
    glow: thin.Glow | None = None
    #: The sides of the goal's bounding box the dilating band gathers the robots beside, beyond
    #: :data:`sandbox.model.gather.BEYOND` (:mod:`sandbox.model.gather`); '' lights the whole band.
    gather: str = ""
    #: Flare and switch reshape a scaled outline; a grown goal has nothing for them to do.
    switchable = False
    shape = None
    _distances: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(cls, config: Config, goal: Goal, chase: float = 0.0) -> "OffsetSizing":
        """The smallest, largest and turning distances for this goal (see the module docstring), and its
        notches unless ``chase`` is on (it lights its own band)."""
        pitch, centre = config.light_pitch, np.full(2, config.centre)
        walls = wall_distance(goal, config.arena_size, pitch)
        smallest = 2.0 * config.robot_radius
        largest = max(min(covering_distance(goal, centre, config.robot_spawn_size / 2.0) + pitch, walls), smallest)
        turn = min(covering_distance(goal, centre, config.construction_size / 2.0) + pitch, largest)
        notches = notch_lights.lit_notches(config, goal.vertices, chase)
        return cls(goal, smallest, largest, max(turn, smallest), goal.radius, config.circle_max * config.arena_size / 2.0,
                   notches, notch_lights.PACE if notches else 1.0, notch_lights.SLOW_WITHIN,
                   thin.Glow.of(config) if notches else None, gather_sides(config, goal.vertices, notches))

    def pace_at(self, size: float) -> float:
        """The power each step's factor is raised to at this size: ``pace`` within ``slow_within``."""
        return self.pace if size <= self.slow_within else 1.0

    def step(self, size: float, factor: float) -> float:
        return (size + self.unit_radius) * factor**self.pace_at(size) - self.unit_radius

    def step_back(self, size: float, factor: float) -> float:
        return (size + self.unit_radius) / factor**self.pace_at(size) - self.unit_radius

    def widen(self, size: float, metres: float) -> float:
        return size + metres

    def radius(self, size: float) -> float:
        return self.unit_radius + size

    def circle_radius(self, size: float) -> float:
        """The circle a circle goal grown by ``size`` is."""
        return self.unit_radius + size

    def polygon(self, size: float) -> np.ndarray:
        """The goal grown by ``size``: the band's middle line, to draw and to measure against."""
        if self.goal.vertices is None:
            return geometry.regular_polygon(self.circle_radius(size), CIRCLE_DRAW_VERTICES, self.goal.centre)
        grown = shapely.Polygon(self.goal.vertices).buffer(size, quad_segs=8)
        return np.asarray(grown.exterior.coords)[:-1]

    def corners(self, size: float) -> np.ndarray:
        return np.empty((0, 2))

    def distance(self, size: float) -> float:
        return size

    def radius_beyond(self, distance: float) -> float:
        return self.unit_radius + distance

    def lit(self, centres: np.ndarray, size: float, band: float, dilating: bool = False) -> np.ndarray:
        """The lights whose signed distance to the goal is within ``band`` of ``size`` (or of their least
        distance beside a thin part, when ``size`` is below it), and unless the band is dilating those of a
        notch it has come within reach of (measured once per goal); dilating beyond
        :data:`sandbox.model.gather.BEYOND`, only those beside the sides it gathers at."""
        known = self._distances.get("centres")
        if known is None or known[0] is not centres:
            known = self._distances["centres"] = (centres, *self._light_distances(centres))
        _, distances, reach, least, starved = known
        level = size if least is None else np.maximum(size, least)
        on = np.abs(distances - level) <= band + _EDGE
        if reach is not None and not dilating:
            on |= size <= reach
        if dilating and starved is not None and size > gathering.BEYOND:
            on &= starved
        return on

    def gathering_at(self, size: float, dilating: bool) -> str:
        """The sides the band gathers the robots beside at this size ('' for none)."""
        return self.gather if dilating and size > gathering.BEYOND else ""

    def _light_distances(self, centres: np.ndarray) -> tuple:
        """Each light's signed distance to the goal, the band size within which it is lit as part of a
        notch, the least distance the band comes to it (None where the goal has no notch), and whether it
        lies beside a side the dilating band gathers at (None: no gathering)."""
        distances = signed_distance(centres, self.goal)
        if not self.notches:
            return distances, None, None, None
        least = (thin.hold_distances(self.glow, centres, distances, self.goal.vertices, self.smallest)
                 if self.glow is not None else None)
        starved = (gathering.beyond_sides(centres, shapely.Polygon(self.goal.vertices).bounds, self.gather)
                   if self.gather else None)
        return distances, notch_lights.notch_reach(centres, self.notches, distances), least, starved
