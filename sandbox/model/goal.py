"""The goal region: the user's polygon (or a circle) fitted to the assembly
centre and to the boxes' total area (SPEC §4), and kept where the boxes are.

The boxes start in, and never leave, the construction area: a square wall
stops them (robots pass it). A goal is fitted as the authors' program does,
its centroid on the assembly centre. A goal that, at the boxes' area,
cannot lie mostly inside the construction area cannot be built anywhere: it
is refused, with what would make it fit. :func:`inside_construction` finds the least move that
puts a goal inside the wall (a crescent's centroid lies near its hollow, so
centred it reaches past)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from sandbox.model import budget
from sandbox.model.config import Config
from sandbox.shapes import geometry
from sandbox.shapes.errors import ShapeError

#: Vertices of the polygon that stands for a circle when one is drawn or measured against.
CIRCLE_DRAW_VERTICES = 96
#: A goal is refused when, centred between the construction walls, less than this share of it lies inside.
MOSTLY_INSIDE = 0.9
#: Every fitted goal is simplified within this share of a light pitch: far finer than a light can show.
SIMPLIFY_WITHIN = 1.0 / 20.0
#: A goal with more vertices than the outlines afford (sandbox.model.budget.MAX_GOAL_VERTICES) is
#: simplified within twice, four times... that, up to this share of a light pitch: the band's distance
#: to a light moves by at most a quarter of the lights' spacing, so it lights the same lights, or one
#: beside them.
SIMPLIFY_AT_MOST = 1.0 / 4.0


@dataclass(frozen=True)
class Goal:
    """The goal region in arena coordinates: a polygon, or a circle when ``vertices`` is None."""

    centre: np.ndarray
    area: float
    vertices: np.ndarray | None  # absolute, file order
    #: Area of the polygon as its file drew it (the program sizes outlines from it).
    file_area: float = 0.0
    #: How far the goal was moved off the assembly centre to lie inside the construction wall (m).
    moved: tuple[float, float] = (0.0, 0.0)
    #: The outline family the band follows ('scaled' or 'offset') and why (sandbox.model.family).
    family: str = "scaled"
    family_reason: str = ""
    #: How the goal was simplified to what the outlines afford, in words ('' when it was not).
    simplified: str = ""

    @property
    def is_circle(self) -> bool:
        return self.vertices is None

    @property
    def radius(self) -> float:
        """Radius of the circle of the goal's area (the goal itself for a circle)."""
        return math.sqrt(self.area / math.pi)

    def outline(self) -> np.ndarray:
        """Vertices to draw or measure against (a fine polygon for a circle)."""
        if self.vertices is None:
            return geometry.regular_polygon(self.radius, CIRCLE_DRAW_VERTICES, self.centre)
        return self.vertices

    def contains(self, points: np.ndarray) -> np.ndarray:
        if self.vertices is None:
            return np.hypot(*(points - self.centre).T) <= self.radius
        return geometry.points_in_polygon(points, self.vertices)

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance to the nearest point of the goal region (0 inside)."""
        if self.vertices is None:
            return np.maximum(np.hypot(*(points - self.centre).T) - self.radius, 0.0)
        d = geometry.distance_to_outline(points, self.vertices)
        return np.where(self.contains(points), 0.0, d)


def fit_goal(config: Config, vertices: np.ndarray | None) -> Goal:
    """The user's polygon (or a circle) fitted, its centroid on the assembly centre (the family undecided)."""
    centre = np.full(2, config.centre)
    area = max(config.boxes, 1) * config.box_area
    if vertices is None:
        return Goal(centre, area, None)
    vertices = np.asarray(vertices, dtype=float)
    fitted = geometry.fit_to_area(vertices, area, centre)
    simpler, said = affordable_outline(config, fitted)
    if len(simpler) < len(fitted):
        fitted = geometry.fit_to_area(simpler, area, centre)  # simplifying nudges the area: refit
    check_fits_construction(config, fitted)
    check_goal_budget(config, fitted)
    return Goal(centre, area, fitted, abs(geometry.signed_area(vertices)), simplified=said)


def affordable_outline(config: Config, fitted: np.ndarray) -> tuple[np.ndarray, str]:
    """The fitted goal simplified within :data:`SIMPLIFY_WITHIN` of a light pitch, and what to say about
    it. One with more than :data:`sandbox.model.budget.MAX_GOAL_VERTICES` vertices left is simplified
    within twice that, four times..., up to :data:`SIMPLIFY_AT_MOST` of a pitch, until it has no more;
    then it is refused (a ShapeError, one line). Below the bound nothing changes: a goal of the
    paper's or any shape with fewer vertices comes out as it always did."""
    pitch, most = config.light_pitch, budget.MAX_GOAL_VERTICES
    tolerance = pitch * SIMPLIFY_WITHIN
    simpler = geometry.simplify(fitted, tolerance)
    below = tolerance
    while len(simpler) > most and tolerance < pitch * SIMPLIFY_AT_MOST:
        below, tolerance = tolerance, min(2.0 * tolerance, pitch * SIMPLIFY_AT_MOST)
        simpler = geometry.simplify(fitted, tolerance)
    if len(simpler) <= most < len(fitted) and tolerance > below:
        tolerance, simpler = _least_tolerance(fitted, below, tolerance, simpler, most)
    if len(simpler) > most:
        raise ShapeError(f"the goal has {len(fitted):,} vertices, and simplified within {tolerance:.2g} m (a quarter "
                         f"of the light pitch) still {len(simpler):,}: the outlines afford at most {most:,} (growing "
                         f"the goal at every update costs as the square of its vertices); use a smoother outline "
                         f"with fewer vertices")
    if len(fitted) <= most:
        return simpler, ""
    return simpler, f"simplified from {len(fitted):,} to {len(simpler):,} vertices within {tolerance:.2g} m"


def _least_tolerance(fitted: np.ndarray, too_fine: float, enough: float, simpler: np.ndarray,
                     most: int) -> tuple[float, np.ndarray]:
    """The goal kept as close as it can be: between a tolerance that leaves more than ``most`` vertices
    and one that does not (``simpler``), halved eight times (within 0.4 % of the least that does)."""
    for _ in range(8):
        middle = 0.5 * (too_fine + enough)
        tried = geometry.simplify(fitted, middle)
        if len(tried) <= most:
            enough, simpler = middle, tried
        else:
            too_fine = middle
    return enough, simpler


def check_goal_budget(config: Config, fitted: np.ndarray) -> None:
    """Refuse (ShapeError, one line) a goal whose outlines' work would take the world over the memory
    budget (sandbox.model.budget: its vertices grown at every update, the widths of a notched goal)."""
    if not budget.budget_checked():
        return
    width, height = np.ptp(fitted, axis=0)
    cost = budget.world_cost(config, len(fitted), float(width), float(height))
    limit = budget.memory_budget()
    if cost.total > limit:
        raise ShapeError(budget.goal_refusal(config, cost, limit, len(fitted)))


def check_fits_construction(config: Config, fitted: np.ndarray) -> None:
    """A ShapeError, with what would make it fit, when the goal is too large for the construction area:
    centred between its walls, less than :data:`MOSTLY_INSIDE` of its area would lie inside. (The paper
    text's star, 16.3 m across its tips with 16 m between the walls, is built all the same.)"""
    low, high = fitted.min(axis=0), fitted.max(axis=0)
    size = high - low
    if (size <= config.construction_size + 1e-9).all():
        return
    centred = fitted - (low + high) / 2.0 + config.centre
    half = config.construction_size / 2.0
    square = shapely.box(config.centre - half, config.centre - half, config.centre + half, config.centre + half)
    polygon = shapely.Polygon(centred)
    if polygon.intersection(square).area < MOSTLY_INSIDE * polygon.area:
        raise ShapeError(too_large(config, size))


def inside_construction(config: Config, fitted: np.ndarray) -> np.ndarray:
    """The least move (dx, dy) that puts the fitted goal inside the construction area, a box's
    circumradius clear of its wall where there is room (else centred between the walls); a
    ShapeError when the goal is larger than the area itself."""
    half, clear = config.construction_size / 2.0, config.box_circumradius
    check_fits_construction(config, fitted)
    low, high = fitted.min(axis=0), fitted.max(axis=0)
    size = high - low
    shift = np.zeros(2)
    for axis in range(2):
        wall_low, wall_high = config.centre - half, config.centre + half
        room = wall_high - wall_low - size[axis]
        margin = min(clear, room / 2.0)
        if low[axis] < wall_low + margin:
            shift[axis] = wall_low + margin - low[axis]
        elif high[axis] > wall_high - margin:
            shift[axis] = wall_high - margin - high[axis]
    return shift


def too_large(config: Config, size: np.ndarray) -> str:
    """Why a goal of this size (at the boxes' area) cannot be built, and what would make it fit."""
    side = config.construction_size
    fits = min(side / size[0], side / size[1]) ** 2  # the area scales with the square of the length
    boxes = int(config.boxes * fits)
    fewer = f"use at most {boxes:,} boxes, or " if boxes >= 1 else "use "
    return (f"at the boxes' total area ({config.boxes:,} boxes, {config.boxes * config.box_area:.0f} m²) the goal "
            f"is {size[0]:.1f} x {size[1]:.1f} m, larger than the {side:g} m construction area the boxes cannot "
            f"leave: {fewer}a less elongated shape (both sides at most {side:g} m)")
