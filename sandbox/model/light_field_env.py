"""A Gymnasium-style environment: the light pattern is the action.

>>> env = LightFieldEnv(Config(robots=20, boxes=30, steps=1000))
>>> observation, info = env.reset(seed=1)
>>> pattern = np.zeros(env.pattern_shape)
>>> observation, reward, terminated, truncated, info = env.step(pattern)

Each :meth:`step` lights the pattern and runs ``steps_per_action`` world
steps (the configuration's ``update_every``, 100, by default). The reward is
the gain in the fraction of boxes in the goal over those steps; the episode
is truncated after ``config.steps`` world steps and never terminates
earlier. It follows Gymnasium's ``reset`` / ``step`` signatures without
depending on it: observations are dicts of numpy arrays (``step``,
``box_positions``, ``robot_positions``, ``robot_charges``, ``intensities``).

For RL libraries, :mod:`sandbox.rl` wraps it as a real Gymnasium environment
(spaces, seeding, ``gymnasium.make("phototaxis/LightField-v0")``, a
low-dimensional action); see docs/gymnasium.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sandbox.model.config import Config
from sandbox.model.programs import LightProgram, check_pattern
from sandbox.model.simulation import Simulation


class _Held(LightProgram):
    """Keeps whatever the environment lit: the agent is the program."""

    senses = frozenset({"boxes", "robots"})
    every = 2**62

    def update(self, observation):
        return None


class LightFieldEnv:
    def __init__(self, config: Config | None = None, *, shape: Any = "from-config", steps_per_action: int | None = None):
        self.config = config or Config()
        self.shape = shape
        self.steps_per_action = int(steps_per_action or self.config.update_every)
        if self.steps_per_action < 1:
            raise ValueError(f"steps_per_action must be at least 1 (got {steps_per_action})")
        self.sim: Simulation | None = None

    @property
    def pattern_shape(self) -> tuple[int, int]:
        n = self.config.lights_per_side
        return (n, n)

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        config = self.config if seed is None else self.config.replace(seed=int(seed))
        self.sim = Simulation(config, shape=self.shape, program=_Held())
        return self._observation(), self._info()

    def step(self, pattern: Any) -> tuple[dict, float, bool, bool, dict]:
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        sim = self.sim
        sim.set_pattern(check_pattern(pattern, self.pattern_shape, "the action"))
        before = sim.measure().fraction_in_goal
        sim.step(min(self.steps_per_action, max(0, self.config.steps - sim.steps_done)))
        reward = sim.measure().fraction_in_goal - before
        truncated = sim.steps_done >= self.config.steps
        return self._observation(), float(reward), False, truncated, self._info()

    def _observation(self) -> dict:
        sim = self.sim
        return {"step": sim.steps_done, "box_positions": np.array(sim.box_positions),
                "robot_positions": np.array(sim.robot_positions), "robot_charges": np.array(sim.robot_charges),
                "intensities": np.array(sim.light_intensities)}

    def _info(self) -> dict:
        sample = self.sim.measure()
        return {"fraction_in_goal": sample.fraction_in_goal, "mean_outside_distance": sample.mean_outside_distance,
                "light_energy": self.sim.light_energy}
