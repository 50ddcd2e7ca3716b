"""The paper's controller, Algorithm 1 (SPEC §5): contract, hold, dilate.

A band of lights follows an outline: the goal, or a circle, at a size
(:mod:`sandbox.model.outlines` gives the outline of each size, and the
smallest and largest; today the goal scaled about the assembly centre, the
size being the scale, 1 the goal itself, whose area equals the boxes'). The
size shrinks by ``scale_rate`` every ``update_every`` steps down to the
smallest, holds there for ``hold_steps``, grows back to the largest, and the
cycle repeats. Three strategies change what is lit: *flare* pushes the
outline's corners out, *switch* lights a circle in its place while it is
large, *no corners* darkens the band's lights nearest its convex corners.

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

This controller looks at nothing: what it lights never depends on the robots
or the boxes. A strategy that looks subclasses it and overrides its hooks:
where a dilation turns (:meth:`Cycle._turn_radius`, :meth:`Cycle._turns_early`),
how long the smallest outline is held (:meth:`Cycle._start_hold`,
:meth:`Cycle._hold_step`, :meth:`Cycle._end_hold`) and what is lit
(:meth:`Controller._redraw`). :class:`Cycle` is the schedule alone, lighting
nothing, and all it changes is a :class:`Schedule`: a copy of one can be run
ahead to see when the next hold comes.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import numpy as np

from sandbox.model import geometry
from sandbox.model.config import STRATEGY_NAMES, Config
from sandbox.model.goal import CIRCLE_DRAW_VERTICES, Goal, make_goal
from sandbox.model.lights import light_centres
from sandbox.model.notes import goal_fit_notes
from sandbox.model.outlines import ScaledSizing, Sizing
from sandbox.model.phases import CONTRACTING, DILATING, HOLDING

#: After holding, the authors' program grows a circle back by this much (its ``delta``, m).
PROGRAM_CIRCLE_REGROWTH = 0.6
_NOTHING_PENDING: Mapping[str, float] = MappingProxyType({})


@dataclass
class Schedule:
    """Where the controller is in its cycle: with the configuration and the goal,
    all its next sizes depend on. ``dataclasses.replace`` copies it: the sizing and
    the mappings are replaced when they change, never changed in place."""

    sizing: Sizing  # the outline family for the strategies applied now
    strategies: Mapping[str, float]  # as applied now
    pending: Mapping[str, float]  # set live, applied at the next update
    scale: float  # the outline's size
    phase: str = CONTRACTING
    circle_radius: float | None = None  # the circle lit in the polygon's place (switch_mode 'inradius')
    cycle: int = 0  # completed contract -> hold -> dilate cycles
    updates: int = 0
    until_update: int = 0  # world steps to the next update
    hold_left: int = 0  # world steps the hold has left

    @classmethod
    def start(cls, config: Config, goal: Goal) -> "Schedule":
        """A new cycle's: contracting from the largest size, the strategies as configured."""
        strategies = {name: getattr(config, name) for name in STRATEGY_NAMES}
        sizing = ScaledSizing.of(config, goal, strategies["flare"])
        return cls(sizing, MappingProxyType(strategies), _NOTHING_PENDING, sizing.largest,
                   until_update=config.update_every)


class _InSchedule:
    """An attribute of the cycle kept in its :class:`Schedule`."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, cycle: "Cycle | None", owner: type | None = None):
        return self if cycle is None else getattr(cycle.state, self.name)

    def __set__(self, cycle: "Cycle", value) -> None:
        setattr(cycle.state, self.name, value)


class Cycle:
    """Algorithm 1's schedule, one world step at a time (:meth:`advance`): sizes and
    phases, lighting nothing (:class:`Controller` lights them)."""

    phase, scale, circle_radius, cycle, updates = _InSchedule(), _InSchedule(), _InSchedule(), _InSchedule(), _InSchedule()

    def __init__(self, config: Config, goal: Goal, state: Schedule):
        self.config, self.goal, self.state = config, goal, state

    # -- sizes ------------------------------------------------------------
    @property
    def sizing(self) -> Sizing:
        return self.state.sizing

    @property
    def strategies(self) -> Mapping[str, float]:
        return self.state.strategies

    @property
    def shape(self):
        """The outline at scale 1 (None for the circle)."""
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
        s = self.state
        return s.circle_radius if s.circle_radius is not None else s.sizing.radius(s.scale)

    @property
    def max_radius(self) -> float:
        """The largest inradius (radius for a circle) the lit outline may have now."""
        if self.state.circle_radius is not None:
            return self.circle_max_radius
        return self.sizing.radius(self.sizing.largest)

    @property
    def circle_max_radius(self) -> float:
        return self.config.circle_max * self.config.arena_size / 2.0

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

    @property
    def _program(self) -> bool:
        return self.config.size_schedule == "program"

    # -- live changes -----------------------------------------------------
    def reconfigure(self, config: Config) -> None:
        """Take new controller values (rate, band, sizes...) keeping the phase
        and a scale within the new limits; the pattern is redrawn at once."""
        self.config, s = config, self.state
        self._resize()
        s.until_update = min(s.until_update, config.update_every)
        if config.switch_mode != "inradius":
            s.circle_radius = None
        self._redraw()

    def set_strategies(self, **values: float) -> None:
        """Change strategies (flare, switch, no_corners...); applied at the next controller update."""
        unknown = set(values) - set(self.strategies)
        if unknown:
            raise ValueError(f"unknown strategies: {sorted(unknown)}")
        self.state.pending = MappingProxyType({**self.state.pending, **values})

    def _take_pending_strategies(self) -> None:
        s = self.state
        if not s.pending:
            return
        flare_changed = s.pending.get("flare", s.strategies["flare"]) != s.strategies["flare"]
        s.strategies, s.pending = MappingProxyType({**s.strategies, **s.pending}), _NOTHING_PENDING
        if flare_changed:
            self._resize()
        if s.strategies["switch"] <= 0:
            s.circle_radius = None

    def _resize(self) -> None:
        """The outline family for the configuration and strategies now; the scale kept within it."""
        s = self.state
        s.sizing = ScaledSizing.of(self.config, self.goal, s.strategies["flare"])
        s.scale = min(max(s.scale, s.sizing.smallest), s.sizing.largest)

    # -- time -------------------------------------------------------------
    def _begin(self) -> None:
        """The start: the largest size is lit (the authors' program steps from it at once)."""
        if self._program:
            self._program_update()
        else:
            self._redraw()

    def advance(self) -> bool:
        """One world step. Returns whether the light pattern may have changed."""
        s = self.state
        if s.phase == HOLDING:
            return self._hold_step()
        s.until_update -= 1
        if s.until_update > 0:
            return False
        return self._update()

    def _update(self) -> bool:
        s = self.state
        s.until_update = self.config.update_every
        s.updates += 1
        self._take_pending_strategies()
        if self._program:
            self._program_update()
            return True
        if s.circle_radius is not None:
            self._clamped_circle_step()
        else:
            self._clamped_step()
        self._switch_shape()
        self._redraw()
        return True

    # -- the hold (hooks) ---------------------------------------------------
    def _start_hold(self) -> None:
        """At the smallest size: hold for ``hold_steps`` (none: dilate at once).
        Hook: chase holds on while boxes keep arriving."""
        s = self.state
        s.phase = HOLDING if self.config.hold_steps > 0 else DILATING
        s.hold_left = self.config.hold_steps

    def _hold_step(self) -> bool:
        """One world step of holding; returns whether the pattern may have changed. Hook."""
        s = self.state
        s.hold_left -= 1
        if s.hold_left > 0:
            return False
        return self._end_hold()

    def _end_hold(self) -> bool:
        """Let go of the smallest outline: dilate from the next size. Hook."""
        self.state.phase = DILATING
        if self._program:
            self._grow_back()
        return self._update()

    # -- where a dilation turns (hooks) ---------------------------------------
    def _turn_radius(self) -> float:
        """The inradius (radius for a circle) at which dilation turns: the largest.
        Hook: chase turns as soon as the outline is beyond the farthest stray box."""
        return self.max_radius

    def _turns_early(self) -> bool:
        """Whether a dilation turns at this update whatever its size: never. Hook:
        chase turns in time for the step its run is measured at."""
        return False

    def _turn_to_contracting(self) -> None:
        self.state.phase = CONTRACTING
        self.state.cycle += 1

    # -- the paper text's schedule ------------------------------------------
    def _clamped_step(self) -> None:
        s, rate = self.state, self.config.scale_rate
        if s.phase == CONTRACTING:
            s.scale = s.sizing.step(s.scale, rate)
            if s.scale <= s.sizing.smallest:
                s.scale = s.sizing.smallest
                self._start_hold()
        elif s.phase == DILATING:
            s.scale = s.sizing.step_back(s.scale, rate)
            if s.scale >= s.sizing.largest:
                s.scale = s.sizing.largest
                self._turn_to_contracting()
            elif self.inradius >= self._turn_radius() or self._turns_early():
                self._turn_to_contracting()

    def _clamped_circle_step(self) -> None:
        """The circle lit in the polygon's place (switch_mode 'inradius') under
        the clamped schedule: it turns at the circle's largest size; the
        polygon returns below the switch threshold (see _switch_shape)."""
        s, rate = self.state, self.config.scale_rate
        if s.phase == CONTRACTING:
            s.circle_radius *= rate
        else:
            s.circle_radius = min(s.circle_radius / rate, self.circle_max_radius)
            if s.circle_radius >= self.circle_max_radius or self._turns_early():
                self._turn_to_contracting()

    # -- the authors' program's schedule ------------------------------------
    def _program_update(self) -> None:
        """One update of the program's main loop: light the current size, then
        step it (see the module docstring)."""
        s, rate = self.state, self.config.scale_rate
        if self.inradius < self.min_radius and s.phase == CONTRACTING:
            # First size below the smallest: lit while holding, then grown back.
            self._start_hold()
            self._redraw()
            if s.phase == DILATING:
                self._grow_back()
                self._program_update()
            return
        if s.phase == DILATING and (self.inradius > self._turn_radius() * (1 + 1e-12) or self._turns_early()):
            # First size above the largest (or the last that can come back in time):
            # not lit; turn and shrink from it.
            self._turn_to_contracting()
            self._step_size(rate)
            return
        self._switch_shape()
        self._redraw()
        self._step_size(rate if s.phase == CONTRACTING else 2.0 - rate)

    def _switch_shape(self) -> None:
        """switch_mode 'inradius': a circle in the polygon's place while it is large."""
        s = self.state
        if self.goal.is_circle or self.config.switch_mode != "inradius" or s.strategies["switch"] <= 0:
            return
        threshold = s.strategies["switch"] * self.config.arena_size / 2.0
        if s.circle_radius is None and s.phase == DILATING and self.inradius > threshold:
            s.circle_radius = self.inradius  # the polygon stays frozen at this scale
        elif s.circle_radius is not None and s.phase == CONTRACTING and s.circle_radius < threshold:
            s.circle_radius = None  # the frozen polygon returns

    def _step_size(self, factor: float) -> None:
        s = self.state
        if s.circle_radius is not None:
            s.circle_radius *= factor
        else:
            s.scale = s.sizing.step(s.scale, factor)

    def _grow_back(self) -> None:
        """After the hold: back to at least the smallest size (a circle goal by the program's 0.6 m)."""
        s = self.state
        if self.goal.is_circle:
            s.scale = s.sizing.widen(s.scale, PROGRAM_CIRCLE_REGROWTH)
            return
        grow = 2.0 - self.config.scale_rate
        while self.inradius < self.min_radius:
            self._step_size(grow)

    def _redraw(self) -> None:
        """Light the current outline: the cycle alone lights nothing."""


class Controller(Cycle):
    """The paper's controller: the cycle, lit as a band of lights along its outline.
    A light program (:mod:`sandbox.model.programs`) asked every world step."""

    #: Called every world step: the controller keeps its own update clock.
    every = 1
    #: The open loop looks at nothing.
    senses: frozenset = frozenset()

    def __init__(self, config: Config, goal: Goal):
        super().__init__(config, goal, Schedule.start(config, goal))
        self._centres = light_centres(config).reshape(-1, 2)
        self.outline = np.empty((0, 2))
        self.corners = np.empty((0, 2))
        self.intensities = np.zeros((config.lights_per_side,) * 2)
        #: Said about the goal's fit (its largest outline past the walls); a goal whose smallest
        #: outline does not fit is refused here with a ShapeError.
        self.notes = goal_fit_notes(config, self.sizing)
        self._begin()

    def reset(self, config: Config, goal: Goal) -> None:
        """Nothing to do: the simulation builds a new Controller for a new world."""

    def update(self, observation) -> np.ndarray | None:
        """One world step: the new pattern when it changed, else None (the open loop
        does not read the observation)."""
        return self.intensities if self.advance() else None

    # -- pattern (hook) -----------------------------------------------------
    def _redraw(self) -> None:
        """Recompute the outline and which lights are on. Hook: chase lights the goal
        grown, sculpted from what the boxes show."""
        goal, s = self.goal, self.state
        if self.is_circle:
            radius = s.circle_radius if s.circle_radius is not None else s.sizing.circle_radius(s.scale)
            self.outline = geometry.regular_polygon(radius, CIRCLE_DRAW_VERTICES, goal.centre)
            self.corners = np.empty((0, 2))
            on = np.abs(np.hypot(*(self._centres - goal.centre).T) - radius) <= self.config.band + 1e-9
        else:
            self.outline = s.sizing.polygon(s.scale)
            self.corners = s.sizing.corners(s.scale)
            on = self._band(self.outline)
            if s.strategies["no_corners"] > 0 and len(self.corners):
                on = self._darken_corners(on)
        self._light(on)

    def _band(self, outline: np.ndarray) -> np.ndarray:
        """Which lights are within the band of the outline (flat, a boolean each)."""
        return geometry.distance_to_outline(self._centres, outline) <= self.config.band + 1e-9

    def _light(self, on: np.ndarray) -> None:
        self.intensities = (on * self.config.light_intensity).reshape(self.intensities.shape)

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
    """World steps until the first contract-hold-dilate cycle ends, seeing nothing.
    Exact for the open loop, which never looks; a strategy that looks runs its own
    cycles (chase's turn sooner and hold longer), so for it this is an estimate."""
    ctrl = Controller(config, make_goal(config, vertices))
    steps = 0
    while ctrl.cycle == 0 and steps < limit:
        ctrl.advance()
        steps += 1
    return steps
