"""The Gymnasium environment: steer the swarm with the light, one update at a time.

>>> import gymnasium, sandbox.rl
>>> env = gymnasium.make("phototaxis/LightField-v0", robots=50, boxes=60, steps=10_000)
>>> observation, info = env.reset(seed=0)
>>> observation, reward, terminated, truncated, info = env.step(env.action_space.sample())

Each step lights the action's pattern for ``steps_per_action`` world steps
(the configuration's ``update_every``, 100, by default): one controller
update. The world, the reward (the gain in the fraction of boxes in the goal
over the step) and the truncation (after ``config.steps`` world steps; it
never terminates earlier) are :class:`sandbox.model.light_field_env.LightFieldEnv`'s,
which this wraps; what it adds is Gymnasium's spaces, seeding and a compact
observation.

Two actions (``action=``):

* ``"outline"`` (default): four knobs in [0, 1], the paper's controller's own
  (outline size, flare, circle, no corners; see :mod:`sandbox.rl.outline`);
* ``"pattern"``: every light's intensity, (n, n) in [0, 1] times the
  configuration's ``light_intensity``.

Actions outside the space are clipped to it. The observation is the vector
of :mod:`sandbox.rl.features` (names in ``env.unwrapped.observation_names``);
``info`` carries the full state as arrays (``box_positions``,
``robot_positions``, ``robot_charges``, ``intensities``) and ``step``,
``fraction_in_goal``, ``mean_outside_distance``, ``light_energy``.

Seeding follows Gymnasium: ``reset(seed=s)`` builds the world of seed ``s``
(the seed ``phototaxis run --seed s`` uses) and seeds ``np_random``; a later
``reset()`` without a seed draws the next world's seed from ``np_random``.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from sandbox.model.config import Config
from sandbox.model.light_field_env import LightFieldEnv
from sandbox.rl.features import feature_names, observe
from sandbox.rl.outline import KNOBS, Knobs, OutlinePainter

ACTIONS = ("outline", "pattern")
#: World seeds are drawn below the configuration's largest seed.
_SEED_HIGH = 2**63 - 1


def make_config(config: Config | None, values: dict[str, Any]) -> Config:
    """The configuration: ``config`` (default: the paper's) with ``values`` (parameter names) changed."""
    base = config if config is not None else Config()
    return base.replace(**values) if values else base


class LightFieldGymEnv(gymnasium.Env):
    """See the module docstring. ``config`` and keyword parameters (``robots=50``, ``shape="star"``...)
    set the world; ``steps_per_action`` the world steps per action."""

    metadata = {"render_modes": []}

    def __init__(self, config: Config | None = None, *, action: str = "outline", steps_per_action: int | None = None,
                 render_mode: str | None = None, **values: Any):
        if action not in ACTIONS:
            raise ValueError(f"action must be one of {ACTIONS} (got {action!r})")
        if render_mode is not None:
            raise ValueError(f"no render modes (got {render_mode!r}); draw from info's arrays instead")
        self.render_mode = None
        self.action_kind = action
        self._core = LightFieldEnv(make_config(config, values), steps_per_action=steps_per_action)
        self.config = self._core.config
        n = self.config.lights_per_side
        if action == "outline":
            self.action_space = spaces.Box(0.0, 1.0, (len(KNOBS),), np.float32)
        else:
            self.action_space = spaces.Box(0.0, 1.0, (n, n), np.float32)
        self.observation_names = feature_names(KNOBS if action == "outline" else ())
        self.observation_space = spaces.Box(0.0, 1.0, (len(self.observation_names),), np.float32)
        self._painter: OutlinePainter | None = None
        self._last_action = np.zeros(len(KNOBS))

    @property
    def simulation(self):
        """The running :class:`sandbox.model.simulation.Simulation` (after reset), for reading it."""
        return self._core.sim

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        world_seed = seed if seed is not None else int(self.np_random.integers(_SEED_HIGH))
        full, info = self._core.reset(world_seed)
        if self._painter is None:  # the goal depends on the configuration only, not on the seed
            self._painter = OutlinePainter(self.config, self._core.sim.goal)
        self._last_action = np.zeros(len(KNOBS))
        return self._observe(), {**full, **info}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self._core.sim is None:
            raise RuntimeError("call reset() before step()")
        full, reward, terminated, truncated, info = self._core.step(self._pattern(action))
        return self._observe(), reward, terminated, truncated, {**full, **info}

    def _pattern(self, action: Any) -> np.ndarray:
        """The intensities an action lights (clipped to the action space first)."""
        action = np.clip(np.asarray(action, dtype=float), 0.0, 1.0)
        if self.action_kind == "pattern":
            return action.reshape(self.action_space.shape) * self.config.light_intensity
        self._last_action = action.reshape(len(KNOBS))
        return self._painter.pattern(Knobs.from_action(self._last_action))

    def _observe(self) -> np.ndarray:
        sim = self._core.sim
        time = sim.steps_done / self.config.steps if self.config.steps > 0 else 1.0
        return observe(sim, time, self._last_action if self.action_kind == "outline" else None)
