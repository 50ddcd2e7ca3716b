"""Nothing a user types can hang or corrupt a run: populations that cannot be
placed, goals that cannot fit, outlines of thousands of vertices."""

import math
import threading

import numpy as np
import pytest

from sandbox.app.world.orders import BuildCancelled, CancelBuild, Reset, SetPlaying, UpdateConfig
from sandbox.app.world.runner import Runner
from sandbox.model.config import Config, ConfigError
from sandbox.model.simulation import Simulation
from sandbox.model.world import World
from sandbox.shapes import ShapeError
from tests.waiting import wait_until

SLIVER = np.array([[-120.0, 0.0], [120.0, 0.0], [0.0, 0.3]])  # at 60 boxes, 125 m long: mostly outside 16 m


def test_populations_that_cannot_be_placed_are_refused_with_the_numbers():
    with pytest.raises(ConfigError, match=r"100,000 robots .* at most 3,007"):
        Config().replace(robots=100_000)
    with pytest.raises(ConfigError, match=r"5,000 boxes .* at most 986"):
        Config().replace(boxes=5_000)
    # The limits follow the geometry: a bigger spawn square holds more robots.
    assert Config(arena_size=128.0, robot_spawn_size=64.0).max_robots > 4 * 3_007


def test_no_robot_starts_inside_the_construction_area_even_when_crowded():
    cfg = Config(robots=3_000, boxes=10)
    world = World(cfg, np.random.default_rng(4))
    inside = np.abs(world.state[: cfg.robots, :2] - cfg.centre).max(axis=1) < cfg.construction_size / 2
    assert not inside.any()


def test_a_goal_that_cannot_fit_is_refused_and_the_old_one_stays():
    sim = Simulation(Config(robots=10, boxes=60), seed=1)
    too_long = r"sliver: at the boxes. total area \(60 boxes, 10 m²\) the goal is 124\.9 x 0\.2 m.*: use a less elongated"
    with pytest.raises(ShapeError, match=too_long):
        sim.set_shape(SLIVER, "sliver")
    assert sim.goal.is_circle and sim.config.shape == "circle"
    sim.step(10)  # still running
    with pytest.raises(ShapeError, match="larger than the 16 m construction area"):
        Simulation(Config(robots=10, boxes=60), shape=SLIVER)


def test_a_goal_whose_largest_outline_reaches_past_the_walls_is_said_so():
    sim = Simulation(Config(robots=10, boxes=500, shape="star"), seed=1)
    assert any("past the 64 m arena's walls" in note for note in sim.controller.notes)
    assert Simulation(Config(robots=10, boxes=500), seed=1).controller.notes == []


def test_outlines_of_thousands_of_vertices_are_simplified_below_the_light_pitch():
    t = np.linspace(0.0, 2 * math.pi, 9_999, endpoint=False)
    wobbly = np.c_[np.cos(t) * (1 + 0.1 * np.sin(5 * t)), np.sin(t) * (1 + 0.1 * np.sin(5 * t))]
    sim = Simulation(Config(robots=10, boxes=500), seed=1, shape=wobbly)
    assert len(sim.goal.vertices) < 100
    assert abs(sim.goal.area - 500 * sim.config.box_area) < 1e-6 * sim.goal.area


def test_building_a_world_reports_progress_and_can_be_cancelled():
    runner = Runner(Config(robots=10, boxes=20), shape=None, playing=False)
    runner.start()
    try:
        seen, outcome = [], {}
        done = threading.Event()
        reset = Reset()
        runner.on_progress(lambda f: (seen.append(f), f is not None and f > 0.2
                                      and runner.submit(CancelBuild(reset.build))))
        runner.ask(UpdateConfig({"robots": 3_000, "boxes": 900}))
        runner.ask(reset, on_done=lambda r: (outcome.setdefault("done", r), done.set()),
                   on_error=lambda e: (outcome.setdefault("error", e), done.set()))
        assert done.wait(60)
        assert isinstance(outcome.get("error"), BuildCancelled)
        assert seen[-1] is None and any(f is not None and 0 < f < 1 for f in seen)
        # The error is reported before the loop takes its next snapshot: wait for that one.
        wait_until(lambda: runner.latest.config.robots == 3_000, 10)
        snap = runner.latest
        assert len(snap.robot_positions) == 10 and snap.config.robots == 3_000  # old world on; change still waits
        runner.submit(SetPlaying(True))  # and it goes on stepping, its speed measured
        wait_until(lambda: runner.latest.step > 0, 30)
        assert len(runner.latest.robot_positions) == 10
        assert runner.steps_per_second() > 0.0
    finally:
        runner.stop()
