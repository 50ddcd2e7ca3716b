"""The goal region: the user's polygon (or a circle) fitted to the assembly
centre and to the boxes' total area (SPEC §4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sandbox.model import geometry
from sandbox.model.config import Config

#: Vertices of the polygon that stands for a circle when one is drawn or measured against.
CIRCLE_DRAW_VERTICES = 96


@dataclass(frozen=True)
class Goal:
    """The goal region in arena coordinates: a polygon, or a circle when ``vertices`` is None."""

    centre: np.ndarray
    area: float
    vertices: np.ndarray | None  # absolute, file order
    #: Area of the polygon as its file drew it (the program sizes outlines from it).
    file_area: float = 0.0

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


def make_goal(config: Config, vertices: np.ndarray | None) -> Goal:
    """Fit the user's polygon (or a circle) to the assembly centre and the boxes' total area.

    The fitted outline is simplified to a twentieth of a light pitch: far
    finer than a light can show, and a 10,000-vertex file then costs what a
    hand-drawn one does (every light and every box is measured against it)."""
    centre = np.full(2, config.centre)
    area = max(config.boxes, 1) * config.box_area
    if vertices is None:
        return Goal(centre, area, None)
    vertices = np.asarray(vertices, dtype=float)
    fitted = geometry.fit_to_area(vertices, area, centre)
    simpler = geometry.simplify(fitted, config.light_pitch / 20.0)
    if len(simpler) < len(fitted):
        fitted = geometry.fit_to_area(simpler, area, centre)  # simplifying nudges the area: refit
    return Goal(centre, area, fitted, abs(geometry.signed_area(vertices)))
