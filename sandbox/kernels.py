"""The robots' per-step work, compiled with numba: one call per world step.

Each step every robot reads the light at its centre, charges and spends
energy, and is given a velocity; robots at their refresh step also read
their four photocells and set a new command. Written with numpy (see
:mod:`sandbox.robots` and :meth:`sandbox.lights.LightField.sample`), that
is about 40 small array operations on 200 robots, each paying numpy's
per-call overhead; here it is one compiled loop. That halved the time our
own code takes per step (about 100 µs saved per step, measured in one
run), which matters because every microsecond outside ``Space.step`` is
one we control.

The formulas are those of :mod:`sandbox.robots` and the light sampling,
with the same floating-point operations in the same order, so a run gives
bit-for-bit the positions the numpy version gives (tested in
``tests/test_kernels.py`` against a numpy reference step).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .robots import SENSOR_ANGLES  # numba freezes this global array as a constant


class SampleLayout(NamedTuple):
    """What the compiled sampler needs from :class:`sandbox.lights._AxisLayout`."""

    limit: float
    origin: float
    inv_pitch: float
    pitch: float
    knots_x: np.ndarray  # position within a layout cell -> sample coordinate,
    knots_g: np.ndarray  # piecewise linear (at most 2 strips, so at most 4 knots)
    per_cell: int
    row_base: int
    length: int  # samples per side of the field array


def sample_layout(lights) -> SampleLayout:
    """The compiled sampler's view of a :class:`sandbox.lights.LightField`."""
    ax = lights.axis
    return SampleLayout(float(ax.limit), float(ax.origin), 1.0 / ax.pitch, float(ax.pitch),
                        ax.knots_x, ax.knots_g, int(ax.per_cell), int(ax.row_base), int(ax.length))


@njit(cache=True, inline="always")
def _interp(x, xp, fp):
    """``np.interp(x, xp, fp)`` for one value and at most 4 knots, with numpy's
    arithmetic: a linear search for knot j with xp[j] <= x < xp[j + 1], then
    ``slope * (x - xp[j]) + fp[j]``."""
    m = xp.shape[0]
    if x > xp[m - 1]:
        return fp[m - 1]
    if x < xp[0]:
        return fp[0]
    i = 1
    while i < m and x >= xp[i]:
        i += 1
    j = i - 1
    if j == m - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + fp[j]


@njit(cache=True, inline="always")
def _locate(x, lay):
    """Row of the sample at or before ``x`` and the fraction to the next:
    ``_AxisLayout.locate`` for one coordinate."""
    if x < 0.0:
        x = 0.0
    elif x > lay.limit:
        x = lay.limit
    x -= lay.origin
    cell = math.floor(x * lay.inv_pitch)
    g = _interp(x - cell * lay.pitch, lay.knots_x, lay.knots_g)
    i = int(g)
    return int(cell) * lay.per_cell + lay.row_base + i, g - i


@njit(cache=True)
def sample_point(x, y, field, lay):
    """Luminosity at (x, y): bilinear within strips, as ``LightField.sample``."""
    rx, fu = _locate(x, lay)
    ry, fv = _locate(y, lay)
    n = lay.length
    flat = rx * n + ry
    f00 = field[flat]
    f10 = field[flat + n] - f00
    f01 = field[flat + 1] - f00
    f11 = field[flat + (n + 1)] - f00 - f10 - f01
    return f00 + fu * f10 + fv * (f01 + fu * f11)


@njit(cache=True)
def _refresh_commands(state, due, field, lay, offset, k_drive, k_turn, command, readings):
    """Robots in ``due`` read their photocells and set (v, w) (Braitenberg)."""
    for d in due:
        x, y, h = state[d, 0], state[d, 1], state[d, 2]
        for k in range(4):
            a = h + SENSOR_ANGLES[k]  # front, back, left, right, as robots.sensor_points
            px = math.cos(a) * offset + x
            py = math.sin(a) * offset + y
            readings[d, k] = sample_point(px, py, field, lay)
        command[d, 0] = k_drive * (readings[d, 0] - readings[d, 1])
        command[d, 1] = k_turn * (readings[d, 2] - readings[d, 3])


@njit(cache=True)
def robot_step(state, n_robots, due, field, lay, offset, k_drive, k_turn, eta_in, metabolic, eta_out,
               capacity, velocity_scale, command, readings, charge, applied, velocities):
    """One world step of robot work, in place.

    ``state`` rows are (x, y, angle, vx, vy, w) for robots, then boxes, then
    the static body; ``velocities`` receives (vx, vy, w) for every row:
    robots' new ones (divided by the space's damping factor, so they arrive
    unchanged) and everything else's current ones, ready for pymunk.batch.
    """
    _refresh_commands(state, due, field, lay, offset, k_drive, k_turn, command, readings)
    for r in range(n_robots):
        lum = sample_point(state[r, 0], state[r, 1], field, lay)
        moving = 1.0 if charge[r] > 0.0 else 0.0  # an empty robot cannot move
        v = command[r, 0] * moving
        w = command[r, 1] * moving
        applied[r, 0] = v
        applied[r, 1] = w
        gained = eta_in * lum
        spent = metabolic + eta_out * (abs(v) + abs(w))
        charge[r] = min(max(charge[r] + gained - spent, 0.0), capacity)
        h = state[r, 2]
        velocities[r, 0] = v * math.cos(h) * velocity_scale
        velocities[r, 1] = v * math.sin(h) * velocity_scale
        velocities[r, 2] = w * velocity_scale
    for b in range(n_robots, state.shape[0]):
        velocities[b, 0] = state[b, 3]
        velocities[b, 1] = state[b, 4]
        velocities[b, 2] = state[b, 5]


_warm = False


def warm_up() -> None:
    """Compile (or load from numba's on-disk cache) before the first real step,
    so that a first step does not take seconds: a benchmark times only
    stepping, and a live view does not stall when it starts."""
    global _warm
    if _warm:
        return
    lay = SampleLayout(4.0, 0.0, 1.0, 1.0, np.array([0.0, 1.0]), np.array([0.0, 2.0]), 3, 4, 24)
    field = np.zeros(24 * 24, dtype=np.float32)
    state = np.zeros((3, 6))
    robot_step(state, 1, np.zeros(1, dtype=np.intp), field, lay, 0.1, 5.0, 20.0, 0.4, 0.01, 0.1, 20.0, 1.0,
               np.zeros((1, 2)), np.zeros((1, 4)), np.zeros(1), np.zeros((1, 2)), np.zeros((3, 3)))
    _warm = True
