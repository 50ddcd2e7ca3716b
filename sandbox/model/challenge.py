"""Build the goal by hand: a timed round scored against the paper's controller (issue 25, item 3;
issue 41, item 6).

A round starts a new world from :data:`ROUND_SEED` and gives the lights to
a person (:mod:`sandbox.model.lamp`) for :data:`ROUND_STEPS` world steps.
Its score is a :class:`Gain`: the boxes in the goal at its end beyond those
that were in it at step 0 (scattered boxes start in the goal by chance: a
third of them in the paper's world, so a share in the goal rewarded doing
nothing). The reference is the paper's controller's gain in the same world
(same configuration and seed) over the same steps, computed here, headless,
so that the comparison is honest. The lamp starts where the robots are
(:func:`lamp_start`), not over the empty goal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sandbox.model.config import Config

#: A round's length in world steps (25 minutes of simulated time): about a minute of play at `serve`'s
#: default pace, 25 steps a frame at 30 frames a second (750 a second); 20,000 lasted 27-29 s.
ROUND_STEPS = 45_000
#: The seed every round starts from (the paper's evaluations' first).
ROUND_SEED = 0
#: Robots :func:`lamp_start` compares pairwise, at most (1,000: 8 MB and a few milliseconds).
MOST_ROBOTS_COMPARED = 1000


@dataclass(frozen=True)
class Gain:
    """What a round did: boxes in the goal at step 0 (``started``) and at its end (``ended``), of ``boxes``."""

    started: int
    ended: int
    boxes: int

    @property
    def brought(self) -> int:
        """Boxes brought into the goal beyond those that started there (fewer than none: pushed out)."""
        return self.ended - self.started

    @property
    def share(self) -> float:
        """``brought`` as a share of the boxes that started outside the goal (0 when none did)."""
        outside = self.boxes - self.started
        return self.brought / outside if outside > 0 else 0.0


def lamp_start(robot_positions: np.ndarray, radius: float,
               within: tuple[float, float, float, float] | None = None) -> tuple[float, float]:
    """Where a round's lamp is first lit: on the robot with the most others within ``radius`` (the
    densest group the lamp can cover), the most central of equals. Robots start scattered over the
    whole arena, so their centroid is the arena's middle, where the goal is and few of them are.
    ``within`` (left, right, bottom, top): only a robot on that floor will do (the floor every page
    shows; the densest group elsewhere was under a folded panel or off a phone's edge); with none
    there, one less than ``radius`` from it, moved onto its edge (the lamp still lights it); with none
    of those either, any, moved onto its edge."""
    xy = np.asarray(robot_positions, dtype=float).reshape(-1, 2)
    if not len(xy):
        raise ValueError("no robots to light")
    # Every pair is n^2: a large swarm is judged by an even sample of it (the densest group stays densest).
    xy = xy[np.linspace(0, len(xy) - 1, min(len(xy), MOST_ROBOTS_COMPARED)).astype(int)]
    d2 = (xy[:, None, 0] - xy[None, :, 0]) ** 2 + (xy[:, None, 1] - xy[None, :, 1]) ** 2
    near = (d2 <= radius * radius).sum(axis=1)
    if within is not None:
        left, right, bottom, top = within
        off = np.hypot(np.maximum(0.0, np.maximum(left - xy[:, 0], xy[:, 0] - right)),
                       np.maximum(0.0, np.maximum(bottom - xy[:, 1], xy[:, 1] - top)))  # how far from the box
        for reach in (0.0, radius):
            if (off <= reach).any():
                near = np.where(off <= reach, near, -1)
                break
    crowded = np.flatnonzero(near == near.max())
    middle = xy.mean(axis=0)
    best = crowded[np.argmin(np.hypot(*(xy[crowded] - middle).T))]
    x, y = float(xy[best, 0]), float(xy[best, 1])
    if within is not None:
        x, y = min(max(x, within[0]), within[1]), min(max(y, within[2]), within[3])
    return x, y


def paper_gain(config: Config, seed: int, steps: int, shape: np.ndarray | None | str = "from-config") -> Gain:
    """The paper's controller's :class:`Gain` over ``steps`` world steps of the world built from
    ``config``, ``seed`` and ``shape`` (the goal's vertices as given, None for the circle), as a live
    round runs it (open-ended)."""
    from sandbox.model.simulation import Simulation  # here: the web server imports this module, steps no world

    sim = Simulation(config, seed=seed, shape=shape, open_ended=True)
    started = int(np.count_nonzero(sim.box_in_goal))
    sim.step(steps)
    return Gain(started, int(np.count_nonzero(sim.box_in_goal)), len(sim.box_positions))


def paper_gains(config: Config, seed: int, steps: Any, shape: np.ndarray | None | str = "from-config") -> dict[int, Gain]:
    """:func:`paper_gain` at each of ``steps`` (world steps), from one run: a class challenge's rounds end
    in the same world a frame or two apart (a late frame takes its steps in one)."""
    from sandbox.model.simulation import Simulation

    sim = Simulation(config, seed=seed, shape=shape, open_ended=True)
    started = int(np.count_nonzero(sim.box_in_goal))
    gains, done = {}, 0
    for step in sorted({int(s) for s in steps}):
        sim.step(step - done)
        done = step
        gains[step] = Gain(started, int(np.count_nonzero(sim.box_in_goal)), len(sim.box_positions))
    return gains
