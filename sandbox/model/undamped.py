"""Bodies that pymunk's space damping does not slow: the robots of the
authors' program.

pymunk (Chipmunk2D) has one damping factor for the whole space, applied in
each body's velocity-update function, while in the authors' Box2D program
only the boxes are damped: a robot keeps the velocity it was set to until a
collision or the next command changes it. So robots get their own velocity
function, which calls Chipmunk's default one with a damping factor of 1.

A Python velocity function would cost a call back into Python per robot
per step (about 200 µs a step for 200 robots). Instead the function is a
tiny numba ``cfunc``, a C function pointer handed to Chipmunk, so the
physics never leaves C. Chipmunk passes the gravity vector (a struct of two
doubles) by value; on x86-64 System V and AArch64 such a struct travels
exactly like two separate double arguments, which is what the cfunc
declares. Elsewhere (Windows, 32-bit) the same behaviour comes from a
slower Python velocity function.
"""

from __future__ import annotations

import ctypes
import platform
import sys

import pymunk

from sandbox.model import pymunk_seam

#: Where a struct of two doubles passed by value is laid out like two doubles.
VECT_AS_TWO_DOUBLES = sys.platform != "win32" and platform.machine().lower() in ("x86_64", "amd64", "aarch64", "arm64")

_cfunc_address: int | None = None


def _compiled_velocity_function() -> int:
    """Address of the C velocity function (compiled once per process: it
    embeds the address of Chipmunk's own function, so it is not cached)."""
    global _cfunc_address, _keep
    if _cfunc_address is None:
        from numba import cfunc, types

        default = pymunk_seam.velocity_update_address()
        signature = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                                     ctypes.c_double)
        update_velocity = signature(default)

        @cfunc(types.void(types.voidptr, types.float64, types.float64, types.float64, types.float64))
        def velocity_without_damping(body, gravity_x, gravity_y, damping, dt):
            update_velocity(body, gravity_x, gravity_y, 1.0, dt)

        _keep = velocity_without_damping  # the function must outlive every body that uses it
        _cfunc_address = velocity_without_damping.address
    return _cfunc_address


def _python_velocity_function(body: pymunk.Body, gravity, damping: float, dt: float) -> None:
    pymunk.Body.update_velocity(body, gravity, 1.0, dt)


def make_undamped(body: pymunk.Body) -> None:
    """Let ``body`` ignore the space's damping (gravity and forces still apply)."""
    if VECT_AS_TWO_DOUBLES:
        pymunk_seam.set_velocity_function(body, _compiled_velocity_function())
    else:  # pragma: no cover - other platforms
        body.velocity_func = _python_velocity_function
