"""Reading every body's pose and velocity straight from Chipmunk's memory, in one compiled loop;
setting robots' velocities through Chipmunk's setters from compiled code.

``World.read`` needs, each step, the position, angle, velocity and angular
velocity of all 700 bodies. ``pymunk.batch.get_space_bodies`` walks the
space (awake bodies, then each sleeping group), pushes every value into a
growing C array, and lists the bodies in an order that moves whenever a
group falls asleep or wakes, so the rows must be matched to bodies by id:
24-38 µs a step, a tenth of a whole step. Here a compiled loop reads the
six numbers of each body at a fixed place inside its ``cpBody`` struct, in
our own row order: 2.4 µs, and nothing to match.

The values are exactly those pymunk's getters return: the angle and the
velocities are plain fields, and the position is Chipmunk's
``cpTransformPoint(transform, (0, 0))`` (``a*0 + c*0 + tx``), computed here
with the same operations in the same order.

Where the struct lies comes from Munk2D's ``chipmunk_structs.h`` (the
Chipmunk2D fork inside pymunk 7), which is not part of pymunk's API (nor
are the bodies' addresses and the setters: :mod:`sandbox.model.pymunk_seam`
hands them out). So it
is used only with pymunk 7, and only after :func:`layout_holds` has checked
it against pymunk's own getters on a body whose centre of gravity is off its
origin (where the position is not the field ``p``). Anything else reads
through ``pymunk.batch``, as before; ``World`` also compares the two reads
once, when a world is built.

A robot whose command is refreshed (4 a step in a trial, 40 at 10x the
population) gets its velocity through ``cpBodySetVelocity`` and
``cpBodySetAngularVelocity``, which also wake it. From Python, through cffi,
that cost 1.4 µs a robot; :func:`set_velocities` calls the same two C
functions from compiled code, by their addresses. ``cpBodySetVelocity``
takes its vector (a struct of two doubles) by value, which on x86-64 System V
and AArch64 travels exactly like two doubles, as :mod:`undamped` relies on
too; elsewhere the setters are called through cffi.
"""

from __future__ import annotations

import ctypes
import functools
import math

import numpy as np
import pymunk
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from sandbox.model import pymunk_seam
from sandbox.model.undamped import VECT_AS_TWO_DOUBLES

# Byte offsets of the fields in struct cpBody (Munk2D, 64-bit): two function
# pointers, m, m_inv, i, i_inv (doubles), cog, p, v, f (vectors), a, w, t, then
# the transform (a, b, c, d, tx, ty).
_V = 80
_ANGLE, _W = 112, 120
_TRANSFORM = 136


@intrinsic
def _load_double(typingctx, address):
    """The double at memory ``address`` (an integer): what C's ``*(double *)address`` reads."""
    if not isinstance(address, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        return builder.load(builder.inttoptr(args[0], ir.DoubleType().as_pointer()))

    return types.float64(address), codegen


@intrinsic
def _call_with_two_doubles(typingctx, function, body, x, y):
    """Call the C function ``void f(void *body, double x, double y)`` at address ``function``."""
    if not all(isinstance(t, types.Integer) for t in (function, body)):
        return None

    def codegen(context, builder, signature, args):
        pointer = ir.IntType(8).as_pointer()
        kind = ir.FunctionType(ir.VoidType(), [pointer, ir.DoubleType(), ir.DoubleType()])
        function_pointer = builder.inttoptr(args[0], kind.as_pointer())
        builder.call(function_pointer, [builder.inttoptr(args[1], pointer), args[2], args[3]])
        return context.get_dummy_value()

    return types.void(function, body, types.float64, types.float64), codegen


@intrinsic
def _call_with_double(typingctx, function, body, x):
    """Call the C function ``void f(void *body, double x)`` at address ``function``."""
    if not all(isinstance(t, types.Integer) for t in (function, body)):
        return None

    def codegen(context, builder, signature, args):
        pointer = ir.IntType(8).as_pointer()
        kind = ir.FunctionType(ir.VoidType(), [pointer, ir.DoubleType()])
        builder.call(builder.inttoptr(args[0], kind.as_pointer()), [builder.inttoptr(args[1], pointer), args[2]])
        return context.get_dummy_value()

    return types.void(function, body, types.float64), codegen


#: Addresses of Chipmunk's velocity setters, for :func:`set_velocities` (None where the vector's
#: passing is not known to match two doubles).
SETTERS = pymunk_seam.velocity_setter_addresses() if VECT_AS_TWO_DOUBLES else None


@njit(cache=True)
def set_velocities(addresses, writes, count, set_velocity, set_angular_velocity):
    """For each of the first ``count`` rows (row, vx, vy, w) of ``writes``, in turn, set the velocity
    and then the angular velocity of the body at ``addresses[row]``, with Chipmunk's setters (at
    addresses ``set_velocity`` and ``set_angular_velocity``: :data:`SETTERS`)."""
    for n in range(count):
        body = addresses[int(writes[n, 0])]
        _call_with_two_doubles(set_velocity, body, writes[n, 1], writes[n, 2])
        _call_with_double(set_angular_velocity, body, writes[n, 3])


@njit(cache=True)
def read_rows(addresses, state):
    """``state[row] = (x, y, angle, vx, vy, w)`` of the ``cpBody`` at ``addresses[row]``, every row."""
    for row in range(addresses.shape[0]):
        body = addresses[row]
        ta, tb = _load_double(body + _TRANSFORM), _load_double(body + _TRANSFORM + 8)
        tc, td = _load_double(body + _TRANSFORM + 16), _load_double(body + _TRANSFORM + 24)
        state[row, 0] = ta * 0.0 + tc * 0.0 + _load_double(body + _TRANSFORM + 32)
        state[row, 1] = tb * 0.0 + td * 0.0 + _load_double(body + _TRANSFORM + 40)
        state[row, 2] = _load_double(body + _ANGLE)
        state[row, 3] = _load_double(body + _V)
        state[row, 4] = _load_double(body + _V + 8)
        state[row, 5] = _load_double(body + _W)


def addresses(bodies: list[pymunk.Body]) -> np.ndarray:
    """The ``cpBody`` address of each body, as :func:`read_rows` takes them. The bodies must
    outlive every read (the world keeps them)."""
    return np.array([pymunk_seam.body_address(body) for body in bodies], dtype=np.uintp)


@functools.cache
def layout_holds() -> bool:
    """Whether this pymunk's ``cpBody`` is laid out as :func:`read_rows` reads it: pymunk 7, and a
    body with distinct values and an off-centre centre of gravity reads back what pymunk's getters
    say, bit for bit."""
    if not pymunk.version.startswith("7.") or ctypes.sizeof(ctypes.c_void_p) != 8:
        return False
    space = pymunk.Space()
    body = pymunk.Body(2.0, 3.0)
    space.add(body, pymunk.Circle(body, 0.5, offset=(0.75, -0.25)))
    body.center_of_gravity = (0.75, -0.25)
    body.position, body.angle = (1.25, -2.5), 0.375
    body.velocity, body.angular_velocity = (3.5, -4.75), 5.125
    space.step(0.01)  # the transform now comes from Chipmunk's own integration
    state = np.full((1, 6), math.nan)
    read_rows(addresses([body]), state)
    expected = np.array([[*body.position, body.angle, *body.velocity, body.angular_velocity]])
    return bool(np.array_equal(state.view(np.uint64), expected.view(np.uint64)))
