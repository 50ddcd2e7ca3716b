"""The robots' motor and the bodies' damping (SPEC §9 rows 8-10): with the
authors' 'set-once' motor a robot's velocity is set at its refresh and then
persists (robots are undamped); boxes lose velocity as Box2D damps it."""

import math

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.simulation import Simulation
from sandbox.model.world import World


def lone_world(**changes) -> World:
    cfg = Config(robots=1, boxes=1, **changes)
    return World(cfg, np.random.default_rng(0))


@pytest.mark.parametrize("model, per_step", [("box2d", 1 / (1 + 10 / 30)), ("exponential", math.exp(-10 / 30))])
def test_box_damping_per_step(model, per_step):
    world = lone_world(box_damping_model=model)
    box = next(b for b in world.space.bodies if b not in world.robot_bodies)
    box.velocity, box.angular_velocity = (1.0, 0.0), 1.0
    world.step()
    assert box.velocity.x == pytest.approx(per_step)
    assert box.angular_velocity == pytest.approx(per_step)


def test_set_once_robots_are_not_damped():
    world = lone_world()  # motor 'set-once'
    robot = world.robot_bodies[0]
    robot.velocity, robot.angular_velocity = (0.3, -0.4), 2.0
    start = robot.position
    for _ in range(30):
        world.step()
    assert tuple(robot.velocity) == pytest.approx((0.3, -0.4))
    assert robot.angular_velocity == pytest.approx(2.0)
    # The velocity stays fixed in the world frame while the body turns.
    assert tuple(robot.position - start) == pytest.approx((0.3, -0.4))
    assert robot.angle == pytest.approx(world.state[0, 2] + 2.0, abs=1e-9)


def charged(**changes) -> Simulation:
    """Robots that never run empty, in a light pattern that does not change."""
    values = dict(robots=40, boxes=0, start_charge=20.0, eta_in=1000.0, update_every=10**6)
    cfg = Config(**{**values, **changes})
    return Simulation(cfg, seed=3)


def test_each_robot_refreshes_once_per_period_at_its_own_phase(monkeypatch):
    sim = charged()
    refreshed = []
    original = sim.world.set_robot_velocities
    monkeypatch.setattr(sim.world, "set_robot_velocities",
                        lambda writes, count: (refreshed.append(writes[:count, 0].astype(int).tolist()),
                                               original(writes, count)))
    sim.step(100)
    per_step = refreshed  # one entry per step that wrote anything
    counts = np.bincount([r for step in per_step for r in step], minlength=40)
    assert (counts == 2).all()  # 100 steps = two periods of 50
    first = {r: i for i, step in enumerate(per_step) for r in step}
    assert len(set(first.values())) > 10  # phases are spread, not all at one step


def test_a_robot_moves_at_its_commanded_speed_until_something_stops_it():
    sim = charged(robots=1)
    dt = sim.config.dt
    while not sim.robot_commands[0].any():  # step up to the refresh
        sim.step(1)
    v, w = sim.robot_commands[0]
    heading_then = sim.robot_headings[0] - w * dt  # the heading it read its cells at, a step ago
    expected = (v * math.cos(heading_then), v * math.sin(heading_then))
    velocity = sim.world.state[0, 3:5]
    assert tuple(velocity) == pytest.approx(expected, abs=1e-9)
    position = sim.robot_positions[0].copy()
    sim.step(10)  # before the next refresh: straight on at the same velocity
    assert tuple(sim.robot_positions[0] - position) == pytest.approx(tuple(np.array(expected) * 10 * dt), abs=1e-9)
    assert sim.robot_headings[0] == pytest.approx(heading_then + w * 11 * dt, abs=1e-9)


def test_a_robot_out_of_charge_is_stopped():
    sim = Simulation(Config(robots=20, boxes=0, start_charge=0.05, eta_in=0.0), seed=1)
    sim.step(120)
    assert (sim.robot_charges == 0).all()
    assert (sim.world.state[:20, 3:6] == 0).all()
    before = sim.robot_positions.copy()
    sim.step(100)
    assert np.array_equal(sim.robot_positions, before)


def test_state_rows_stay_with_their_bodies_when_bodies_sleep():
    """pymunk lists sleeping bodies after the awake ones; the state must not mix them up."""
    sim = Simulation(Config(robots=30, boxes=80, sleep_time=0.2, update_every=10**6), seed=2)
    sim.step(600)
    world = sim.world
    assert any(b.is_sleeping for b in world.box_bodies)
    bodies = [*world.robot_bodies, *world.box_bodies]
    expected = np.array([[b.position.x, b.position.y, b.angle] for b in bodies])
    np.testing.assert_array_equal(world.state[: len(bodies), :3], expected)
