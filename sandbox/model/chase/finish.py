"""Chase's plan for the step a run is measured at (mixed into the Controller).

A run of fixed length is measured at its last step, and the fraction in the
goal is highest while the smallest outline is held. So the closed loop
plans for that step (:func:`sculpt.hold_for_the_end` says when a hold goes
on):

* **Counting a cycle.** How long the next cycle (out to the farthest stray
  box, back, and the shortest hold) takes is counted by running a copy of
  the controller, undrawn and without a deadline, on the boxes as they are
  now. The count is exact for the schedule, whatever it is (the program's
  overshoot, a circle switched in). The boxes do not stay still: a dilation
  drags some out and turns later, so the count is stretched by the most a
  real cycle has overrun one in this run.
* **Turning in time.** Each dilation near the end turns as soon as waiting
  one more update would bring the contraction back with less than the
  shortest hold to spare. The contraction never looks at the boxes, so a
  copy forced to turn counts it exactly.

An open-ended run (the live app's) has no deadline and plans nothing.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from sandbox.model.chase import sculpt
from sandbox.model.phases import HOLDING


@dataclass(frozen=True)
class _Snapshot:
    """The part of an observation the controller reads, kept still (see EndPlanning._ghost)."""

    step: int
    box_positions: np.ndarray


class EndPlanning:
    """The Controller's closed-loop planning for its deadline (a mixin: it reads the
    controller's config, phase, sizes and observation, and runs copies of it)."""

    @property
    def deadline(self) -> int | None:
        """The step at which the run is measured (the closed loop plans its last cycle
        for it); None for an open-ended run."""
        return None if self.open_ended else self.config.steps

    def _steps_left(self) -> int | None:
        """Steps from the last observation to the deadline; None when there is nothing
        to plan for (an open-ended run, nothing observed yet, or the deadline passed)."""
        if self.deadline is None or self._observation is None:
            return None
        left = self.deadline - self._observation.step
        return left if left >= 0 else None

    @property
    def _shortest_hold(self) -> int:
        """The fewest steps the closed loop holds the smallest outline."""
        return max(self.config.hold_steps, self.sculpting.check)

    def _finish_in_hold(self) -> bool:
        """Whether a hold that would let go now goes on, planning for the step the run is
        measured at (see :func:`sculpt.hold_for_the_end`)."""
        left = self._steps_left()
        if left is None:
            return False
        if self._predicted is None:
            self._predicted = self._steps_to_next_hold(limit=left + 1)
        # The copy keeps the boxes still, but a dilation drags boxes out and turns later:
        # cycles ran up to 1.9 times the copy's count (with switch; the circle 0.93-1.16).
        # So the count is stretched by the most this run has seen.
        cycle = math.ceil(self._predicted * self._overrun) + self._shortest_hold
        return sculpt.hold_for_the_end(left, cycle, self._shortest_cycle)

    @property
    def _shortest_cycle(self) -> int:
        """The fewest steps left for which a hold still lets go (its dilation turning back
        in time): the shortest hold and ten updates, five out and five back (on the
        circle's smallest outline, about 0.7 m out)."""
        return self._shortest_hold + 10 * self.config.update_every

    def _turn_for_the_deadline(self) -> bool:
        """Whether a closed-loop dilation turns now, wherever the farthest box is, so
        that the contraction is back on the smallest outline, with the shortest hold to
        spare, when the run is measured. Turning one update later would cost about two
        updates (one more out, one more back). Without it the last cycle could only be
        planned from its start, and a dilation that dragged boxes out overran the plan."""
        if self._force_turn:
            self._force_turn = False
            return True
        left = self._steps_left()
        if not self._closed_loop or left is None:
            return False
        margin = 2 * self.config.update_every + self._shortest_hold
        if self._contraction_steps_at_most() + margin <= left:
            return False  # far enough from the deadline to skip counting
        return self._steps_back_if_turning_now(limit=left + 1) + margin > left

    def _contraction_steps_at_most(self) -> int:
        """An upper bound on the steps from turning now to the next hold: the inradius
        shrinks by ``scale_rate`` per update from where it is to below the smallest;
        a circle switched in contracts to the switch threshold, where the polygon
        frozen a size above it returns (one update more), and each schedule may take
        one more update to see it is there."""
        rate = self.config.scale_rate
        updates = math.log(max(self.inradius, self.min_radius) / self.min_radius) / -math.log(rate)
        return self.config.update_every * (math.ceil(updates) + 3)

    def _ghost(self):
        """A copy of this controller that runs on the boxes as they are now, without a
        deadline and without drawing, to count its schedule's steps."""
        ghost = copy.copy(self)
        ghost.strategies, ghost._pending = dict(self.strategies), dict(self._pending)
        ghost._observation = _Snapshot(self._observation.step, np.array(self._observation.box_positions))
        ghost._redraw = lambda: None  # only its sizes and phases matter, not which lights are on
        ghost.open_ended = True  # it counts a whole cycle, not one cut short for the deadline
        return ghost

    @staticmethod
    def _steps_until_hold(ghost, limit: int) -> int:
        steps = 0
        while ghost.phase != HOLDING and steps < limit:
            ghost.advance()
            steps += 1
        return steps

    def _steps_to_next_hold(self, limit: int) -> int:
        """World steps from letting go of this hold until the next one starts (at most
        ``limit``), found by running a copy of this controller on the boxes as they are
        now. Exact for the schedule, whatever it is (the program's overshoot, a circle
        switched in that grows farther than the polygon would); boxes that move
        while it runs can still make the real cycle longer or shorter."""
        ghost = self._ghost()
        ghost._end_hold()
        return self._steps_until_hold(ghost, limit)

    def _steps_back_if_turning_now(self, limit: int) -> int:
        """World steps until the next hold if the dilation turned at this update (at most
        ``limit``). The contraction does not look at the boxes, so this is exact."""
        ghost = self._ghost()
        ghost._force_turn = True
        ghost._update()
        return self._steps_until_hold(ghost, limit)
