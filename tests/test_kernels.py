"""The compiled robot step equals the readable numpy formulas, bit for bit."""

import numpy as np
import pytest

from sandbox import kernels, robots
from sandbox.config import Config
from sandbox.lights import LightField
from sandbox.simulation import Simulation


class NumpySimulation(Simulation):
    """The simulation with the robots' step written with numpy, as
    :mod:`sandbox.robots` and ``LightField.sample`` state the model."""

    def _step_once(self) -> None:
        cfg = self.world.config
        state = self._sync()
        if self.controller.advance():
            self.lights.set_intensities(self.controller.intensities)
        nr = self.world.n_robots
        positions, headings = state[:nr, 0:2], state[:nr, 2]
        due = self._due[self.steps_done % cfg.command_period]
        cells = robots.sensor_points(positions[due], headings[due], cfg.sensor_offset).reshape(-1, 2)
        lum = self.lights.sample(np.concatenate([positions, cells]))
        readings = lum[nr:].reshape(-1, 4)
        self._readings[due] = readings
        v, w = robots.braitenberg(readings, cfg.k_drive, cfg.k_turn)
        self._command[due, 0], self._command[due, 1] = v, w
        moving = self._charge > 0.0
        np.multiply(self._command, moving[:, None], out=self._applied)
        v, w = self._applied[:, 0], self._applied[:, 1]
        self._charge = robots.charge_step(self._charge, lum[:nr], v, w, cfg)
        scale = 1.0 / self.world.damping_per_step
        out = self.world.velocities
        out[:] = state[:, 3:6]
        out[:nr, 0] = v * np.cos(headings) * scale
        out[:nr, 1] = v * np.sin(headings) * scale
        out[:nr, 2] = w * scale
        self.world.push_velocities()
        self.world.step()
        self.steps_done += 1
        self._fresh = False


@pytest.mark.parametrize("falloff", [1.0, 2.0])
def test_compiled_sampler_equals_numpy_sampler(falloff):
    cfg = Config(light_falloff=falloff)
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
    layout = kernels.sample_layout(field)
    got = np.array([kernels.sample_point(x, y, field.values_flat, layout) for x, y in points])
    np.testing.assert_array_equal(got, expected)


def test_compiled_step_equals_numpy_step_bit_for_bit():
    cfg = Config(robots=60, boxes=120, arena_size=32.0, construction_size=8.0, robot_spawn_size=16.0,
                 update_every=20)
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
