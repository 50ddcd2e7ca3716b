"""The paper's controller, its Algorithm 1 (SPEC §5): contract, hold, dilate.

A band of lights follows an outline at a size (the outline family,
:mod:`sandbox.model.outlines`, gives the outline of each size; today's
scales the goal about the assembly centre). Every ``update_every`` steps
the size shrinks by ``scale_rate`` down to the smallest, is held there
``hold_steps`` steps, grows back to the largest, and the cycle repeats: in
the paper text's reading (:meth:`Cycle._clamped_step`) or the authors'
program's (:meth:`Cycle._program_update`). Flare reshapes the outline (in
its family), switch lights a circle in its place while it is large
(:meth:`Cycle._switch_shape`), no corners darkens the lights nearest its
convex corners (:mod:`sandbox.model.band`).

:class:`Cycle` is the state machine alone: it changes nothing but its
:class:`~sandbox.model.schedule.Schedule` and lights nothing, so a copy of
its state can be run ahead. :class:`Controller` lights it, and looks at
nothing: what it lights never depends on the robots or the boxes. A strategy
that looks subclasses it and overrides its hooks: where a dilation turns
(``_turn_radius``, ``_turns_early``), how long the smallest outline is held
(``_start_hold``, ``_hold_step``, ``_end_hold``) and what is lit (``_redraw``).
"""

from __future__ import annotations

import numpy as np

from sandbox.model import band, gather
from sandbox.model.config import Config
from sandbox.model.family import make_goal
from sandbox.model.goal import CIRCLE_DRAW_VERTICES, Goal
from sandbox.model.lights import light_centres
from sandbox.model.notes import goal_notes
from sandbox.model.phases import CONTRACTING, DILATING, HOLDING
from sandbox.model.schedule import InSchedule, Schedule
from sandbox.shapes import geometry

#: After holding, the authors' program grows a circle back by this much (its ``delta``, m).
PROGRAM_CIRCLE_REGROWTH = 0.6


class Cycle:
    """Algorithm 1's state machine, one world step at a time (:meth:`advance`): sizes
    and phases, lighting nothing. Its attributes below are its schedule's."""

    phase, scale, circle_radius, cycle, updates = InSchedule(), InSchedule(), InSchedule(), InSchedule(), InSchedule()
    sizing, strategies, progress = InSchedule(), InSchedule(), InSchedule()
    min_radius, inradius, max_radius = InSchedule(), InSchedule(), InSchedule()

    def __init__(self, config: Config, goal: Goal, state: Schedule):
        self.config, self.goal, self.state = config, goal, state

    # -- sizes ------------------------------------------------------------
    shape = property(lambda self: self.sizing.shape, doc="The outline at scale 1 (None for the circle).")
    min_scale = property(lambda self: self.sizing.smallest)
    max_scale = property(lambda self: self.sizing.largest)

    @property
    def is_circle(self) -> bool:
        """Whether the lit outline is now a circle: the goal's, or switched in. With
        switch_mode ``fraction`` (paper text), a circle of the goal's equal-area radius
        times the scale whenever the size is at least ``switch`` of the way from the
        smallest to the largest, both ways."""
        if self.goal.is_circle or self.circle_radius is not None:
            return True
        switch = self.strategies["switch"]
        return (self.config.switch_mode == "fraction" and switch > 0 and self.sizing.switchable
                and self.progress >= switch - 1e-12)

    @property
    def _program(self) -> bool:
        return self.config.size_schedule == "program"

    # -- live changes -----------------------------------------------------
    def reconfigure(self, config: Config) -> None:
        """Take new controller values (rate, band, sizes...) keeping the phase
        and a scale within the new limits; the pattern is redrawn at once."""
        self.config = config
        self.state.reconfigure(config, self.goal)
        self._redraw()

    def set_strategies(self, **values: float) -> None:
        """Change strategies (flare, switch, no_corners...); applied at the next controller update."""
        self.state.set_pending(values)

    # -- time -------------------------------------------------------------
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
        s.take_pending(self.config, self.goal)
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

    # -- the hold (hooks) -------------------------------------------------------
    def _start_hold(self) -> None:
        """At the smallest size: hold for ``hold_steps`` (none: dilate at once).
        Hook, with the next two: chase holds on while boxes keep arriving."""
        s = self.state
        s.phase = HOLDING if self.config.hold_steps > 0 else DILATING
        s.hold_left = self.config.hold_steps

    def _hold_step(self) -> bool:
        """One world step of holding; returns whether the pattern may have changed."""
        s = self.state
        s.hold_left -= 1
        if s.hold_left > 0:
            return False
        return self._end_hold()

    def _end_hold(self) -> bool:
        """Let go of the smallest outline and dilate."""
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
        self.state.phase, self.state.cycle = CONTRACTING, self.state.cycle + 1

    # -- the paper text's schedule ------------------------------------------
    def _clamped_step(self) -> None:
        """One update (size_schedule ``clamped``): the scale times ``scale_rate``
        contracting, over it dilating, clamped to the smallest (held ``hold_steps``)
        and the largest sizes."""
        s, rate = self.state, self.config.scale_rate
        if s.phase == CONTRACTING:
            s.scale = s.sizing.step(s.scale, rate)
            if s.scale <= s.sizing.smallest:
                s.scale = s.sizing.smallest
                self._start_hold()
        elif s.phase == DILATING:
            s.scale = s.sizing.step_back(s.scale, rate)
            if s.scale >= s.sizing.turn:
                s.scale = s.sizing.turn
                self._turn_to_contracting()
            elif s.inradius >= self._turn_radius() or self._turns_early():
                self._turn_to_contracting()

    def _clamped_circle_step(self) -> None:
        """The circle lit in the polygon's place (see _switch_shape) under the clamped
        schedule: it turns at the circle's largest size."""
        s, rate = self.state, self.config.scale_rate
        if s.phase == CONTRACTING:
            s.circle_radius *= rate
        else:
            s.circle_radius = min(s.circle_radius / rate, s.sizing.circle_largest)
            if s.circle_radius >= s.sizing.circle_largest or self._turns_early():
                self._turn_to_contracting()

    # -- the authors' program's schedule ------------------------------------
    def _program_update(self) -> None:
        """One update of the program's main loop (size_schedule ``program``, its
        ``main.cc``): light the current size, then step it by ``scale_rate``
        contracting, ``2 - scale_rate`` dilating. The first size found below the
        smallest is lit for ``hold_steps`` steps, then grown back to at least the
        smallest; the first found above the largest is not lit: it turns and shrinks."""
        s, rate = self.state, self.config.scale_rate
        if s.inradius < s.min_radius and s.phase == CONTRACTING:
            # First size below the smallest: lit while holding, then grown back.
            self._start_hold()
            self._redraw()
            if s.phase == DILATING:
                self._grow_back()
                self._program_update()
            return
        if s.phase == DILATING and (s.inradius > self._turn_radius() * (1 + 1e-12) or self._turns_early()):
            # First size above the largest (or the last that can come back in time):
            # not lit; turn and shrink from it.
            self._turn_to_contracting()
            self._step_size(rate)
            return
        self._switch_shape()
        self._redraw()
        self._step_size(rate if s.phase == CONTRACTING else 2.0 - rate)

    def _switch_shape(self) -> None:
        """switch_mode ``inradius`` (the authors' program): only while dilating, once
        the polygon's inradius exceeds ``switch`` times half the arena (the program's
        fixed 8 m is 0.25 of 32 m), the polygon is frozen and a circle of that radius
        takes its place; it grows to the circle's largest size, contracts, and the
        frozen polygon returns once its radius falls below the same threshold."""
        s = self.state
        if (self.goal.is_circle or self.config.switch_mode != "inradius" or s.strategies["switch"] <= 0
                or not s.sizing.switchable):
            return
        threshold = s.strategies["switch"] * self.config.arena_size / 2.0
        if s.circle_radius is None and s.phase == DILATING and s.inradius > threshold:
            s.circle_radius = s.inradius  # the polygon stays frozen at this scale
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
        while s.inradius < s.min_radius:
            self._step_size(grow)

    def _redraw(self) -> None:
        """Light the current outline: the state machine alone lights nothing."""


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
        #: The goal's sides beside which alone the band is lit now ('' the whole band; :mod:`sandbox.model.gather`).
        self.gathering = ""
        #: Said about the goal's fit (its largest outline past the walls); a goal whose smallest
        #: outline does not fit is refused here with a ShapeError.
        self.notes = goal_notes(config, goal, self.sizing)
        if self._program:  # the largest size is lit, and the program steps from it at once
            self._program_update()
        else:
            self._redraw()

    def reset(self, config: Config, goal: Goal) -> None:
        """Nothing to do: the simulation builds a new Controller for a new world."""

    def update(self, observation) -> np.ndarray | None:
        """One world step: the new pattern when it changed, else None (the observation is unread)."""
        return self.intensities if self.advance() else None

    def redraw(self) -> None:
        """Light the outline for the size and phase as they are now: for a caller that set them itself (the
        learn panel's pictures set the smallest size). Each step redraws on its own when they change."""
        self._redraw()

    def _redraw(self) -> None:
        """Recompute the outline and which lights are on. Hook: chase lights the goal
        grown, sculpted from what the boxes show."""
        s = self.state
        if self.is_circle:
            radius = s.circle_radius if s.circle_radius is not None else s.sizing.circle_radius(s.scale)
            self.outline = geometry.regular_polygon(radius, CIRCLE_DRAW_VERTICES, self.goal.centre)
            self.corners = np.empty((0, 2))
            on = band.around(self._centres, self.goal.centre, radius, self.config.band)
            self.gathering = ""
        else:
            self.outline, self.corners = s.sizing.polygon(s.scale), s.sizing.corners(s.scale)
            on = s.sizing.lit(self._centres, s.scale, self.config.band, dilating=s.phase == DILATING)
            self.gathering = s.sizing.gathering_at(s.scale, s.phase == DILATING)
            if s.strategies["no_corners"] > 0 and len(self.corners):
                on = self._darken_corners(on)
        self._light(on)

    @property
    def phase_said(self) -> str:
        """The phase in words, with the sides the band gathers the robots beside when it does (short: a
        phone's caption shows it on one line)."""
        if not self.gathering:
            return self.phase
        return f"{self.phase}, gathering beside {gather.said(self.gathering)}"

    def _darken_corners(self, on: np.ndarray) -> np.ndarray:
        return band.darken_corners(on, self._centres, self.corners, self.strategies["no_corners"], self.config)

    def _light(self, on: np.ndarray) -> None:
        self.intensities = (on * self.config.light_intensity).reshape(self.intensities.shape)


def first_cycle_steps(config: Config, vertices: np.ndarray | None, limit: int = 10**7) -> int:
    """World steps until the first contract-hold-dilate cycle ends, seeing nothing.
    Exact for the open loop, which never looks; a strategy that looks at the boxes
    runs its own cycles (turning sooner, holding longer): for it, an estimate."""
    ctrl = Controller(config, make_goal(config, vertices))
    steps = 0
    while ctrl.cycle == 0 and steps < limit:
        ctrl.advance()
        steps += 1
    return steps
