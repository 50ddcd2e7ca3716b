"""Reading bodies from Chipmunk's memory gives, bit for bit, what pymunk's getters and batch give."""

import math

import numpy as np
import pymunk

from sandbox.model import body_memory, pymunk_seam
from sandbox.model.config import Config
from sandbox.model.simulation import Simulation


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.uint64)


def test_a_body_reads_back_its_getters_values():
    """Hand-set values, and a centre of gravity off the body's origin, so that the position
    (Chipmunk's transform applied to (0, 0)) is not the field holding the centre of gravity."""
    assert body_memory.layout_holds()  # pymunk 7 on a 64-bit machine, as this project pins
    space = pymunk.Space()
    body = pymunk.Body(1.0, 1.0)
    space.add(body, pymunk.Poly.create_box(body, (1.0, 2.0)))
    body.center_of_gravity = (0.5, 0.25)
    body.position, body.angle = (3.0, -7.5), -1.25
    body.velocity, body.angular_velocity = (0.125, -2.0), 0.75
    state = np.zeros((1, 6))

    def getters() -> np.ndarray:
        return np.array([[*body.position, body.angle, *body.velocity, body.angular_velocity]])

    body_memory.read_rows(body_memory.addresses([body]), state)
    # Turning about the centre of gravity moved the origin (what Chipmunk calls the position).
    assert state[0, 2:].tolist() == [-1.25, 0.125, -2.0, 0.75] and state[0, 0] != 3.0
    assert np.array_equal(bits(state), bits(getters()))
    space.step(0.1)  # moved by Chipmunk's integration: still what the getters say
    before = state.copy()
    body_memory.read_rows(body_memory.addresses([body]), state)
    assert not np.array_equal(state[:, :3], before[:, :3])
    assert np.array_equal(bits(state), bits(getters()))


def test_a_running_world_reads_as_through_the_batch():
    """Robots and boxes fall asleep and wake (the batch's order moves): every row still matches
    the batch's read, sleeping bodies included."""
    sim = Simulation(Config(seed=2))
    world = sim.world
    assert world._addresses is not None
    asleep = set()
    for _ in range(12):
        sim.step(250)
        from_memory = world.read().copy()
        assert np.array_equal(bits(from_memory), bits(world._read_batch()))
        asleep.add(sum(b.is_sleeping for b in world.box_bodies))
    assert max(asleep) > 0 and len(asleep) > 1  # bodies did sleep, and not always the same number


def test_without_the_layout_the_batch_reads_the_same_run(monkeypatch):
    """Where the layout is not known to hold, worlds read through the batch, and the run is the same."""
    def run() -> str:
        sim = Simulation(Config(robots=40, boxes=80, seed=5))
        sim.step(1500)
        return sim.state_digest()

    from_memory = run()
    monkeypatch.setattr(body_memory, "layout_holds", lambda: False)
    sim = Simulation(Config(robots=40, boxes=80, seed=5))
    assert sim.world._addresses is None
    assert run() == from_memory


def test_the_continuous_motor_reads_through_the_batch():
    """Its velocities go back through the batch, in the order only the batch's read keeps."""
    sim = Simulation(Config(robots=20, boxes=40, motor="continuous"))
    assert sim.world._addresses is None
    sim.step(200)
    assert not math.isnan(sim.world.state.sum())


def test_compiled_setters_set_and_wake_as_chipmunks_setters_through_cffi():
    """Each row sets a velocity and an angular velocity, in turn (a body twice: the last row wins),
    and wakes a sleeping body, as the same setters called through cffi do."""
    assert body_memory.SETTERS is not None  # x86-64 or AArch64, as the project's machines

    def world() -> tuple[pymunk.Space, list[pymunk.Body]]:
        space = pymunk.Space()
        space.sleep_time_threshold = 0.05
        bodies = [pymunk.Body(1.0, 1.0) for _ in range(3)]
        for k, body in enumerate(bodies):
            body.position = (3.0 * k, 0.0)
            space.add(body, pymunk.Circle(body, 0.5))
        for _ in range(20):
            space.step(0.01)
        assert all(body.is_sleeping for body in bodies)
        return space, bodies

    writes = np.array([[2, 0.5, -1.0 / 3.0, 0.25], [0, 1e-3, 2.0, -7.0], [2, 1.5, 0.0, -0.125]])
    space, bodies = world()
    body_memory.set_velocities(body_memory.addresses(bodies), writes, 3, *body_memory.SETTERS)
    space_c, bodies_c = world()
    set_velocity, set_angular_velocity = pymunk_seam.velocity_setters()
    for row, vx, vy, w in writes.tolist():
        body = pymunk_seam.body_pointer(bodies_c[int(row)])
        set_velocity(body, (vx, vy))
        set_angular_velocity(body, w)
    for compiled, through_cffi in zip(bodies, bodies_c):
        assert (compiled.velocity, compiled.angular_velocity, compiled.is_sleeping) == \
            (through_cffi.velocity, through_cffi.angular_velocity, through_cffi.is_sleeping)
    assert [b.velocity for b in bodies] == [(1e-3, 2.0), (0.0, 0.0), (1.5, 0.0)]
    assert [b.is_sleeping for b in bodies] == [False, True, False]
