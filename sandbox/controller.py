"""The open-loop light-field controller (SPEC §5, the paper's Algorithm 1).

A band of lights follows an outline (the goal polygon or a circle) scaled
about the arena centre. The scale shrinks by ``scale_rate`` every
``update_every`` steps down to the smallest size, holds there for
``hold_steps``, grows back to the largest size, and the cycle repeats. The
controller never looks at robots or boxes.

``scale`` is measured relative to the goal: at scale 1 the outline is the
goal shape itself, whose area equals the total area of the boxes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import geometry
from .config import Config
from .lights import light_centres

CONTRACTING, HOLDING, DILATING = "contracting", "holding", "dilating"
CIRCLE_DRAW_VERTICES = 96


@dataclass(frozen=True)
class Goal:
    """The goal region in arena coordinates: a polygon, or a circle when ``vertices`` is None."""

    centre: np.ndarray
    area: float
    vertices: np.ndarray | None  # absolute, file order

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
    """Fit the user's polygon (or a circle) to the arena centre and the boxes' total area."""
    centre = np.full(2, config.arena_size / 2.0)
    area = max(config.boxes, 1) * config.box_area
    if vertices is None:
        return Goal(centre, area, None)
    return Goal(centre, area, geometry.fit_to_area(vertices, area, centre))


class Controller:
    """State machine driving the light pattern. Call :meth:`advance` once per world step."""

    def __init__(self, config: Config, goal: Goal):
        self.config = config
        self.goal = goal
        self._centres = light_centres(config).reshape(-1, 2)
        self._set_limits()
        self.scale = self.max_scale
        self.phase = CONTRACTING
        self.cycle = 0  # completed contract -> hold -> dilate cycles
        self.updates = 0
        self._until_update = config.update_every
        self._hold_left = 0
        self.strategies = dict(flare=config.flare, switch=config.switch, no_corners=config.no_corners)
        self._pending: dict[str, float] = {}
        self.outline = np.empty((0, 2))
        self.corners = np.empty((0, 2))
        self.intensities = np.zeros((config.lights_per_side,) * 2)
        self._redraw()

    # -- sizes ------------------------------------------------------------
    def _set_limits(self) -> None:
        """Smallest scale: the goal grown by one robot diameter; largest: see below."""
        self.min_scale = (self.goal.radius + 2.0 * self.config.robot_radius) / self.goal.radius
        self.max_scale = max(self._largest_scale(), self.min_scale)

    def _largest_scale(self) -> float:
        cfg, goal = self.config, self.goal
        if goal.is_circle:
            return cfg.circle_max * cfg.arena_size / 2.0 / goal.radius
        by_area = math.sqrt(cfg.polygon_max_area * cfg.arena_size**2 / goal.area)
        # Keep the goal shape (one light pitch clear of the wall) inside the arena.
        reach = np.abs(goal.vertices - goal.centre).max()
        by_fit = (cfg.arena_size / 2.0 - cfg.light_pitch) / reach
        return min(by_area, by_fit)

    @property
    def progress(self) -> float:
        """How far the scale is from smallest (0) to largest (1)."""
        span = self.max_scale - self.min_scale
        return 0.0 if span <= 0 else (self.scale - self.min_scale) / span

    @property
    def is_circle(self) -> bool:
        """Whether the lit outline is currently a circle."""
        switch = self.strategies["switch"]
        return self.goal.is_circle or (switch > 0 and self.progress >= switch - 1e-12)

    # -- live changes -----------------------------------------------------
    def reconfigure(self, config: Config) -> None:
        """Take new controller values (rate, band, sizes...) keeping the phase
        and a scale within the new limits; the pattern is redrawn at once."""
        self.config = config
        self._set_limits()
        self.scale = min(max(self.scale, self.min_scale), self.max_scale)
        self._until_update = min(self._until_update, config.update_every)
        self._redraw()

    def set_strategies(self, **values: float) -> None:
        """Change flare / switch / no_corners; applied at the next controller update."""
        unknown = set(values) - set(self.strategies)
        if unknown:
            raise ValueError(f"unknown strategies: {sorted(unknown)}")
        self._pending.update(values)

    # -- time -------------------------------------------------------------
    def advance(self) -> bool:
        """One world step. Returns whether the light pattern may have changed."""
        if self.phase == HOLDING:
            self._hold_left -= 1
            if self._hold_left > 0:
                return False
            self.phase = DILATING
            return self._update()
        self._until_update -= 1
        if self._until_update > 0:
            return False
        return self._update()

    def _update(self) -> bool:
        self._until_update = self.config.update_every
        self.updates += 1
        self.strategies.update(self._pending)
        self._pending.clear()
        rate = self.config.scale_rate
        if self.phase == CONTRACTING:
            self.scale *= rate
            if self.scale <= self.min_scale:
                self.scale = self.min_scale
                self.phase = HOLDING if self.config.hold_steps > 0 else DILATING
                self._hold_left = self.config.hold_steps
        elif self.phase == DILATING:
            self.scale /= rate
            if self.scale >= self.max_scale:
                self.scale = self.max_scale
                self.phase = CONTRACTING
                self.cycle += 1
        self._redraw()
        return True

    # -- pattern ----------------------------------------------------------
    def _redraw(self) -> None:
        """Recompute the outline and which lights are on."""
        cfg, goal = self.config, self.goal
        if self.is_circle:
            radius = goal.radius * self.scale
            self.outline = geometry.regular_polygon(radius, CIRCLE_DRAW_VERTICES, goal.centre)
            self.corners = np.empty((0, 2))
            dist = np.abs(np.hypot(*(self._centres - goal.centre).T) - radius)
            on = dist <= cfg.band + 1e-9
        else:
            relative = goal.vertices - goal.centre
            is_corner = geometry.interior_angles(relative) < 180.0
            if self.strategies["flare"] > 0:
                relative, original = geometry.flare(relative, self.strategies["flare"])
                convex = np.zeros(len(relative), dtype=bool)
                convex[original] = is_corner
                is_corner = convex
            self.outline = goal.centre + self.scale * relative
            self.corners = self.outline[is_corner]
            on = geometry.distance_to_outline(self._centres, self.outline) <= cfg.band + 1e-9
            if self.strategies["no_corners"] > 0 and len(self.corners):
                on = self._darken_corners(on)
        self.intensities = (on * cfg.light_intensity).reshape(self.intensities.shape)

    def _darken_corners(self, on: np.ndarray) -> np.ndarray:
        """The no-corners strategy: switch off the band lights nearest convex corners."""
        lit = np.flatnonzero(on)
        off = int(round(self.strategies["no_corners"] * len(lit)))
        if off == 0:
            return on
        d = np.hypot(*(self._centres[lit, None, :] - self.corners[None, :, :]).transpose(2, 0, 1)).min(axis=1)
        on = on.copy()
        # Rounded so that equally near lights tie exactly, whatever order the
        # file lists its vertices in; ties then go by light index.
        on[lit[np.argsort(np.round(d, 9), kind="stable")[:off]]] = False
        return on
