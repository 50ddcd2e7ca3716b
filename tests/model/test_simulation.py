"""Integration: the whole simulation, seeded and steppable."""

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.controller import CONTRACTING, DILATING, HOLDING
from sandbox.model.metrics import escaped
from sandbox.model.simulation import Simulation


def test_same_seed_same_run(small_config):
    a = Simulation(small_config, seed=7)
    b = Simulation(small_config, seed=7)
    a.step(600)
    b.step(600)
    assert np.array_equal(a.robot_positions, b.robot_positions)
    assert np.array_equal(a.box_positions, b.box_positions)
    assert np.array_equal(a.robot_charges, b.robot_charges)
    c = Simulation(small_config, seed=8)
    c.step(600)
    assert not np.array_equal(a.robot_positions, c.robot_positions)


def test_reset_replays_the_run(small_config):
    sim = Simulation(small_config, seed=3)
    sim.step(300)
    first = sim.robot_positions.copy()
    sim.reset(3)
    assert sim.steps_done == 0
    sim.step(300)
    assert np.array_equal(sim.robot_positions, first)


def test_initial_placement(small_config):
    sim = Simulation(small_config.replace(robots=150, boxes=300), seed=1)
    robots, boxes = sim.robot_positions, sim.box_positions
    c = sim.config.centre
    assert (np.abs(robots - c) <= 16).all()  # inside the 32 m spawn square
    assert (np.abs(robots - c).max(axis=1) >= 8).all()  # outside the construction area
    assert (np.abs(boxes - c) < 8).all()
    assert not escaped(boxes, c, 16.0).any()


def test_robots_cross_the_construction_wall_and_boxes_never_do():
    cfg = Config(robots=60, boxes=120, update_every=20, start_charge=20.0)
    sim = Simulation(cfg, seed=2)
    c = cfg.centre
    outside = np.abs(sim.robot_positions - c).max(axis=1) >= 8.25 - 1e-9  # clear of the wall by a radius
    assert outside.all()
    crossed = np.zeros(len(outside), bool)
    for _ in range(12):
        sim.step(500)
        crossed |= np.abs(sim.robot_positions - c).max(axis=1) < 7.5
        assert sim.measure().boxes_escaped == 0
    assert crossed.sum() >= 5
    assert not sim.has_nan()


def test_controller_cycles_inside_the_simulation(small_config):
    sim = Simulation(small_config.replace(update_every=5, hold_steps=10), seed=0)
    seen = [sim.phase]
    while sim.cycle < 1 and sim.steps_done < 20_000:
        sim.step(5)
        if sim.phase != seen[-1]:
            seen.append(sim.phase)
    assert seen[:4] == [CONTRACTING, HOLDING, DILATING, CONTRACTING]


def test_empty_robots_do_not_move(small_config):
    cfg = small_config.replace(eta_in=0.0, start_charge=0.0)
    sim = Simulation(cfg, seed=5)
    start = sim.robot_positions.copy()
    sim.step(200)
    assert np.allclose(sim.robot_positions, start, atol=1e-6)
    assert (sim.robot_velocities == 0).all()


def test_robots_climb_towards_the_light():
    """A charged robot near the band drives onto it (phototaxis)."""
    cfg = Config(robots=40, boxes=0, start_charge=20.0, update_every=10**6)
    sim = Simulation(cfg, seed=4)
    before = sim.lights.sample(sim.robot_positions).mean()
    sim.step(600)
    after = sim.lights.sample(sim.robot_positions).mean()
    assert after > 1.5 * before


def test_metrics_are_recorded_every_interval(small_config):
    sim = Simulation(small_config.replace(metrics_every=100), seed=0)
    sim.step(350)
    assert [s.step for s in sim.history] == [0, 100, 200, 300]
    last = sim.measure()
    assert 0.0 <= last.fraction_in_goal <= 1.0 and last.mean_outside_distance >= 0.0


def test_live_changes(small_config):
    sim = Simulation(small_config.replace(shape="square"), seed=0)
    sim.step(10)
    deferred = sim.update_config(k_drive=2.0, robots=99, flare=1.75)
    assert deferred == ["robots"]
    assert sim.config.k_drive == 2.0 and sim.world.n_robots == 30 and sim.config.robots == 30
    sim.step(200)
    assert sim.controller.strategies["flare"] == 1.75
    sim.update_config(shape="star")
    assert sim.config.shape == "star" and len(sim.goal.vertices) == 10
    sim.reset(config=sim.config.replace(robots=99))
    assert sim.world.n_robots == 99 and sim.config.k_drive == 2.0


def test_read_only_state(small_config):
    sim = Simulation(small_config)
    with pytest.raises(ValueError):
        sim.robot_positions[0, 0] = 1.0


# --- one configuration: the simulation holds what its world was built with ----

def test_a_shape_change_sizes_the_goal_from_the_boxes_in_the_world(small_config):
    sim = Simulation(small_config, seed=0)  # 60 boxes
    assert sim.update_config(boxes=400) == ["boxes"]  # waits for a reset, kept by the caller
    sim.set_shape(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float), name="square")
    assert sim.goal.area == pytest.approx(60 * sim.config.box_area)
    assert sim.config.boxes == 60


def test_measuring_uses_the_arena_the_world_was_built_in(small_config):
    sim = Simulation(small_config, seed=0)
    sim.update_config(arena_size=32.0, construction_size=8.0, robot_spawn_size=16.0)
    sim.step(50)
    assert sim.measure().boxes_escaped == 0


def test_time_and_photocells_use_the_built_values(small_config):
    sim = Simulation(small_config, seed=0)
    sim.update_config(dt=0.5, sensor_offset=2.0)
    sim.step(30)
    assert sim.time == pytest.approx(30 / 30)
    cells = sim.sensor_points(0)
    assert np.hypot(*(cells - sim.robot_positions[0]).T) == pytest.approx([0.1 * np.sqrt(2)] * 4)


def test_a_reset_takes_the_waiting_changes_when_given_them(small_config):
    sim = Simulation(small_config, seed=0)
    waiting = sim.update_config(boxes=40, k_turn=7.0)
    assert waiting == ["boxes"] and sim.config.k_turn == 7.0
    sim.reset(config=sim.config.replace(boxes=40))
    assert len(sim.box_positions) == 40 and sim.config.k_turn == 7.0


def test_only_a_run_with_a_last_step_plans_for_it(small_config):
    """The closed loop plans its last cycle to end before ``config.steps``;
    the live app's runs go on, so there the controller has no deadline, also after
    a reset or a new goal."""
    cfg = small_config.replace(chase=2.0, steps=5000)
    assert Simulation(cfg, seed=1).controller.deadline == 5000
    sim = Simulation(cfg, seed=1, open_ended=True)
    assert sim.controller.deadline is None
    sim.reset(2)
    assert sim.controller.deadline is None
    sim.set_shape(None, "circle")
    assert sim.controller.deadline is None
