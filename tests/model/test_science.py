"""The model does what the paper is about, on a small world in seconds:
light moves boxes into the goal, and without light nothing does."""

import pytest

from sandbox.model.config import Config
from sandbox.model.simulation import Simulation

SMALL_WORLD = Config(arena_size=32.0, construction_size=8.0, robot_spawn_size=16.0, robots=50, boxes=120)


def fraction_after(config: Config, seed: int, steps: int = 8000) -> tuple[float, float]:
    sim = Simulation(config, seed=seed)
    start = sim.measure().fraction_in_goal
    sim.step(steps)
    return start, sim.measure().fraction_in_goal


@pytest.mark.parametrize("seed", [1, 2])
def test_the_light_pushes_boxes_into_the_goal(seed):
    start, end = fraction_after(SMALL_WORLD, seed)
    assert end >= start + 0.25, (start, end)  # one compression: about a third in the goal at first


@pytest.mark.parametrize("seed", [1, 2])
def test_without_light_nothing_improves(seed):
    start, end = fraction_after(SMALL_WORLD.replace(light_intensity=0.0), seed)
    assert end <= start + 1e-9, (start, end)
