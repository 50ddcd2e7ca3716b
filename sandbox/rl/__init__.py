"""Reinforcement learning on the light field (needs the ``rl`` extra: ``pip install -e '.[rl]'``).

Importing this package registers :data:`ENV_ID` with Gymnasium::

    import gymnasium
    import sandbox.rl  # registers phototaxis/LightField-v0

    env = gymnasium.make("phototaxis/LightField-v0", robots=50, boxes=60, steps=10_000)

``gymnasium.make("sandbox.rl:phototaxis/LightField-v0")`` imports it for you
(Gymnasium 1.x has no plugin entry points). The environment is
:class:`sandbox.rl.env.LightFieldGymEnv`; see docs/gymnasium.md.

Without Gymnasium installed this package imports and registers nothing, so
nothing else in ``sandbox`` (headless runs, the app) ever needs it;
:mod:`sandbox.rl.outline` and :mod:`sandbox.rl.features` use numpy only.
"""

from __future__ import annotations

ENV_ID = "phototaxis/LightField-v0"


def register() -> bool:
    """Register :data:`ENV_ID` (once); False when Gymnasium is not installed."""
    try:
        import gymnasium
    except ModuleNotFoundError:
        return False
    if ENV_ID not in gymnasium.registry:
        # No max_episode_steps: the environment truncates itself after the configuration's ``steps``.
        gymnasium.register(id=ENV_ID, entry_point="sandbox.rl.env:LightFieldGymEnv")
    return True


register()
