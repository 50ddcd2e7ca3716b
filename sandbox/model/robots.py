"""A phototaxic robot (SPEC §4) as vectorised formulas over the whole swarm.

Each robot has four photocells and drives as a Braitenberg vehicle: forward
speed ``v = k_drive (front cells - back cells)`` and turn rate
``w = k_turn (left cells - right cells)``, counter-clockwise positive, so it
turns toward the brighter side. It lives on the light it receives:
``charge += eta_in Lum - metabolic - motion cost``.

Where the photocells sit, which of them steer and what motion costs differ
between the paper's text and the authors' program (``Config.photocells``,
``steering``, ``energy_turn_cost``):

* paper text: cells on the body axes (front, back, left, right), steering
  from left minus right, cost ``eta_out (|v| + |w|)`` of the command;
* the authors' program: cells at the four diagonal corners ``(+-d, +-d)`` of
  the body frame, drive from the front pair minus the back pair, steering
  from the front pair only, and cost ``eta_out (speed + w)`` of the body's
  actual motion with ``w`` *signed* (a robot turning clockwise gains charge).

These numpy functions are the readable statement of the model; the compiled
per-step kernels in :mod:`sandbox.kernels` do the same arithmetic.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sandbox.model.config import Config


class Photocells(NamedTuple):
    """A photocell layout and the control law's weights on its four cells."""

    names: tuple[str, str, str, str]
    #: Direction of each cell from the robot's centre, as an angle from its heading.
    angles: np.ndarray
    #: Distance of each cell from the centre, in units of ``sensor_offset``.
    reach: float
    #: v = k_drive * drive . readings
    drive: np.ndarray
    #: w = k_turn * turn[steering] . readings
    turn: dict[str, np.ndarray]


PHOTOCELLS = {
    "axes": Photocells(
        ("front", "back", "left", "right"),
        np.array([0.0, np.pi, np.pi / 2, -np.pi / 2]), 1.0,
        np.array([1.0, -1.0, 0.0, 0.0]),
        # Only the side cells steer, whichever rule: they are the front-most side cells too.
        {"sides": np.array([0.0, 0.0, 1.0, -1.0]), "front": np.array([0.0, 0.0, 1.0, -1.0])}),
    "corners": Photocells(
        ("front-left", "front-right", "back-left", "back-right"),
        np.array([np.pi / 4, -np.pi / 4, 3 * np.pi / 4, -3 * np.pi / 4]), math.sqrt(2.0),
        np.array([1.0, 1.0, -1.0, -1.0]),
        {"sides": np.array([1.0, -1.0, 1.0, -1.0]), "front": np.array([1.0, -1.0, 0.0, 0.0])}),
}

#: The paper text's layout, for code that shows one robot's cells by name.
SENSOR_NAMES = PHOTOCELLS["axes"].names
SENSOR_ANGLES = PHOTOCELLS["axes"].angles


def sensor_points(positions: np.ndarray, headings: np.ndarray, offset: float,
                  layout: str = "axes") -> np.ndarray:
    """Floor points under each robot's four photocells, shape (n, 4, 2)."""
    cells = PHOTOCELLS[layout]
    a = headings[:, None] + cells.angles[None, :]
    out = np.empty(a.shape + (2,))
    np.multiply(np.cos(a), offset * cells.reach, out=out[..., 0])
    np.multiply(np.sin(a), offset * cells.reach, out=out[..., 1])
    out += positions[:, None, :]
    return out


def braitenberg(readings: np.ndarray, k_drive: float, k_turn: float, layout: str = "axes",
                steering: str = "sides") -> tuple[np.ndarray, np.ndarray]:
    """Forward speed and turn rate (counter-clockwise positive) from (n, 4) readings."""
    cells = PHOTOCELLS[layout]
    return k_drive * weighted(readings, cells.drive), k_turn * weighted(readings, cells.turn[steering])


def weighted(readings: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """sum_i weights[i] * readings[:, i], added left to right (as the kernels do)."""
    total = np.zeros(len(readings))
    for i in range(4):
        total = total + weights[i] * readings[:, i]
    return total


def charge_step(charge: np.ndarray, luminosity: np.ndarray, v: np.ndarray, w: np.ndarray,
                config: Config) -> np.ndarray:
    """One step of the paper text's energy store, clamped to [0, capacity]:
    the motion cost is ``eta_out (|v| + |w|)`` of what the robot is commanded to do."""
    gained = config.eta_in * luminosity
    spent = config.metabolic + config.eta_out * (np.abs(v) + np.abs(w))
    return (charge + gained - spent).clip(0.0, config.capacity)


def charge_step_actual(charge: np.ndarray, luminosity: np.ndarray, speed: np.ndarray, w: np.ndarray,
                       config: Config) -> np.ndarray:
    """One step of the authors' program's energy store: the motion cost is
    ``eta_out (speed + w)`` of the body's actual motion, ``w`` signed when
    ``energy_turn_cost`` is 'signed' (|w| when 'absolute'); clamped to
    [0, capacity]. A robot whose charge reaches 0 is stopped by the caller."""
    turn = w if config.energy_turn_cost == "signed" else np.abs(w)
    delta = config.eta_in * luminosity - config.metabolic - config.eta_out * turn - config.eta_out * speed
    return (charge + delta).clip(0.0, config.capacity)


def reference_step_continuous(state: np.ndarray, n: int, due: np.ndarray, sample, config: Config,
                              command: np.ndarray, readings: np.ndarray, charge: np.ndarray,
                              applied: np.ndarray) -> np.ndarray:
    """One world step of the paper text's robots, in numpy: the readable
    reference for :func:`sandbox.kernels.robot_step_continuous` (the same
    arithmetic; a test holds them equal bit for bit). ``sample(points)`` is
    the luminosity field. Updates the arrays in place; returns the robots'
    new velocities, (n, 3) rows (vx, vy, w), before damping compensation."""
    positions, headings = state[:n, 0:2], state[:n, 2]
    _refresh(positions, headings, due, sample, config, command, readings)
    moving = charge[:n] > 0.0  # an empty robot cannot move
    np.multiply(command, moving[:, None], out=applied)
    v, w = applied[:, 0], applied[:, 1]
    charge[:] = charge_step(charge, sample(positions), v, w, config)
    return np.stack([v * np.cos(headings), v * np.sin(headings), w], axis=1)


def reference_step_set_once(state: np.ndarray, n: int, due: np.ndarray, sample, config: Config,
                            command: np.ndarray, readings: np.ndarray, charge: np.ndarray,
                            applied: np.ndarray) -> np.ndarray:
    """One world step of the authors' program's robots, in numpy: the
    reference for :func:`sandbox.kernels.robot_step_set_once`. Robots in
    ``due`` get their velocity set once along their heading; every robot
    pays for its actual motion; an empty one is stopped. Updates ``state``
    (the robots' velocities) and the other arrays in place; returns the
    indices of the robots whose velocity pymunk must be given."""
    positions, headings = state[:n, 0:2], state[:n, 2]
    _refresh(positions, headings, due, sample, config, command, readings)
    v = command[due, 0]
    state[due, 3], state[due, 4], state[due, 5] = v * np.cos(headings[due]), v * np.sin(headings[due]), command[due, 1]
    velocity = state[:n, 3:6]
    speed = np.sqrt(velocity[:, 0] * velocity[:, 0] + velocity[:, 1] * velocity[:, 1])
    charge[:] = charge_step_actual(charge, sample(positions), speed, velocity[:, 2], config)
    stopped = (charge[:n] <= 0.0) & (velocity != 0.0).any(axis=1)
    velocity[stopped] = 0.0
    applied[:, 0] = velocity[:, 0] * np.cos(headings) + velocity[:, 1] * np.sin(headings)
    applied[:, 1] = velocity[:, 2]
    return np.concatenate([due, np.flatnonzero(stopped)])


def _refresh(positions, headings, due, sample, config, command, readings) -> None:
    """Robots in ``due`` read their photocells and set their command."""
    cells = sensor_points(positions[due], headings[due], config.sensor_offset, config.photocells)
    readings[due] = sample(cells.reshape(-1, 2)).reshape(-1, 4)
    v, w = braitenberg(readings[due], config.k_drive, config.k_turn, config.photocells, config.steering)
    command[due, 0], command[due, 1] = v, w
