"""The paper's controller with chase: its hooks, closed over what the boxes show."""

from __future__ import annotations

import numpy as np

from sandbox.model import band
from sandbox.model.chase import finish, sculpt, sight
from sandbox.model.chase.hold import Hold
from sandbox.model.chase.tuning import SCULPTING, Sculpting
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.goal import Goal
from sandbox.model.phases import DILATING, HOLDING
from sandbox.shapes import geometry

_SENSES_BOXES, _SENSES_NOTHING = frozenset({"boxes"}), frozenset()


class ChaseController(Controller):
    """The paper's controller, and while its ``chase`` strategy is on (live, like any
    strategy) the closed loop: it sees the boxes and changes where dilations turn,
    how long the smallest outline is held and what is lit (see :mod:`sandbox.model.chase`).
    With chase off it is the open loop, step for step."""

    #: How the closed loop shapes the band near the goal and holds it.
    sculpting: Sculpting = SCULPTING

    def __init__(self, config: Config, goal: Goal):
        #: What the last update saw (an observation with the boxes) while it senses them, else None.
        self.seen = None
        #: Whether the run goes on past ``config.steps`` (the live app's): then there is no deadline.
        self.open_ended = False
        self.plan = finish.EndPlan()
        self._hold: Hold | None = None  # the closed loop's hold, while one is on
        super().__init__(config, goal)  # draws: the hooks read the attributes above

    @property
    def chasing(self) -> bool:
        return self.strategies["chase"] > 0

    @property
    def senses(self) -> frozenset:
        """Open loop: nothing. With chase on (or switched on for the next update), the boxes."""
        return _SENSES_BOXES if self.chasing or self.state.pending.get("chase", 0) > 0 else _SENSES_NOTHING

    def update(self, observation) -> np.ndarray | None:
        # Only what it senses: with chase off it looks at nothing, as the open loop.
        self.seen = observation if self.senses else None
        return super().update(observation)

    @property
    def deadline(self) -> int | None:
        """The step at which the run is measured (chase plans its last cycle for it);
        None for an open-ended run."""
        return None if self.open_ended else self.config.steps

    def steps_left(self) -> int | None:
        """Steps from the last observation to the deadline; None when there is nothing
        to plan for (an open-ended run, nothing seen, or the deadline passed)."""
        if self.deadline is None or self.seen is None:
            return None
        left = self.deadline - self.seen.step
        return left if left >= 0 else None

    # -- where a dilation turns ---------------------------------------------
    def _turn_radius(self) -> float:
        """Chase metres beyond the farthest stray box (see :func:`sight.turn_radius`)."""
        return sight.turn_radius(self, self.seen)

    def _turns_early(self) -> bool:
        """In time for the run's deadline (see :func:`finish.turns_for_the_deadline`)."""
        left = self.steps_left()
        return self.chasing and left is not None and finish.turns_for_the_deadline(self, left)

    # -- the hold -------------------------------------------------------------
    def _start_hold(self) -> None:
        """Chasing, hold as long as :class:`Hold` says."""
        super()._start_hold()
        if self.phase == HOLDING and self.chasing and self.seen is not None:
            self._hold = Hold(self.config.hold_steps, self._boxes_in_goal(), self.sculpting)
            self.plan.hold_started(self.seen.step)

    def _hold_step(self) -> bool:
        """One step of the closed loop's hold: the band is re-sculpted every update."""
        if self._hold is None or self.seen is None:
            return super()._hold_step()
        if self._hold.tick(self._boxes_in_goal, self._boxes_out_of_reach) or self._holds_for_the_end():
            if self._hold.clock % self.config.update_every == 0:
                self._redraw()
                return True
            return False
        return self._end_hold()

    def _holds_for_the_end(self) -> bool:
        left = self.steps_left()
        return left is not None and finish.keeps_holding(self, left)

    def _end_hold(self) -> bool:
        self._hold = None
        if self.seen is not None:
            self.plan.released_at = self.seen.step
        return super()._end_hold()

    def _boxes_in_goal(self) -> int:
        return sight.boxes_in_goal(self.goal, self.seen.box_positions)

    def _boxes_out_of_reach(self) -> int:
        return sight.boxes_out_of_reach(self.goal, self.seen.box_positions, self.config.robot_radius)

    # -- what is lit ------------------------------------------------------------
    def _redraw(self) -> None:
        """Chasing, the goal grown and sculpted; a circle switched in is lit as the open loop's."""
        goal = self.goal
        if self.chasing and self.circle_radius is None and (goal.is_circle or not self.is_circle):
            self._redraw_sculpted()
        else:
            super()._redraw()

    def _redraw_sculpted(self) -> None:
        """The goal grown by the distance the scale gives, sculpted near the goal from
        what the boxes show (see :mod:`sandbox.model.chase.sculpt`)."""
        cfg, goal = self.config, self.goal
        self.gathering = ""  # chase lights its own band, never the notches' gathering
        polygon = goal.outline()
        distance = self.sizing.distance(self.scale)
        if self.seen is None:
            shaped = sculpt.Sculpted(sculpt.offset_outline(polygon, distance), np.empty((0, 2)))
        else:
            boxes = self.seen.box_positions
            shaped = sculpt.sculpt(polygon, distance, boxes, goal.contains(boxes), cfg.box_area, self.sculpting)
        self.outline = shaped.outline
        if goal.is_circle:
            self.corners = np.empty((0, 2))
        else:
            convex = geometry.interior_angles(polygon) < 180.0
            self.corners = sculpt.corner_points(polygon, convex, distance)
        on = band.along(self._centres, self.outline, cfg.band)
        if self.strategies["no_corners"] > 0 and len(self.corners) and self.phase == DILATING:
            on = self._darken_corners(on)  # contracting, the tips need their robots
        self._light(sculpt.darken_near(on, self._centres, shaped.dark, self.sculpting.dark))
