"""The outline the controller lights, and its smallest and largest sizes (SPEC §5, §9).

The controller asks an outline *family* (:class:`Sizing`) for its smallest
and largest sizes, how a size steps, the outline's inradius at a size (what
its schedules compare), the outline itself and which lights its band lights;
it never looks inside a size. Two families: :class:`ScaledSizing`, the goal
(or the circle) scaled about the assembly centre, a size being the scale
(the paper's word, which the controller keeps); and
:class:`~sandbox.model.offset.OffsetSizing`, the goal grown by a distance.
The goal says which one it takes (:mod:`sandbox.model.family` decides);
:func:`sizing_for` builds it.

An :class:`OutlineShape` is a polygon relative to the assembly centre at
*scale 1*; the controller lights ``centre + scale * vertices``. For a plain
polygon scale 1 is the goal itself. Flare changes the shape, in one of two
ways (``Config.flare_mode``):

* ``on-goal`` (paper text): the goal's convex corners are pushed out, and the
  sizes are those of the goal, so at scale 1 the corners reach past the goal;
* ``scaled-outline`` (the authors' program): every corner is pushed out by
  ``90 f / |angle between its edges|`` (reflex corners too), and that new
  polygon, rescaled to the goal's area, is what is scaled and sized.

Sizes:

* smallest (``min_size_rule``): the goal's equal-area radius plus one robot
  diameter (paper text), or the outline's inradius (distance from the centre
  to the outline) equal to its inradius at scale 1 plus one robot diameter
  (the authors' program);
* largest for a polygon (``polygon_max_rule``): the largest scale inside the
  arena, one light pitch clear, up to ``polygon_max_area`` of the arena
  (paper text), or the file's own outline grown by 1.05 at a time until it
  covers ``polygon_max_area`` of the arena or reaches its edge, that last
  step included (the authors' program: so the size depends on the size the
  file was drawn at, and a star's tips may reach past the walls);
* largest for a circle: ``circle_max`` of half the arena.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sandbox.model import band
from sandbox.model.config import Config
from sandbox.model.goal import CIRCLE_DRAW_VERTICES, Goal
from sandbox.model.offset import OffsetSizing
from sandbox.shapes import geometry

#: The authors' program grows a polygon to its largest size in steps of this factor.
PROGRAM_GROWTH_STEP = 1.05


@dataclass(frozen=True)
class OutlineShape:
    """A polygon outline at scale 1, relative to the assembly centre."""

    vertices: np.ndarray
    #: Which vertices are convex corners (the no-corners strategy darkens lights near them).
    corners: np.ndarray
    #: The polygon the sizes are measured on, at scale 1 (the goal, or the flared outline).
    sized: np.ndarray
    #: ``sized`` times this is the polygon at the size its file gave (for polygon_max_rule 'grow').
    file_scale: float

    @property
    def inradius(self) -> float:
        """Distance from the centre to the nearest point of the sized outline at scale 1."""
        return float(geometry.distance_to_outline(np.zeros((1, 2)), self.sized)[0])


class Sizing(Protocol):
    """An outline family: the outlines the controller can light, one per size."""

    #: The smallest and largest sizes (the first contraction starts at the largest), and the size
    #: every dilation turns at.
    smallest: float
    largest: float
    turn: float
    #: The largest radius of a circle lit in the outline's place (switch), and whether switch may.
    circle_largest: float
    switchable: bool

    def step(self, size: float, factor: float) -> float:
        """The size one update on, ``factor`` being the schedule's (below 1: contracting)."""

    def step_back(self, size: float, factor: float) -> float:
        """The size one update back (the clamped schedule dilates so)."""

    def widen(self, size: float, metres: float) -> float:
        """The size whose outline's inradius is ``metres`` more."""

    def radius(self, size: float) -> float:
        """The outline's inradius at ``size`` (its radius for a circle)."""

    def circle_radius(self, size: float) -> float:
        """The radius of the circle lit in the outline's place at ``size`` (switch)."""

    def polygon(self, size: float) -> np.ndarray:
        """The outline at ``size``, absolute (a fine polygon for a circle)."""

    def corners(self, size: float) -> np.ndarray:
        """The outline's convex corners at ``size`` (none for a circle)."""

    def distance(self, size: float) -> float:
        """How far the outline at ``size`` lies beyond the goal-sized one, on their inradii."""

    def radius_beyond(self, distance: float) -> float:
        """The inradius of the outline ``distance`` beyond the goal-sized one."""

    def lit(self, centres: np.ndarray, size: float, width: float, dilating: bool = False) -> np.ndarray:
        """Which lights (centres, flat) the band at ``size`` lights: those within ``width`` of it (and, for
        the offset family, a notch's while the band is not ``dilating``)."""

    def gathering_at(self, size: float, dilating: bool) -> str:
        """The sides of the goal's bounding box (any of ``LRBT``) beside which alone the band is lit at
        ``size``, gathering the robots there ('' for the whole band; see :mod:`sandbox.model.gather`)."""


@dataclass(frozen=True)
class ScaledSizing:
    """The goal (flared, or the circle) scaled about the assembly centre: a size is
    the scale, 1 being the outline at the goal's area (see the module docstring)."""

    goal: Goal
    shape: OutlineShape | None  # None: the circle
    smallest: float
    largest: float
    #: The outline's inradius at scale 1 (the radius, for a circle).
    unit_radius: float
    circle_largest: float
    #: Switch may light a circle in its place.
    switchable = True

    @property
    def turn(self) -> float:
        """Where dilations turn: the largest scale."""
        return self.largest

    @classmethod
    def of(cls, config: Config, goal: Goal, flare: float) -> "ScaledSizing":
        """The outline at scale 1 for this goal and flare, and its smallest and largest scales."""
        circle_largest = max_circle_radius(config)
        if goal.is_circle:
            smallest = (goal.radius + 2.0 * config.robot_radius) / goal.radius
            largest = max_circle_scale(config, goal.radius)
            return cls(goal, None, smallest, max(largest, smallest), goal.radius, circle_largest)
        shape = outline_shape(goal.vertices - goal.centre, goal.area, goal.file_area, flare, config.flare_mode)
        smallest = min_polygon_scale(config, shape, goal.radius)
        largest = max_polygon_scale(config, shape, goal.area)
        return cls(goal, shape, smallest, max(largest, smallest), shape.inradius, circle_largest)

    def step(self, size: float, factor: float) -> float:
        return size * factor

    def step_back(self, size: float, factor: float) -> float:
        return size / factor

    def widen(self, size: float, metres: float) -> float:
        return size + metres / self.unit_radius

    def radius(self, size: float) -> float:
        return size * self.unit_radius

    def circle_radius(self, size: float) -> float:
        """The goal's equal-area radius times the scale."""
        return self.goal.radius * size

    def polygon(self, size: float) -> np.ndarray:
        if self.shape is None:
            return geometry.regular_polygon(self.goal.radius * size, CIRCLE_DRAW_VERTICES, self.goal.centre)
        return self.goal.centre + size * self.shape.vertices

    def corners(self, size: float) -> np.ndarray:
        if self.shape is None:
            return np.empty((0, 2))
        return self.polygon(size)[self.shape.corners]

    def distance(self, size: float) -> float:
        return self.radius(size) - self.unit_radius

    def radius_beyond(self, distance: float) -> float:
        return self.unit_radius + distance

    def lit(self, centres: np.ndarray, size: float, width: float, dilating: bool = False) -> np.ndarray:
        return band.along(centres, self.polygon(size), width)

    def gathering_at(self, size: float, dilating: bool) -> str:
        return ""


def sizing_for(config: Config, goal: Goal, flare: float, chase: float = 0.0) -> Sizing:
    """The outline family the goal takes (see :mod:`sandbox.model.family`), for this flare and chase
    (chase lights its own band: an offset goal's notches are lit, and paced, in the open loop only)."""
    if goal.family == "offset":
        return OffsetSizing.of(config, goal, chase)
    return ScaledSizing.of(config, goal, flare)


def outline_shape(goal_relative: np.ndarray, goal_area: float, file_area: float, flare: float,
                  flare_mode: str) -> OutlineShape:
    """The outline at scale 1 for a goal polygon (relative to its centre) and a flare."""
    file_scale = math.sqrt(file_area / goal_area)
    convex = geometry.interior_angles(goal_relative) < 180.0
    if flare <= 0:
        return OutlineShape(goal_relative, convex, goal_relative, file_scale)
    if flare_mode == "on-goal":
        vertices, original = geometry.flare(goal_relative, flare)
        corners = np.zeros(len(vertices), dtype=bool)
        corners[original] = convex
        return OutlineShape(vertices, corners, goal_relative, file_scale)
    flared = program_flare(goal_relative, flare)
    to_goal_area = math.sqrt(goal_area / abs(geometry.signed_area(flared)))
    vertices = flared * to_goal_area
    corners = geometry.interior_angles(vertices) < 180.0
    return OutlineShape(vertices, corners, vertices, file_scale / to_goal_area)


def program_flare(relative: np.ndarray, amount: float) -> np.ndarray:
    """The authors' program's flare: after every vertex insert the midpoint of
    its edge to the next, then push every original vertex away from the
    centre by ``max(1, 90 * amount / angle)``, ``angle`` being the angle
    between its two edges in whole degrees (so reflex corners are pushed too)."""
    v = np.asarray(relative, dtype=float)
    to_prev = v - np.roll(v, 1, axis=0)
    to_next = v - np.roll(v, -1, axis=0)
    dot = (to_prev * to_next).sum(axis=1)
    cross = to_prev[:, 0] * to_next[:, 1] - to_prev[:, 1] * to_next[:, 0]
    angle = np.abs(np.floor(np.degrees(np.arctan2(cross, dot)) + 0.5))
    factor = np.maximum(1.0, 90.0 * amount / np.maximum(angle, 1.0))
    out = np.empty((2 * len(v), 2))
    out[0::2] = v * factor[:, None]
    out[1::2] = 0.5 * (v + np.roll(v, -1, axis=0))  # midpoints of the edges before flaring
    return out


def min_polygon_scale(config: Config, shape: OutlineShape, goal_radius: float) -> float:
    """Smallest scale of a polygon outline (see the module docstring)."""
    gap = 2.0 * config.robot_radius
    if config.min_size_rule == "inradius":
        return (shape.inradius + gap) / shape.inradius
    return (goal_radius + gap) / goal_radius


def max_polygon_scale(config: Config, shape: OutlineShape, goal_area: float) -> float:
    """Largest scale of a polygon outline (see the module docstring)."""
    arena = config.arena_size
    reach = np.abs(shape.sized).max()
    if config.polygon_max_rule == "fit":
        by_area = math.sqrt(config.polygon_max_area * arena**2 / goal_area)
        by_fit = (arena / 2.0 - config.light_pitch) / reach
        return min(by_area, by_fit)
    # Grow the file's polygon by 1.05 while it covers less than the target
    # area and stays strictly inside the arena; the step that fails is kept.
    file_area, file_reach = goal_area * shape.file_scale**2, reach * shape.file_scale
    target = config.polygon_max_area * arena**2
    growth = PROGRAM_GROWTH_STEP
    while True:
        file_area *= PROGRAM_GROWTH_STEP**2
        file_reach *= PROGRAM_GROWTH_STEP
        if file_area >= target or file_reach >= arena / 2.0:
            return growth * shape.file_scale
        growth *= PROGRAM_GROWTH_STEP


def max_circle_radius(config: Config) -> float:
    """The largest radius of a circle: ``circle_max`` of half the arena."""
    return config.circle_max * config.arena_size / 2.0


def max_circle_scale(config: Config, goal_radius: float) -> float:
    return max_circle_radius(config) / goal_radius


def overreach(config: Config, outline: np.ndarray) -> tuple[float, float, float, float] | None:
    """The outline's bounding box (x0, x1, y0, y1) if it reaches past the arena walls, else None."""
    (x0, y0), (x1, y1) = outline.min(axis=0), outline.max(axis=0)
    edge = 1e-9
    if x0 < -edge or y0 < -edge or x1 > config.arena_size + edge or y1 > config.arena_size + edge:
        return float(x0), float(x1), float(y0), float(y1)
    return None


def describe_box(box: tuple[float, float, float, float]) -> str:
    x0, x1, y0, y1 = box
    return f"x = {x0:.0f} .. {x1:.0f} m, y = {y0:.0f} .. {y1:.0f} m"
