"""A phototaxic robot (SPEC §4) as vectorised formulas over the whole swarm.

Each robot has four photocells (front, back, left, right), drives as a
Braitenberg vehicle, ``v = k_drive (front - back)``, ``w = k_turn (left - right)``,
and lives on the light it receives: ``charge += eta_in Lum - metabolic - eta_out (|v| + |w|)``.
"""

from __future__ import annotations

import numpy as np

from .config import Config

FRONT, BACK, LEFT, RIGHT = range(4)
SENSOR_NAMES = ("front", "back", "left", "right")

#: Direction of each photocell in the robot's frame, as an angle from its heading.
SENSOR_ANGLES = np.array([0.0, np.pi, np.pi / 2, -np.pi / 2])


def sensor_points(positions: np.ndarray, headings: np.ndarray, offset: float) -> np.ndarray:
    """Floor points under each robot's four photocells, shape (n, 4, 2)."""
    a = headings[:, None] + SENSOR_ANGLES[None, :]
    out = np.empty(a.shape + (2,))
    np.multiply(np.cos(a), offset, out=out[..., 0])
    np.multiply(np.sin(a), offset, out=out[..., 1])
    out += positions[:, None, :]
    return out


def braitenberg(readings: np.ndarray, k_drive: float, k_turn: float) -> tuple[np.ndarray, np.ndarray]:
    """Forward speed and turn rate (counter-clockwise positive) from (n, 4) readings."""
    v = k_drive * (readings[:, FRONT] - readings[:, BACK])
    w = k_turn * (readings[:, LEFT] - readings[:, RIGHT])
    return v, w


def charge_step(charge: np.ndarray, luminosity: np.ndarray, v: np.ndarray, w: np.ndarray,
                config: Config) -> np.ndarray:
    """One step of the energy store, clamped to [0, capacity]."""
    gained = config.eta_in * luminosity
    spent = config.metabolic + config.eta_out * (np.abs(v) + np.abs(w))
    return (charge + gained - spent).clip(0.0, config.capacity)


def charge_colours(charge: np.ndarray, capacity: float) -> np.ndarray:
    """Display colours, (n, 3) floats in [0, 1]: red when empty, green when full."""
    f = np.clip(charge / capacity if capacity > 0 else np.ones_like(charge), 0.0, 1.0)
    red = np.array([0.90, 0.16, 0.16])
    green = np.array([0.18, 0.80, 0.25])
    return red + f[:, None] * (green - red)
