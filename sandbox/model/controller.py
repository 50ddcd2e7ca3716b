"""The open-loop light-field controller (SPEC §5, the paper's Algorithm 1).

A band of lights follows an outline (the goal polygon or a circle) scaled
about the assembly centre. The scale shrinks by ``scale_rate`` every
``update_every`` steps down to the smallest size, holds there for
``hold_steps``, grows back to the largest size, and the cycle repeats. The
controller never looks at robots or boxes.

``scale`` is measured relative to the outline at scale 1 (see
:mod:`sandbox.outlines`): for a plain polygon or the circle, the goal itself,
whose area equals the total area of the boxes.

Two schedules (``Config.size_schedule``):

* ``clamped`` (paper text): each update multiplies the scale by
  ``scale_rate`` (contracting) or its inverse (dilating) and clamps it to the
  smallest and largest sizes; the smallest is held ``hold_steps`` steps.
* ``program`` (the authors' program, ``main.cc``): each update lights the
  current size, then multiplies it by ``scale_rate`` (contracting) or
  ``2 - scale_rate`` (dilating). The first size found below the smallest is
  lit for ``hold_steps`` steps, then grown back to at least the smallest
  (a circle grows by a fixed 0.6 m, the program's ``delta``); the first size
  found above the largest is not lit: the scale turns and shrinks from it.

And two readings of *switch to circle* (``Config.switch_mode``):

* ``fraction`` (paper text): the outline is a circle of the goal's
  equal-area radius times the scale whenever it is at least ``switch`` of
  the way from the smallest to the largest size, both ways;
* ``inradius`` (the authors' program): only while dilating, once the
  polygon's inradius exceeds ``switch`` times half the arena (the program's
  fixed 8 m is 0.25 of 32 m), the polygon is frozen and a circle of that
  radius takes its place; the circle grows to the circle's largest size,
  contracts, and the frozen polygon returns once the circle's radius falls
  below the same threshold.

With *chase* (the closed loop) the controller also looks at the boxes: its
outline's geometry is :mod:`sandbox.model.sculpt`'s, and its plan for the
step a run is measured at is :mod:`sandbox.model.finish`'s.
"""

from __future__ import annotations

import numpy as np

from sandbox.model import geometry
from sandbox.model.config import STRATEGY_NAMES, Config
from sandbox.model.goal import CIRCLE_DRAW_VERTICES, Goal, make_goal
from sandbox.model.lights import light_centres
from sandbox.model.notes import goal_fit_notes
from sandbox.model.outlines import ScaledSizing
from sandbox.model.phases import CONTRACTING, DILATING, HOLDING

#: After holding, the authors' program grows a circle back by this much (its ``delta``, m).
PROGRAM_CIRCLE_REGROWTH = 0.6


class Controller:
    """State machine driving the light pattern. Call :meth:`advance` once per world step."""

    def __init__(self, config: Config, goal: Goal):
        self.config = config
        self.goal = goal
        self._centres = light_centres(config).reshape(-1, 2)
        self.strategies = {name: getattr(config, name) for name in STRATEGY_NAMES}
        self._pending: dict[str, float] = {}
        self._set_limits()
        self.scale = self.max_scale
        #: Radius of the circle lit in place of the polygon (switch_mode 'inradius'), else None.
        self.circle_radius: float | None = None
        self.phase = CONTRACTING
        self.cycle = 0  # completed contract -> hold -> dilate cycles
        self.updates = 0
        self._until_update = config.update_every
        self._hold_left = 0
        self.outline = np.empty((0, 2))
        self.corners = np.empty((0, 2))
        self.intensities = np.zeros((config.lights_per_side,) * 2)
        #: Said about the goal's fit (its largest outline past the walls); a goal whose smallest
        #: outline does not fit is refused here with a ShapeError.
        self.notes = goal_fit_notes(config, self.sizing)
        if self._program:
            self._program_update()
        else:
            self._redraw()

    @property
    def _program(self) -> bool:
        return self.config.size_schedule == "program"

    # -- sizes ------------------------------------------------------------
    def _set_limits(self) -> None:
        """The outline family for the current strategies."""
        self.sizing = ScaledSizing.of(self.config, self.goal, self.strategies["flare"])

    @property
    def shape(self):
        return self.sizing.shape

    @property
    def min_scale(self) -> float:
        return self.sizing.smallest

    @property
    def max_scale(self) -> float:
        return self.sizing.largest

    @property
    def min_radius(self) -> float:
        """The smallest outline's inradius (its radius for a circle)."""
        return self.sizing.radius(self.sizing.smallest)

    @property
    def inradius(self) -> float:
        """The lit outline's inradius (its radius for a circle)."""
        if self.circle_radius is not None:
            return self.circle_radius
        return self.sizing.radius(self.scale)

    @property
    def max_radius(self) -> float:
        """The largest inradius (radius for a circle) the lit outline may have now."""
        if self.circle_radius is not None:
            return self.circle_max_radius
        return self.sizing.radius(self.sizing.largest)

    @property
    def circle_max_radius(self) -> float:
        cfg = self.config
        return cfg.circle_max * cfg.arena_size / 2.0

    @property
    def progress(self) -> float:
        """How far the scale is from smallest (0) to largest (1)."""
        span = self.max_scale - self.min_scale
        return 0.0 if span <= 0 else (self.scale - self.min_scale) / span

    @property
    def is_circle(self) -> bool:
        """Whether the lit outline is currently a circle."""
        if self.goal.is_circle or self.circle_radius is not None:
            return True
        switch = self.strategies["switch"]
        return self.config.switch_mode == "fraction" and switch > 0 and self.progress >= switch - 1e-12

    # -- live changes -----------------------------------------------------
    def reconfigure(self, config: Config) -> None:
        """Take new controller values (rate, band, sizes...) keeping the phase
        and a scale within the new limits; the pattern is redrawn at once."""
        self.config = config
        self._set_limits()
        self.scale = min(max(self.scale, self.min_scale), self.max_scale)
        self._until_update = min(self._until_update, config.update_every)
        if self.config.switch_mode != "inradius":
            self.circle_radius = None
        self._redraw()

    def set_strategies(self, **values: float) -> None:
        """Change flare / switch / no_corners; applied at the next controller update."""
        unknown = set(values) - set(self.strategies)
        if unknown:
            raise ValueError(f"unknown strategies: {sorted(unknown)}")
        self._pending.update(values)

    def _take_pending_strategies(self) -> None:
        if not self._pending:
            return
        flare_changed = self._pending.get("flare", self.strategies["flare"]) != self.strategies["flare"]
        self.strategies.update(self._pending)
        self._pending.clear()
        if flare_changed:
            self._set_limits()
            self.scale = min(max(self.scale, self.min_scale), self.max_scale)
        if self.strategies["switch"] <= 0:
            self.circle_radius = None

    # -- the light-program interface (sandbox.model.programs) ---------------
    #: Called every world step: the controller keeps its own update clock.
    every = 1

    #: The open loop looks at nothing.
    senses: frozenset = frozenset()

    def reset(self, config: Config, goal: Goal) -> None:
        """Nothing to do: the simulation builds a new Controller for a new world."""

    def update(self, observation) -> np.ndarray | None:
        """One world step: the new pattern when it changed, else None."""
        return self.intensities if self.advance() else None

    # -- time -------------------------------------------------------------
    def advance(self) -> bool:
        """One world step. Returns whether the light pattern may have changed."""
        if self.phase == HOLDING:
            return self._hold_step()
        self._until_update -= 1
        if self._until_update > 0:
            return False
        return self._update()

    # -- the hold (hooks: a strategy may hold on) ---------------------------
    def _start_hold(self) -> None:
        """At the smallest size: hold for ``hold_steps`` (none: dilate at once)."""
        self.phase = HOLDING if self.config.hold_steps > 0 else DILATING
        self._hold_left = self.config.hold_steps

    def _hold_step(self) -> bool:
        """One world step of holding; returns whether the pattern may have changed."""
        self._hold_left -= 1
        if self._hold_left > 0:
            return False
        return self._end_hold()

    def _end_hold(self) -> bool:
        self.phase = DILATING
        if self._program:
            self._grow_back()
        return self._update()

    def _update(self) -> bool:
        self._until_update = self.config.update_every
        self.updates += 1
        self._take_pending_strategies()
        if self._program:
            self._program_update()
            return True
        if self.circle_radius is not None:
            self._clamped_circle_step()
        else:
            self._clamped_step()
        self._switch_shape()
        self._redraw()
        return True

    # -- the paper text's schedule ------------------------------------------
    def _clamped_step(self) -> None:
        rate = self.config.scale_rate
        if self.phase == CONTRACTING:
            self.scale *= rate
            if self.scale <= self.min_scale:
                self.scale = self.min_scale
                self._start_hold()
        elif self.phase == DILATING:
            self.scale /= rate
            if self.scale >= self.max_scale:
                self.scale = self.max_scale
                self._turn_to_contracting()
            elif self.inradius >= self._turn_radius() or self._turns_early():
                self._turn_to_contracting()

    def _clamped_circle_step(self) -> None:
        """The circle lit in the polygon's place (switch_mode 'inradius') under
        the clamped schedule: it turns at the circle's largest size; the
        polygon returns below the switch threshold (see _switch_shape)."""
        rate = self.config.scale_rate
        if self.phase == CONTRACTING:
            self.circle_radius *= rate
        else:
            self.circle_radius = min(self.circle_radius / rate, self.circle_max_radius)
            if self.circle_radius >= self.circle_max_radius or self._turns_early():
                self._turn_to_contracting()

    def _turn_radius(self) -> float:
        """The inradius (radius for a circle) at which dilation turns: the largest.
        Hook: chase turns as soon as the outline is beyond the farthest stray box."""
        return self.max_radius

    def _turns_early(self) -> bool:
        """Whether a dilation turns at this update whatever its size: never. Hook:
        chase turns in time for the step its run is measured at."""
        return False

    def _turn_to_contracting(self) -> None:
        self.phase = CONTRACTING
        self.cycle += 1

    # -- the authors' program's schedule ------------------------------------
    def _program_update(self) -> None:
        """One update of the program's main loop: light the current size, then
        step it (see the module docstring)."""
        rate = self.config.scale_rate
        if self.inradius < self.min_radius and self.phase == CONTRACTING:
            # First size below the smallest: lit while holding, then grown back.
            self._start_hold()
            self._redraw()
            if self.phase == DILATING:
                self._grow_back()
                self._program_update()
            return
        if self.phase == DILATING and (self.inradius > self._turn_radius() * (1 + 1e-12)
                                       or self._turns_early()):
            # First size above the largest (or the last that can come back in time):
            # not lit; turn and shrink from it.
            self._turn_to_contracting()
            self._step_size(rate)
            return
        self._switch_shape()
        self._redraw()
        self._step_size(rate if self.phase == CONTRACTING else 2.0 - rate)

    def _switch_shape(self) -> None:
        """switch_mode 'inradius': a circle in the polygon's place while it is large."""
        if self.goal.is_circle or self.config.switch_mode != "inradius" or self.strategies["switch"] <= 0:
            return
        threshold = self.strategies["switch"] * self.config.arena_size / 2.0
        if self.circle_radius is None and self.phase == DILATING and self.inradius > threshold:
            self.circle_radius = self.inradius  # the polygon stays frozen at this scale
        elif self.circle_radius is not None and self.phase == CONTRACTING and self.circle_radius < threshold:
            self.circle_radius = None  # the frozen polygon returns

    def _step_size(self, factor: float) -> None:
        if self.circle_radius is not None:
            self.circle_radius *= factor
        else:
            self.scale *= factor

    def _grow_back(self) -> None:
        """After the hold: back to at least the smallest size (a circle goal by the program's 0.6 m)."""
        if self.goal.is_circle:
            self.scale = self.sizing.widen(self.scale, PROGRAM_CIRCLE_REGROWTH)
            return
        grow = 2.0 - self.config.scale_rate
        while self.inradius < self.min_radius:
            self._step_size(grow)

    # -- pattern ----------------------------------------------------------
    def _redraw(self) -> None:
        """Recompute the outline and which lights are on."""
        cfg, goal = self.config, self.goal
        if self.is_circle:
            radius = self.circle_radius if self.circle_radius is not None else goal.radius * self.scale
            self.outline = geometry.regular_polygon(radius, CIRCLE_DRAW_VERTICES, goal.centre)
            self.corners = np.empty((0, 2))
            dist = np.abs(np.hypot(*(self._centres - goal.centre).T) - radius)
            on = dist <= cfg.band + 1e-9
        else:
            self.outline = self.sizing.polygon(self.scale)
            self.corners = self.sizing.corners(self.scale)
            on = geometry.distance_to_outline(self._centres, self.outline) <= cfg.band + 1e-9
            if self.strategies["no_corners"] > 0 and len(self.corners):
                on = self._darken_corners(on)
        self.intensities = (on * cfg.light_intensity).reshape(self.intensities.shape)

    def _darken_corners(self, on: np.ndarray) -> np.ndarray:
        """The no-corners strategy: switch off the band lights nearest convex corners."""
        lit = np.flatnonzero(on)
        off = no_corners_count(self.strategies["no_corners"], len(lit), self.config.no_corners_count)
        if off == 0:
            return on
        if self.config.no_corners_count == "at-least":
            # The program breaks ties by its light index, x + y * n (lit lists ix * n + iy).
            n = self.config.lights_per_side
            lit = lit[np.argsort((lit % n) * n + lit // n, kind="stable")]
        d = np.hypot(*(self._centres[lit, None, :] - self.corners[None, :, :]).transpose(2, 0, 1)).min(axis=1)
        on = on.copy()
        # Rounded so that equally near lights tie exactly, whatever order the
        # file lists its vertices in; ties then go by light index.
        on[lit[np.argsort(np.round(d, 9), kind="stable")[:off]]] = False
        return on


def no_corners_count(fraction: float, lit: int, rule: str) -> int:
    """How many of ``lit`` lights the no-corners strategy turns off."""
    if rule == "round":
        return int(round(fraction * lit))
    # The program turns lights off while (turned off) / lit < fraction.
    off = 0
    while off < lit and off / lit < fraction:
        off += 1
    return off


def first_cycle_steps(config: Config, vertices: np.ndarray | None, limit: int = 10**7) -> int:
    """World steps until the first contract-hold-dilate cycle ends (the
    controller alone: it never looks at robots or boxes, so this is exact)."""
    ctrl = Controller(config, make_goal(config, vertices))
    steps = 0
    while ctrl.cycle == 0 and steps < limit:
        ctrl.advance()
        steps += 1
    return steps
