"""The paper's controller with chase (interim)."""

from __future__ import annotations

import numpy as np

from sandbox.model import geometry
from sandbox.model.chase import sculpt
from sandbox.model.chase.finish import EndPlanning
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.goal import Goal
from sandbox.model.phases import DILATING, HOLDING

_SENSES_BOXES, _SENSES_NOTHING = frozenset({"boxes"}), frozenset()


class ChaseController(EndPlanning, Controller):
    #: How the closed loop (chase) shapes the band near the goal and holds it.
    sculpting: sculpt.Sculpting = sculpt.SCULPTING

    def __init__(self, config: Config, goal: Goal):
        self._hold: sculpt.Hold | None = None  # the closed loop's hold (chase), else None
        self._observation = None  # what the last update saw (closed loop only)
        #: Whether the run goes on past ``config.steps`` (the live app's): then there is no deadline.
        self.open_ended = False
        self._released_at: int | None = None  # the step the last hold let go at (closed loop)
        #: Steps the copy counted from letting go of this hold to the next (planned once per hold).
        self._predicted: int | None = None
        #: The longest a cycle ran in this run, as a multiple of the copy's prediction (at least 1).
        self._overrun = 1.0
        #: Turn at the next dilation update whatever the sizes say (set only in a copy; see _ghost).
        self._force_turn = False
        super().__init__(config, goal)

    @property
    def senses(self) -> frozenset:
        """Open loop: nothing. With *chase*, the boxes' positions."""
        return _SENSES_BOXES if self._closed_loop or self._pending.get("chase", 0) > 0 else _SENSES_NOTHING

    def update(self, observation) -> np.ndarray | None:
        self._observation = observation
        return super().update(observation)

    def _hold_step(self) -> bool:
        if self._hold is not None and self._observation is not None:
            return self._closed_loop_hold()
        return super()._hold_step()

    def _end_hold(self) -> bool:
        self._hold = None
        if self._observation is not None:
            self._released_at = self._observation.step
        return super()._end_hold()

    def _start_hold(self) -> None:
        super()._start_hold()
        if self.phase == HOLDING and self._closed_loop and self._observation is not None:
            self._hold = sculpt.Hold(self.config.hold_steps, self._boxes_in_goal(), self.sculpting)
            if self._released_at is not None and self._predicted:
                ran = self._observation.step - self._released_at
                self._overrun = max(self._overrun, ran / self._predicted)
            self._predicted = None

    def _turns_early(self) -> bool:
        return self._turn_for_the_deadline()

    def _redraw(self) -> None:
        goal = self.goal
        if self._closed_loop and self.circle_radius is None and (goal.is_circle or not self.is_circle):
            self._redraw_closed_loop()
            return
        super()._redraw()

    def _closed_loop_hold(self) -> bool:
        """One step of the closed loop's hold: the band is re-sculpted every update."""
        if self._hold.tick(self._boxes_in_goal, self._boxes_out_of_reach) or self._finish_in_hold():
            if self._hold.clock % self.config.update_every == 0:
                self._redraw()
                return True
            return False
        return self._end_hold()

    @property
    def _closed_loop(self) -> bool:
        return self.strategies["chase"] > 0

    def _boxes_in_goal(self) -> int:
        return int(self.goal.contains(self._observation.box_positions).sum())

    def _boxes_out_of_reach(self) -> int:
        """Boxes beyond the reach of robots on the smallest outline (one robot
        diameter from the goal): farther than three robot radii from it."""
        distance = self.goal.distance(self._observation.box_positions)
        return int((distance > 3.0 * self.config.robot_radius).sum())

    def _turn_radius(self) -> float:
        """The inradius (radius for a circle) at which dilation turns: the
        largest, or with *chase* (closed loop) as soon as the outline is
        ``chase`` metres beyond the farthest box outside the goal, and at least
        ``chase`` metres beyond the smallest outline, so the robots always
        back off and push again."""
        largest = self.max_radius
        margin = self.strategies["chase"]
        observation = self._observation
        if margin <= 0 or observation is None:
            return largest
        boxes = observation.box_positions
        stray = boxes[~self.goal.contains(boxes)]
        if not len(stray):
            need = 0.0
        elif self.circle_radius is not None or self.shape is None:
            need = float(np.hypot(*(stray - self.goal.centre).T).max()) + margin
        else:  # the outline is the goal grown by (inradius - its inradius at scale 1): see _redraw_closed_loop
            need = self.sizing.radius_beyond(float(self.goal.distance(stray).max())) + margin
        return min(largest, max(need, self.min_radius + margin))

    def _redraw_closed_loop(self) -> None:
        """*Chase*: the goal grown by the distance the scale gives, sculpted near
        the goal from what the boxes show (see :mod:`sandbox.model.sculpt`)."""
        cfg, goal = self.config, self.goal
        polygon = goal.outline()
        distance = self.sizing.distance(self.scale)
        observation = self._observation
        if observation is None:
            shaped = sculpt.Sculpted(sculpt.offset_outline(polygon, distance), np.empty((0, 2)))
        else:
            boxes = observation.box_positions
            shaped = sculpt.sculpt(polygon, distance, boxes, goal.contains(boxes), cfg.box_area, self.sculpting)
        self.outline = shaped.outline
        if goal.is_circle:
            self.corners = np.empty((0, 2))
        else:
            convex = geometry.interior_angles(polygon) < 180.0
            self.corners = sculpt.corner_points(polygon, convex, distance)
        on = geometry.distance_to_outline(self._centres, self.outline) <= cfg.band + 1e-9
        if self.strategies["no_corners"] > 0 and len(self.corners) and self.phase == DILATING:
            on = self._darken_corners(on)
        on = sculpt.darken_near(on, self._centres, shaped.dark, self.sculpting.dark)
        self.intensities = (on * cfg.light_intensity).reshape(self.intensities.shape)
