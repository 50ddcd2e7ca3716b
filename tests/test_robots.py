"""The robot model (SPEC §4): photocells, Braitenberg control, energy."""

import numpy as np
import pytest

from sandbox import robots
from sandbox.config import Config


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


def test_colours_red_to_green():
    c = robots.charge_colours(np.array([0.0, 20.0, 10.0]), 20.0)
    assert c[0][0] > c[0][1] and c[1][1] > c[1][0]
    assert c[2] == pytest.approx((c[0] + c[1]) / 2)
