"""Random search (a (1+1) evolution strategy) for a linear policy on the outline action: numpy only.

    python examples/random_search.py   # about three minutes; needs the rl extra

A small world for speed: a 32 m arena, 40 robots, 40 boxes, 6,000 steps (60 actions).
"""
import time

import gymnasium
import numpy as np

import sandbox.rl  # registers phototaxis/LightField-v0

env = gymnasium.make(sandbox.rl.ENV_ID, arena_size=32, construction_size=8, robot_spawn_size=16,
                     robots=40, boxes=40, steps=6000)


def episode(policy, seed):
    """The return of one episode: the gain in the fraction of boxes in the goal."""
    observation, _ = env.reset(seed=seed)
    total, done = 0.0, False
    while not done:
        observation, reward, terminated, truncated, _ = env.step(policy(observation))
        total, done = total + reward, terminated or truncated
    return total


def linear(theta):
    return lambda observation: np.clip(theta @ np.append(observation, 1.0), 0.0, 1.0)


rng = np.random.default_rng(0)
theta = np.zeros((env.action_space.shape[0], env.observation_space.shape[0] + 1))
best, start = -np.inf, time.time()
for _ in range(60):  # keep a random change of the weights when it does as well on the two training worlds
    candidate = theta + 0.3 * rng.standard_normal(theta.shape)
    score = np.mean([episode(linear(candidate), seed) for seed in (0, 1)])
    if score >= best:
        theta, best = candidate, score
print(f"searched for {time.time() - start:.0f} s; return on the training worlds {best:.3f}")
env.action_space.seed(0)
for name, policy in (("learned", linear(theta)), ("random", lambda observation: env.action_space.sample())):
    returns = [episode(policy, seed) for seed in range(100, 105)]  # worlds the search never saw
    print(f"{name}: {np.mean(returns):.3f} ± {np.std(returns, ddof=1) / np.sqrt(len(returns)):.3f} ({np.round(returns, 3)})")
