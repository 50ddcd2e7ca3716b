"""box_start 'packed': the boxes start as a hexagonal tiling of the goal (the goal already built)."""

import math

import numpy as np
import pytest

from sandbox.model.config import CASES, Config, ConfigError
from sandbox.model.family import make_goal
from sandbox.model.simulation import Simulation
from sandbox.model.world import packed_in_goal


def test_seven_boxes_are_the_centre_and_its_six_neighbours_across_the_flats():
    cfg = Config(boxes=7, box_start="packed")  # circle goal; circumradius 0.25, skin 0.01
    goal = make_goal(cfg, None)
    pitch = 2 * (0.25 * math.cos(math.pi / 6) + 0.01) + 0.001  # 0.454013 m: skins 1 mm apart
    angles = np.radians([30, 90, 150, 210, 270, 330])
    expected = np.vstack([goal.centre, goal.centre + pitch * np.c_[np.cos(angles), np.sin(angles)]])
    placed = packed_in_goal(cfg, goal)
    assert len(placed) == 7
    assert np.allclose(placed[0], goal.centre)
    # the same set, whatever order ties come in
    assert np.allclose(np.sort(np.round(placed, 9), axis=0), np.sort(np.round(expected, 9), axis=0))


@pytest.mark.parametrize("case", ["circle", "square-flare", "star"])
def test_a_packed_goal_starts_full_and_still(case):
    cfg = Config().replace(**CASES[case], box_start="packed", robots=0)
    sim = Simulation(cfg, seed=1)
    start = sim.box_positions.copy()
    gaps = np.hypot(*(start[:, None, :] - start[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() > 2 * (cfg.box_apothem + cfg.box_skin)  # no box overlaps another
    assert np.all(np.abs(start - cfg.centre) < cfg.construction_size / 2 - cfg.box_circumradius)
    # The tiling holds 0.91 of the area (skins included), so the goal is about that full.
    assert sim.measure().fraction_in_goal > 0.89
    sim.step(300)  # no robots, no overlaps: nothing moves
    assert np.abs(sim.box_positions - start).max() < 1e-9


def test_the_start_of_the_boxes_changes_nothing_else_of_a_seed():
    scattered = Simulation(Config(steps=10), seed=5)
    packed = Simulation(Config(steps=10, box_start="packed"), seed=5)
    assert np.array_equal(scattered.robot_positions, packed.robot_positions)
    assert all(np.array_equal(a, b) for a, b in zip(scattered._due, packed._due))
    assert not np.array_equal(scattered.box_positions, packed.box_positions)


def test_bad_starts_are_refused_with_a_reason():
    with pytest.raises(ConfigError, match="box_start"):
        Config(box_start="built")
    fat = Config(box_start="packed", box_skin=0.6)  # 1.63 m apart: 500 do not tile 16 m
    with pytest.raises(ConfigError, match="do not tile the construction area"):
        Simulation(fat, seed=0)


def test_the_app_keeps_its_world_when_a_packed_start_cannot_be_built():
    import threading

    from sandbox.app.world.orders import Reset, UpdateConfig
    from sandbox.app.world.runner import Runner

    runner = Runner(Config(robots=10, boxes=20), shape=None, playing=False)
    runner.start()
    try:
        outcome, done = {}, threading.Event()
        runner.ask(UpdateConfig({"box_start": "packed", "box_skin": 0.6, "boxes": 400}))
        runner.ask(Reset(), on_done=lambda r: (outcome.setdefault("done", r), done.set()),
                   on_error=lambda e: (outcome.setdefault("error", e), done.set()))
        assert done.wait(60)
        assert isinstance(outcome.get("error"), ConfigError)
        assert "do not tile the construction area" in str(outcome["error"])
        assert runner.sim.config.box_start == "scattered" and len(runner.sim.box_positions) == 20
    finally:
        runner.stop()
