"""The one place the model touches pymunk's private code: the table :data:`USES`, its check, and the
functions the rest of the model calls instead.

pymunk has no public way to what three speed-ups need: a robot's velocity-update function in C
(:mod:`sandbox.model.undamped`), every body's state read from Chipmunk's memory and robots' velocities
set from compiled code (:mod:`sandbox.model.body_memory`), and the same setters through cffi where that
is not available (:mod:`sandbox.model.world`). They reach Chipmunk's C library through pymunk's private
cffi module, and a body's ``cpBody`` through its private ``_body``. Each such use is a row of
:data:`USES`: what we use, where in pymunk it is, why we need it, and how :func:`check` finds it.
:func:`check` runs before the first world is built and refuses, in one line naming the installed pymunk
and what it lacks, when any row is missing. ``tests/model/test_pymunk_seam.py`` fails when any other module of
``sandbox`` names pymunk's private code, and when this module uses a piece no row lists.

Where the fields of a ``cpBody`` lie in memory is no name, and stays in :mod:`sandbox.model.body_memory`:
it is read only after :func:`sandbox.model.body_memory.layout_holds` has checked it against pymunk's
getters, else through ``pymunk.batch``.

The private module is imported without failing where a pymunk lacks it: the model can still be imported,
and :func:`check` says what is missing.
"""

from __future__ import annotations

import functools
import importlib
from dataclasses import dataclass
from typing import Any, Callable

import pymunk

from sandbox.model.config_error import ConfigError

#: The pymunk release this module was written for and tested with (pinned in pyproject.toml).
WRITTEN_FOR = "7.3.1"
#: pymunk's cffi module: Chipmunk's library (``lib``) and the cffi instance that opened it (``ffi``).
CFFI = "pymunk._chipmunk_cffi"

try:
    from pymunk._chipmunk_cffi import ffi, lib
except ImportError:  # pragma: no cover - a pymunk without it: check() says so before any world is built
    ffi = lib = None

# How check() finds a row's piece.
ATTRIBUTE = "attribute"    # attributes of a module
C_FUNCTION = "C function"  # functions of Chipmunk's library, as cffi opened it (lib)
C_TYPE = "C type"          # C types that cffi knows by name (ffi)
BODY = "body"              # an attribute a new pymunk.Body has


@dataclass(frozen=True)
class Use:
    """One use of pymunk's private code: what, where in pymunk (``module`` or ``module:Class.attribute``),
    why, and how :func:`check` finds it (``names``: several attributes, functions or types of ``where``)."""

    what: str
    where: str
    why: str
    how: str = ATTRIBUTE
    names: tuple[str, ...] = ()


USES: tuple[Use, ...] = (
    Use("pymunk's cffi module", CFFI, "Chipmunk's C functions are reached through its lib, and cffi casts "
        "pointers and function addresses through its ffi", names=("ffi", "lib")),
    Use("a body's cpBody pointer", "pymunk:Body._body", "Chipmunk's functions take it, and its address is "
        "where body_memory reads the body's state", BODY, names=("_body",)),
    Use("Chipmunk's velocity setters", f"{CFFI}:lib", "robots' velocities set straight, waking the body: from "
        "compiled code by their addresses (body_memory), else through cffi (world)", C_FUNCTION,
        names=("cpBodySetVelocity", "cpBodySetAngularVelocity")),
    Use("Chipmunk's velocity-update function and its setter", f"{CFFI}:lib", "a robot's velocity function, "
        "compiled, calls Chipmunk's own with a damping of 1 (undamped)", C_FUNCTION,
        names=("cpBodyUpdateVelocity", "cpBodySetVelocityUpdateFunc")),
    Use("the type of a velocity-update function", f"{CFFI}:ffi", "the compiled function's address is cast to "
        "it (undamped)", C_TYPE, names=("cpBodyVelocityFunc",)),
)


class PymunkMismatch(ConfigError):
    """The installed pymunk lacks a piece of :data:`USES`: no world is built on it. A ConfigError, so the
    commands and the page refuse it in one line, as they do settings that cannot run."""


# ------------------------------------------------------------------ check
def check() -> None:
    """Refuse (one line) to build a world on a pymunk that lacks any piece of :data:`USES` (looked for once
    a process)."""
    absent = _installed_lacks()
    if absent:
        raise PymunkMismatch(f"pymunk {pymunk.version} lacks what sandbox/model/pymunk_seam.py uses from pymunk "
                             f"{WRITTEN_FOR}: {', '.join(absent)}; install pymunk=={WRITTEN_FOR}")


@functools.cache
def _installed_lacks() -> tuple[str, ...]:
    return tuple(missing())


def missing(uses: tuple[Use, ...] = USES) -> list[str]:
    """The pieces of ``uses`` the installed pymunk lacks, each as ``module:name``."""
    return [piece for use in uses for piece in _missing(use)]


def _missing(use: Use) -> list[str]:
    module_name, _, path = use.where.partition(":")
    try:
        target: Any = importlib.import_module(module_name)
    except ImportError:
        return [module_name]
    owner = path.rsplit(".", 1)[0] if use.how == BODY else path
    for part in owner.split(".") if owner else ():
        target = getattr(target, part, None)
        if target is None:
            return [f"{module_name}:{part}"]
    have = {
        ATTRIBUTE: lambda name: hasattr(target, name),
        C_FUNCTION: lambda name: hasattr(target, name),
        C_TYPE: lambda name: _knows_type(target, name),
        BODY: lambda name: hasattr(target(1.0, 1.0), name),
    }[use.how]
    return [f"{use.where.split(':')[0]}:{owner + '.' if owner else ''}{name}" for name in use.names if not have(name)]


def _knows_type(cffi: Any, name: str) -> bool:
    try:
        cffi.typeof(name)
    except Exception:  # cffi raises its own error for an unknown type
        return False
    return True


# ------------------------------------------------------------------ what the model calls
def body_pointer(body: pymunk.Body) -> Any:
    """The ``cpBody *`` that ``body`` wraps, as Chipmunk's functions (:func:`velocity_setters`) take it."""
    return body._body


def body_address(body: pymunk.Body) -> int:
    """Where ``body``'s ``cpBody`` lies in memory (the body must outlive every use of it)."""
    return int(ffi.cast("uintptr_t", body._body))


def velocity_setters() -> tuple[Callable[[Any, tuple[float, float]], None], Callable[[Any, float], None]]:
    """Chipmunk's ``cpBodySetVelocity(body, (vx, vy))`` and ``cpBodySetAngularVelocity(body, w)``, called
    through cffi with a :func:`body_pointer`."""
    return lib.cpBodySetVelocity, lib.cpBodySetAngularVelocity


def velocity_setter_addresses() -> tuple[int, int] | None:
    """The addresses of the two :func:`velocity_setters`, for compiled code to call (None on a pymunk that
    lacks them, on which :func:`check` refuses to build a world: read as a module loads, they must not fail)."""
    names = ("cpBodySetVelocity", "cpBodySetAngularVelocity")
    if lib is None or not all(hasattr(lib, name) for name in names):
        return None
    return _function_address(names[0]), _function_address(names[1])


def velocity_update_address() -> int:
    """The address of Chipmunk's own velocity-update function, ``cpBodyUpdateVelocity(body, gravity, damping,
    dt)``."""
    return _function_address("cpBodyUpdateVelocity")


def set_velocity_function(body: pymunk.Body, address: int) -> None:
    """Give ``body`` the C velocity-update function at ``address`` (it must outlive the body)."""
    lib.cpBodySetVelocityUpdateFunc(body._body, ffi.cast("cpBodyVelocityFunc", address))


def _function_address(name: str) -> int:
    return int(ffi.cast("uintptr_t", ffi.addressof(lib, name)))
