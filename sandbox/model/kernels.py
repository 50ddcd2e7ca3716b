"""The robots' per-step work, compiled with numba: one call per world step.

Each step every robot reads the light at its centre, charges and spends
energy, and is given a velocity (every robot with the paper text's
'continuous' motor; only refreshed and stopped ones with the authors'
'set-once' motor); robots at their refresh step also read their four
photocells and set a new command. Written with numpy (see
:mod:`sandbox.robots` and :meth:`sandbox.lights.LightField.sample`), that
is about 40 small array operations on 200 robots, each paying numpy's
per-call overhead; here it is one compiled loop. That halved the time our
own code takes per step (about 100 µs saved per step, measured in one
run), which matters because every microsecond outside ``Space.step`` is
one we control.

The formulas are those of :mod:`sandbox.robots` and the light sampling,
with the same floating-point operations in the same order, so a run gives
bit-for-bit the positions the numpy version gives (tested in
``tests/model/test_kernels.py`` against a numpy reference step).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from sandbox.model import body_memory, lights
from sandbox.model.config import Config
from sandbox.model.robots import PHOTOCELLS


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


# The kernels take their layout and parameters packed in one float64 array each, and unpack them
# into the NamedTuples above inside compiled code: numba's dispatcher checks an array's type in C,
# but a NamedTuple's in Python, field by field (2.8 µs a step for the two).


def sample_layout(lights) -> np.ndarray:
    """The compiled sampler's view of a :class:`sandbox.lights.LightField`, packed (see :func:`layout_of`)."""
    ax = lights.axis
    return np.array([float(ax.limit), float(ax.origin), 1.0 / ax.pitch, float(ax.pitch), ax.per_cell, ax.row_base,
                     ax.length, len(ax.knots_x), *ax.knots_x, *ax.knots_g])


@njit(cache=True, inline="always")
def layout_of(packed):
    """The :class:`SampleLayout` packed by :func:`sample_layout`."""
    m = int(packed[7])
    return SampleLayout(packed[0], packed[1], packed[2], packed[3], packed[8:8 + m], packed[8 + m:8 + 2 * m],
                        int(packed[4]), int(packed[5]), int(packed[6]))


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


class RobotParams(NamedTuple):
    """The robot model's numbers, as the kernels take them (see :func:`robot_params`)."""

    angles: np.ndarray  # direction of each photocell from the heading
    reach: float  # distance of each photocell from the centre
    drive: np.ndarray  # v = k_drive * drive . readings
    turn: np.ndarray  # w = k_turn * turn . readings
    k_drive: float
    k_turn: float
    eta_in: float
    metabolic: float
    eta_out: float
    capacity: float
    signed_turn_cost: bool


def robot_params(config) -> np.ndarray:
    """The kernels' view of a :class:`sandbox.config.Config`, packed (see :func:`params_of`)."""
    cells = PHOTOCELLS[config.photocells]
    return np.array([*cells.angles, *cells.drive, *cells.turn[config.steering],
                     config.sensor_offset * cells.reach, config.k_drive, config.k_turn, config.eta_in,
                     config.metabolic, config.eta_out, config.capacity, config.energy_turn_cost == "signed"],
                    dtype=float)


@njit(cache=True, inline="always")
def params_of(packed):
    """The :class:`RobotParams` packed by :func:`robot_params` (four photocells)."""
    return RobotParams(packed[0:4], packed[12], packed[4:8], packed[8:12], packed[13], packed[14], packed[15],
                       packed[16], packed[17], packed[18], packed[19] != 0.0)


@njit(cache=True)
def _refresh_commands(state, due, field, lay, rp, command, readings):
    """Robots in ``due`` read their photocells and set (v, w) (Braitenberg)."""
    for d in due:
        x, y, h = state[d, 0], state[d, 1], state[d, 2]
        v = 0.0
        w = 0.0
        for k in range(4):
            a = h + rp.angles[k]  # as robots.sensor_points
            px = math.cos(a) * rp.reach + x
            py = math.sin(a) * rp.reach + y
            readings[d, k] = sample_point(px, py, field, lay)
        for k in range(4):  # as robots.weighted: left to right
            v = v + rp.drive[k] * readings[d, k]
            w = w + rp.turn[k] * readings[d, k]
        command[d, 0] = rp.k_drive * v
        command[d, 1] = rp.k_turn * w


@njit(cache=True)
def robot_step_continuous(state, n_robots, due, field, lay, rp, velocity_scale, command, readings, charge,
                          applied, velocities):
    """One world step of the paper text's robots, in place: the command is the
    body's velocity every step, along its current heading.

    ``state`` rows are (x, y, angle, vx, vy, w) for robots, then boxes, then
    the static body; ``velocities`` receives (vx, vy, w) for every row:
    robots' new ones (divided by the space's damping factor, so they arrive
    unchanged) and everything else's current ones, ready for pymunk.batch. ``lay`` and ``rp`` are
    packed by :func:`sample_layout` and :func:`robot_params`.
    """
    lay, rp = layout_of(lay), params_of(rp)
    _refresh_commands(state, due, field, lay, rp, command, readings)
    for r in range(n_robots):
        lum = sample_point(state[r, 0], state[r, 1], field, lay)
        moving = 1.0 if charge[r] > 0.0 else 0.0  # an empty robot cannot move
        v = command[r, 0] * moving
        w = command[r, 1] * moving
        applied[r, 0] = v
        applied[r, 1] = w
        gained = rp.eta_in * lum
        spent = rp.metabolic + rp.eta_out * (abs(v) + abs(w))
        charge[r] = min(max(charge[r] + gained - spent, 0.0), rp.capacity)
        h = state[r, 2]
        velocities[r, 0] = v * math.cos(h) * velocity_scale
        velocities[r, 1] = v * math.sin(h) * velocity_scale
        velocities[r, 2] = w * velocity_scale
    for b in range(n_robots, state.shape[0]):
        velocities[b, 0] = state[b, 3]
        velocities[b, 1] = state[b, 4]
        velocities[b, 2] = state[b, 5]


@njit(cache=True)
def robot_step_set_once(state, n_robots, due, field, lay, rp, command, readings, charge, applied, writes):
    """One world step of the authors' program's robots, in place.

    A robot at its refresh step reads its photocells and its body's velocity
    is set, once, to ``v`` along its current heading and ``w``; otherwise the
    body keeps whatever velocity the physics left it (robots are undamped).
    Every robot then pays for its actual motion (see
    :func:`sandbox.robots.charge_step_actual`) and a robot left with no
    charge is stopped. ``state`` is updated to match; each velocity to hand
    to pymunk is a row (robot, vx, vy, w) of ``writes``. Returns their number. ``lay`` and ``rp``
    are packed by :func:`sample_layout` and :func:`robot_params`.
    """
    lay, rp = layout_of(lay), params_of(rp)
    _refresh_commands(state, due, field, lay, rp, command, readings)
    n = 0
    for d in due:
        h = state[d, 2]
        v = command[d, 0]
        state[d, 3] = v * math.cos(h)
        state[d, 4] = v * math.sin(h)
        state[d, 5] = command[d, 1]
        writes[n, 0], writes[n, 1], writes[n, 2], writes[n, 3] = d, state[d, 3], state[d, 4], state[d, 5]
        n += 1
    for r in range(n_robots):
        lum = sample_point(state[r, 0], state[r, 1], field, lay)
        vx, vy, w = state[r, 3], state[r, 4], state[r, 5]
        turn = w if rp.signed_turn_cost else abs(w)
        c = charge[r] + (rp.eta_in * lum - rp.metabolic - rp.eta_out * turn - rp.eta_out * math.sqrt(vx * vx + vy * vy))
        if c <= 0.0:
            c = 0.0
            if vx != 0.0 or vy != 0.0 or w != 0.0:  # can't move: stopped (a no-op when still)
                state[r, 3] = state[r, 4] = state[r, 5] = 0.0
                writes[n, 0], writes[n, 1], writes[n, 2], writes[n, 3] = r, 0.0, 0.0, 0.0
                n += 1
        elif c > rp.capacity:
            c = rp.capacity
        charge[r] = c
        h = state[r, 2]
        applied[r, 0] = state[r, 3] * math.cos(h) + state[r, 4] * math.sin(h)  # forward speed
        applied[r, 1] = state[r, 5]
    return n


@njit(cache=True)
def scatter_by_id(ids, rows_read, last_ids, rows, sorted_ids, id_order, state):
    """Copy the rows pymunk.batch read (``rows_read[i]`` for the body with id ``ids[i]``) into
    ``state`` at each body's own row. The batch lists sleeping bodies after awake ones, so the
    order moves whenever a group falls asleep or wakes (every other step in a trial): only the
    positions whose id changed since the last read (``last_ids``) look up their row again
    (``id_order[searchsorted(sorted_ids, id)]``). In numpy, comparing the ids, searching them and a
    fancy-indexed copy cost 26 µs a step of 700 bodies; this loop costs a few. Same values copied:
    bit for bit what numpy wrote."""
    for i in range(ids.shape[0]):
        if ids[i] != last_ids[i]:
            rows[i] = id_order[np.searchsorted(sorted_ids, ids[i])]
            last_ids[i] = ids[i]
        row = rows[i]
        for k in range(state.shape[1]):
            state[row, k] = rows_read[i, k]


_warm = False


def warm_up() -> None:
    """Compile (or load from numba's on-disk cache) before the first real step,
    so that a first step does not take seconds: a benchmark times only
    stepping, and a live view does not stall when it starts."""
    global _warm
    if _warm:
        return
    lay = np.array([4.0, 0.0, 1.0, 1.0, 3, 4, 24, 2, 0.0, 1.0, 0.0, 2.0])  # as sample_layout packs it
    field = np.zeros(24 * 24, dtype=np.float32)
    state = np.zeros((3, 6))
    # One call each compiles every case: the parameters' values, the turn cost's sign among them, are data.
    rp = robot_params(Config())
    due = np.zeros(1, dtype=np.intp)
    robot_step_continuous(state, 1, due, field, lay, rp, 1.0, np.zeros((1, 2)), np.zeros((1, 4)), np.zeros(1),
                          np.zeros((1, 2)), np.zeros((3, 3)))
    robot_step_set_once(state, 1, due, field, lay, rp, np.zeros((1, 2)), np.zeros((1, 4)), np.zeros(1),
                        np.zeros((1, 2)), np.zeros((2, 4)))
    ids = np.array([7, 5], dtype=np.uintp)
    scatter_by_id(ids, np.zeros((2, 6)), np.zeros(2, dtype=np.uintp), np.zeros(2, dtype=np.intp), np.sort(ids),
                  np.argsort(ids), np.zeros((2, 6)))
    body_memory.layout_holds()  # compiles (or loads) body_memory.read_rows on a real body
    if body_memory.SETTERS is not None:  # compiled (or loaded); no body is set
        body_memory.set_velocities(np.zeros(1, dtype=np.uintp), np.zeros((1, 4)), 0, *body_memory.SETTERS)
    lights.compiled_add_blocks(np.zeros((2, 2), dtype=np.float32), np.ones((1, 1), dtype=np.float32),
                               np.zeros(1, dtype=np.intp), np.zeros(1, dtype=np.intp), np.ones(1))
    _warm = True
