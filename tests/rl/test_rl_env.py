"""The Gymnasium environment: it passes Gymnasium's checker, gymnasium.make builds it, it is
seeded as Gymnasium expects, and its reward and truncation are the Gym-style environment's."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import sandbox.rl  # noqa: E402  (registers the id)
from sandbox.model.simulation import Simulation  # noqa: E402
from sandbox.rl.env import LightFieldGymEnv  # noqa: E402

#: A 16 m arena (16 x 16 lights) with a handful of bodies: a step costs milliseconds.
TINY = dict(arena_size=16, construction_size=4, robot_spawn_size=8, light_range=4, robots=4, boxes=6, steps=30,
            update_every=10)


@pytest.mark.parametrize("action", ["outline", "pattern"])
def test_gymnasium_checker_passes(action):
    env = gymnasium.make(sandbox.rl.ENV_ID, action=action, **TINY)
    check_env(env.unwrapped)
    assert env.observation_space.shape == (len(env.unwrapped.observation_names),)
    assert env.action_space.shape == ((4,) if action == "outline" else (16, 16))


def test_make_imports_the_registering_module_itself():
    env = gymnasium.make(f"sandbox.rl:{sandbox.rl.ENV_ID}", shape="star", **TINY)
    assert isinstance(env.unwrapped, LightFieldGymEnv) and env.unwrapped.config.shape == "star"


def test_a_seed_is_the_worlds_seed_and_later_resets_follow_np_random():
    env = LightFieldGymEnv(**TINY)
    first, info = env.reset(seed=5)
    np.testing.assert_array_equal(info["box_positions"], Simulation(env.config, seed=5).box_positions)
    worlds = [env.reset()[1]["box_positions"] for _ in range(2)]
    again, _ = env.reset(seed=5)
    np.testing.assert_array_equal(first, again)
    for world in worlds:
        np.testing.assert_array_equal(env.reset()[1]["box_positions"], world)
    assert not np.array_equal(worlds[0], worlds[1])


def test_reward_is_the_gain_in_the_goal_and_the_episode_truncates_at_its_steps():
    env = LightFieldGymEnv(**TINY)
    observation, info = env.reset(seed=1)
    start, total, steps, truncated = info["fraction_in_goal"], 0.0, 0, False
    while not truncated:
        observation, reward, terminated, truncated, info = env.step(np.array([0.0, 0.0, 0.0, 0.0]))
        assert not terminated and observation in env.observation_space
        total, steps = total + reward, steps + 1
    assert steps == 3 and info["step"] == 30 and observation[env.observation_names.index("time")] == 1.0
    assert total == pytest.approx(info["fraction_in_goal"] - start)
    assert observation[env.observation_names.index("boxes inside")] == pytest.approx(info["fraction_in_goal"])
    lit = info["intensities"].sum()
    assert lit > 0 and info["light_energy"] == pytest.approx(30 * lit)


def test_actions_outside_the_space_are_clipped():
    env = LightFieldGymEnv(action="pattern", **TINY)
    env.reset(seed=0)
    *_, info = env.step(np.full((16, 16), 7.0))
    assert info["intensities"].max() == env.config.light_intensity
