"""The compiled robot step equals the readable numpy formulas, bit for bit."""

import numpy as np
import pytest

from sandbox.model import kernels, robots
from sandbox.model.config import Config
from sandbox.model.lights import LightField
from sandbox.model.simulation import Simulation


class NumpySimulation(Simulation):
    """The simulation with the robots' step of :mod:`sandbox.model.robots` (numpy),
    the readable statement of the model, in place of the compiled kernels."""

    def _step_once(self) -> None:
        cfg = self.world.config
        state = self._sync()
        if self.controller.advance():
            self.lights.set_intensities(self.controller.intensities)
        nr = self.world.n_robots
        due = self._due[self.steps_done % cfg.command_period]
        args = (state, nr, due, self.lights.sample, cfg, self._command, self._readings, self._charge, self._applied)
        if cfg.motor == "continuous":
            velocities = robots.reference_step_continuous(*args)
            out = self.world.velocities
            out[:] = state[:, 3:6]
            out[:nr] = velocities * (1.0 / self.world.damping_per_step)  # as the kernel rounds it
            self.world.push_velocities()
        else:
            for r in robots.reference_step_set_once(*args):
                body = self.world.robot_bodies[r]
                body.velocity = tuple(state[r, 3:5])
                body.angular_velocity = state[r, 5]
        self.world.step()
        self.steps_done += 1
        self._fresh = False


@pytest.mark.parametrize("profile, falloff", [("paper-text", 1.0), ("paper-text", 2.0), ("authors-code", 2.0)])
def test_compiled_sampler_equals_numpy_sampler(profile, falloff):
    cfg = Config(profile=profile, light_falloff=falloff)
    field = LightField(cfg)
    rng = np.random.default_rng(3)
    field.set_intensities((rng.random((cfg.lights_per_side,) * 2) < 0.2).astype(float))
    pitch = cfg.light_pitch
    # Random points, points on strip boundaries and light-cell edges, and
    # points off the floor on every side.
    points = np.concatenate([
        rng.uniform(-3.0, cfg.arena_size + 3.0, (3000, 2)),
        np.stack(np.meshgrid(np.arange(0, cfg.arena_size, pitch / 10), [7.3, 31.0]), axis=-1).reshape(-1, 2),
        np.stack(np.meshgrid([0.3, 12.7], np.arange(0, cfg.arena_size + pitch, pitch) + field.axis.origin), axis=-1).reshape(-1, 2),
    ])
    expected = field.sample(points)
    layout = kernels.layout_of(kernels.sample_layout(field))
    got = np.array([kernels.sample_point(x, y, field.values_flat, layout) for x, y in points])
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("profile", ["paper-text", "authors-code"])
def test_compiled_step_equals_numpy_step_bit_for_bit(profile):
    cfg = Config(profile=profile, robots=60, boxes=120, arena_size=32.0, construction_size=8.0,
                 robot_spawn_size=16.0, update_every=20)
    fast, slow = Simulation(cfg, seed=5), NumpySimulation(cfg, seed=5)
    for _ in range(6):
        fast.step(250)
        slow.step(250)
        np.testing.assert_array_equal(fast.world.state, slow.world.state)
        np.testing.assert_array_equal(fast.robot_charges, slow.robot_charges)
        np.testing.assert_array_equal(fast.robot_sensors, slow.robot_sensors)
        np.testing.assert_array_equal(fast.robot_commands, slow.robot_commands)
    assert fast.cycle == slow.cycle and (fast.robot_charges > 0).any()
    assert np.abs(fast.robot_velocities).max() > 0  # robots really moved


def test_reads_land_on_each_bodys_row_whatever_order_the_batch_lists_them():
    """pymunk.batch lists sleeping bodies last: the scatter finds each body's row by its id, and
    looks again only where the order moved (here two bodies fall asleep, then one wakes)."""
    body_ids = np.array([40, 10, 30, 20, 50], dtype=np.uintp)  # row r holds the body with id body_ids[r]
    order = np.argsort(body_ids)
    rows, last_ids = np.zeros(5, dtype=np.intp), np.zeros(5, dtype=np.uintp)
    state = np.zeros((5, 6))
    for listed in ([0, 1, 2, 3, 4], [0, 4, 2, 3, 1], [0, 4, 3, 1, 2], [0, 4, 3, 1, 2], [1, 4, 3, 0, 2]):
        ids = body_ids[listed]
        read = np.array(listed, dtype=float)[:, None] * 10 + np.arange(6)  # row r's values: 10 r + column
        # Where the order did not move, no id is looked up: an index that would answer wrongly changes nothing.
        sorted_ids = body_ids[order] if not np.array_equal(ids, last_ids) else np.zeros(5, dtype=np.uintp)
        kernels.scatter_by_id(ids, read, last_ids, rows, sorted_ids, order, state)
        assert rows.tolist() == listed
        assert np.array_equal(state, np.arange(5)[:, None] * 10.0 + np.arange(6))
        state[:] = 0
