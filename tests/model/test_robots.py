"""The robot model (SPEC §4): photocells, Braitenberg control, energy."""

import numpy as np
import pytest

from sandbox.model import robots
from sandbox.model.config import Config


def test_sensor_points_follow_heading():
    pts = robots.sensor_points(np.array([[10.0, 20.0]]), np.array([np.pi / 2]), 0.1)[0]
    # Heading up (+y): front above, back below, left to the -x side, right to +x.
    assert pts == pytest.approx(np.array([[10, 20.1], [10, 19.9], [9.9, 20], [10.1, 20]]))


def test_braitenberg_by_hand():
    readings = np.array([[0.9, 0.5, 0.3, 0.4]])  # front, back, left, right
    v, w = robots.braitenberg(readings, 5.0, 20.0)
    assert v[0] == pytest.approx(5 * 0.4)
    assert w[0] == pytest.approx(20 * -0.1)  # brighter on the right: turn clockwise


def test_charge_step_by_hand_and_clamped():
    cfg = Config()
    charge = np.array([1.0, 0.0, 19.99])
    lum = np.array([0.5, 0.0, 2.0])
    v = np.array([0.2, 0.0, 0.0])
    w = np.array([-0.3, 0.0, 0.0])
    out = robots.charge_step(charge, lum, v, w, cfg)
    assert out[0] == pytest.approx(1.0 + 0.4 * 0.5 - 0.01 - 0.1 * 0.5)
    assert out[1] == 0.0  # never below empty
    assert out[2] == 20.0  # never above capacity


# --- the authors' program (SPEC §9 rows 6-9) --------------------------------

def test_corner_photocells_follow_heading():
    """Four cells at (+-0.1, +-0.1) in the body frame (x forward, y left)."""
    pts = robots.sensor_points(np.array([[10.0, 20.0]]), np.array([np.pi / 2]), 0.1, "corners")[0]
    # Facing +y: front-left is up and to -x, front-right up and to +x.
    assert pts == pytest.approx(np.array([[9.9, 20.1], [10.1, 20.1], [9.9, 19.9], [10.1, 19.9]]))


def test_program_control_law_by_hand():
    readings = np.array([[0.9, 0.5, 0.3, 0.4]])  # front-left, front-right, back-left, back-right
    v, w = robots.braitenberg(readings, 5.0, 20.0, "corners", "front")
    assert v[0] == pytest.approx(5 * ((0.9 + 0.5) - (0.3 + 0.4)))
    assert w[0] == pytest.approx(20 * (0.9 - 0.5))  # only the front pair steers
    _, w_sides = robots.braitenberg(readings, 5.0, 20.0, "corners", "sides")
    assert w_sides[0] == pytest.approx(20 * ((0.9 + 0.3) - (0.5 + 0.4)))


def test_readings_and_command_of_a_robot_beside_one_light():
    """A robot facing +x, 1 m below a light (program's field): its left cells
    are nearer the light, so it turns left (counter-clockwise) and, level with
    the light, neither drives forward nor back."""
    from sandbox.model.lights import luminosity_direct

    cfg = Config()
    pattern = np.zeros((64, 64))
    pattern[20, 30] = 1.0  # centre (20.5, 30.5)
    cells = robots.sensor_points(np.array([[20.5, 29.5]]), np.array([0.0]), cfg.sensor_offset, "corners")[0]
    readings = luminosity_direct(cells, pattern, cfg)

    def by_hand(dx, dy):
        return 1 / (dx**2 + dy**2 + 4) * 2 / np.sqrt(4 + dx**4 + dy**4)

    assert readings == pytest.approx([by_hand(0.1, -0.9), by_hand(0.1, -1.1), by_hand(-0.1, -0.9), by_hand(-0.1, -1.1)])
    v, w = robots.braitenberg(readings[None, :], cfg.k_drive, cfg.k_turn, "corners", "front")
    assert v[0] == pytest.approx(0.0, abs=1e-12)
    assert w[0] == pytest.approx(20 * (by_hand(0.1, -0.9) - by_hand(0.1, -1.1))) and w[0] > 0


def test_program_energy_uses_actual_motion_and_signed_turn():
    cfg = Config()
    charge = np.array([1.0, 1.0, 0.005])
    lum = np.array([0.5, 0.5, 0.0])
    speed = np.array([0.2, 0.2, 0.0])
    w = np.array([-0.3, 0.3, 0.0])
    out = robots.charge_step_actual(charge, lum, speed, w, cfg)
    assert out[0] == pytest.approx(1.0 + 0.4 * 0.5 - 0.01 - 0.1 * -0.3 - 0.1 * 0.2)  # clockwise turning pays back
    assert out[1] == pytest.approx(1.0 + 0.4 * 0.5 - 0.01 - 0.1 * 0.3 - 0.1 * 0.2)
    assert out[2] == 0.0
    absolute = robots.charge_step_actual(charge, lum, speed, w, cfg.replace(energy_turn_cost="absolute"))
    assert absolute[0] == pytest.approx(out[1])
