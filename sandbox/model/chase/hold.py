"""Chase's patience: when the closed loop lets go of the smallest outline."""

from __future__ import annotations

from sandbox.model.chase.tuning import SCULPTING, Sculpting


class Hold:
    """When the closed loop lets go of the smallest outline.

    At least ``max(hold_steps, check)`` steps; at each check, ``check`` more
    if at least ``gain`` boxes arrived in the goal since the best count so
    far, or if fewer than ``stay`` boxes are out of the robots' reach (there
    is nothing worth dilating for); no extension after ``longest`` steps."""

    def __init__(self, hold_steps: int, in_goal: int, tuning: Sculpting = SCULPTING):
        self.tuning = tuning
        self.clock = 0
        self.best = in_goal
        self.left = max(hold_steps, tuning.check)

    def tick(self, in_goal, out_of_reach) -> bool:
        """One world step of holding; ``in_goal()`` and ``out_of_reach()`` count boxes
        (called only at checks). Returns whether to keep holding."""
        self.clock += 1
        self.left -= 1
        tuning = self.tuning
        if self.clock % tuning.check == 0 and self.clock < tuning.longest:
            now = in_goal()
            if now >= self.best + tuning.gain:
                self.best = now
                self.left = max(self.left, tuning.check)
            elif out_of_reach() < tuning.stay:
                self.left = max(self.left, tuning.check)
        return self.left > 0
