"""Chase's plan for the step a run is measured at.

A run of fixed length is measured at its last step, and the fraction in the
goal is highest while the smallest outline is held. So the closed loop
plans for that step (:func:`hold_for_the_end` says when a hold goes on):

* **Counting a cycle.** How long the next cycle (out to the farthest stray
  box, back, and the shortest hold) takes is counted by a :class:`Rehearsal`:
  the controller's cycle run ahead from a copy of its schedule state, lighting
  nothing and without a deadline, on the boxes as they are now. The count is
  exact for the schedule, whatever it is (the program's overshoot, a circle
  switched in). The boxes do not stay still: a dilation drags some out and
  turns later, so the count is stretched by the most a real cycle has overrun
  one in this run (:class:`EndPlan`).
* **Turning in time.** Each dilation near the end turns as soon as waiting
  one more update would bring the contraction back with less than the
  shortest hold to spare. The contraction never looks at the boxes, so a
  rehearsal made to turn counts it exactly.

An open-ended run (the live app's) has no deadline and plans nothing.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Protocol

import numpy as np

from sandbox.model.chase.sight import turn_radius
from sandbox.model.chase.tuning import Sculpting
from sandbox.model.config import Config
from sandbox.model.controller import Cycle
from sandbox.model.goal import Goal
from sandbox.model.phases import HOLDING
from sandbox.model.schedule import Schedule


@dataclasses.dataclass
class EndPlan:
    """What chase learns in a run about how long its cycles take."""

    #: The step the last hold let go at.
    released_at: int | None = None
    #: Steps a rehearsal counted from letting go of this hold to the next (counted once per hold).
    predicted: int | None = None
    #: The longest a cycle ran in this run, as a multiple of the rehearsal's count (at least 1).
    overrun: float = 1.0

    def hold_started(self, step: int) -> None:
        """A hold starts at ``step``: the cycle that led to it is measured against its count."""
        if self.released_at is not None and self.predicted:
            ran = step - self.released_at
            self.overrun = max(self.overrun, ran / self.predicted)
        self.predicted = None


class Chasing(Protocol):
    """What the plan reads of a chase controller (:class:`sandbox.model.chase.controller.ChaseController`,
    a :class:`Cycle`, which imports this module: named here by what it offers, so the two do not import
    each other)."""

    config: Config
    goal: Goal
    state: Schedule
    #: The last observation with the boxes (its ``box_positions`` and ``step``), or None.
    seen: Any
    sculpting: Sculpting
    plan: EndPlan
    inradius: float
    min_radius: float


@dataclasses.dataclass(frozen=True)
class _Still:
    """The boxes as they were when a rehearsal began (all of an observation it reads)."""

    box_positions: np.ndarray


class Rehearsal(Cycle):
    """A chase controller's cycle run ahead from a copy of its schedule state, on
    the boxes as they are now, to count steps: it lights nothing, has no deadline
    and stops when its next hold starts. The controller is left as it was."""

    def __init__(self, chase: Chasing):
        super().__init__(chase.config, chase.goal, dataclasses.replace(chase.state))
        self._seen = _Still(np.array(chase.seen.box_positions))
        self._turn = False  # turn at the next dilation update whatever the sizes say

    def _turn_radius(self) -> float:
        return turn_radius(self, self._seen)

    def _turns_early(self) -> bool:
        turn, self._turn = self._turn, False
        return turn

    def after_letting_go(self, limit: int) -> int:
        """World steps from letting go of the hold now until the next one starts (at most ``limit``)."""
        self._end_hold()
        return self._until_hold(limit)

    def after_turning(self, limit: int) -> int:
        """World steps until the next hold if its first update turns the dilation (at most ``limit``)."""
        self._turn = True
        self._update()
        return self._until_hold(limit)

    def _until_hold(self, limit: int) -> int:
        steps = 0
        while self.phase != HOLDING and steps < limit:
            self.advance()
            steps += 1
        return steps


def steps_to_next_hold(chase: Chasing, limit: int) -> int:
    """World steps from letting go of this hold until the next one starts (at most
    ``limit``), rehearsed on the boxes as they are now. Exact for the schedule,
    whatever it is (the program's overshoot, a circle switched in that grows
    farther than the polygon would); boxes that move while it runs can still make
    the real cycle longer or shorter."""
    return Rehearsal(chase).after_letting_go(limit)


def steps_back_if_turning_now(chase: Chasing, limit: int) -> int:
    """World steps until the next hold if the dilation turned at this update (at most
    ``limit``). The contraction does not look at the boxes, so this is exact."""
    return Rehearsal(chase).after_turning(limit)


def contraction_steps_at_most(cycle: Cycle | Chasing) -> int:
    """An upper bound on the steps from turning now to the next hold: the inradius
    shrinks by ``scale_rate`` per update from where it is to below the smallest;
    a circle switched in contracts to the switch threshold, where the polygon
    frozen a size above it returns (one update more), and each schedule may take
    one more update to see it is there."""
    rate = cycle.config.scale_rate
    updates = math.log(max(cycle.inradius, cycle.min_radius) / cycle.min_radius) / -math.log(rate)
    return cycle.config.update_every * (math.ceil(updates) + 3)


def shortest_hold(chase: Chasing) -> int:
    """The fewest steps the closed loop holds the smallest outline."""
    return max(chase.config.hold_steps, chase.sculpting.check)


def shortest_cycle(chase: Chasing) -> int:
    """The fewest steps left for which a hold still lets go (its dilation turning back
    in time): the shortest hold and ten updates, five out and five back (on the
    circle's smallest outline, about 0.7 m out)."""
    return shortest_hold(chase) + 10 * chase.config.update_every


def keeps_holding(chase: Chasing, left: int) -> bool:
    """Whether a hold that would let go now, ``left`` steps before the run is measured,
    goes on (see :func:`hold_for_the_end`)."""
    plan = chase.plan
    if plan.predicted is None:
        plan.predicted = steps_to_next_hold(chase, limit=left + 1)
    # A rehearsal keeps the boxes still, but a dilation drags boxes out and turns later:
    # cycles ran up to 1.9 times its count (with switch; the circle 0.93-1.16).
    # So the count is stretched by the most this run has seen.
    cycle = math.ceil(plan.predicted * plan.overrun) + shortest_hold(chase)
    return hold_for_the_end(left, cycle, shortest_cycle(chase))


def turns_for_the_deadline(chase: Chasing, left: int) -> bool:
    """Whether a dilation turns now, ``left`` steps before the run is measured,
    wherever the farthest box is, so that the contraction is back on the smallest
    outline, with the shortest hold to spare, when the run is measured. Turning one
    update later would cost about two updates (one more out, one more back). Without
    it the last cycle could only be planned from its start, and a dilation that
    dragged boxes out overran the plan."""
    margin = 2 * chase.config.update_every + shortest_hold(chase)
    if contraction_steps_at_most(chase) + margin <= left:
        return False  # far enough from the deadline to skip counting
    return steps_back_if_turning_now(chase, limit=left + 1) + margin > left


def hold_for_the_end(left: int, cycle: int, least: int) -> bool:
    """Whether a hold that would let go now goes on, ``left`` steps before the run is
    measured, when one more cycle (out, back and the shortest hold) takes ``cycle``
    steps. When one fits but not two, until exactly one does, so that the last cycle
    sweeps the far boxes in just before the end. When none fits, it still lets go if
    ``least`` steps are left: the dilation turns back in time (see
    :func:`turns_for_the_deadline`), and a cut-short cycle fetches the boxes a long
    hold squeezes out of the robots' crowd. With fewer, to the end."""
    if left < 0:
        return False
    if left < cycle:
        return left < least
    return left < 2 * cycle and left > cycle
