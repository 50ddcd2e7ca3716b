"""Light programs: anything that decides which lights are on.

A light program is an object with

- ``senses``: a set drawn from ``{"boxes", "robots"}``, what it may look at
  (an overhead camera, say). An open-loop program senses nothing;
- ``every``: world steps between two calls of :meth:`update` (0 or None: the
  configuration's ``update_every``, 100 steps by default);
- ``reset(config, goal)``: called when a world is built; it may return the
  first pattern (else the floor is dark until the first update);
- ``update(observation)``: returns the new pattern, one intensity per light
  (an (n, n) array indexed [ix, iy], or n * n values in that order), or None
  to keep the current one.

The paper's controller is one (:class:`sandbox.model.controller.Controller`;
the simulation's, :class:`sandbox.model.chase.ChaseController`, senses the
boxes while its chase strategy is on), called every step with an observation
like any other; :class:`LightProgram` is a base class for others. A user's
program's pattern is checked at every update: a wrong shape, a negative or
non-finite value stops the run with a :class:`ProgramError` that says so.

>>> class Blink(LightProgram):
...     def update(self, observation):
...         on = (observation.step // 1000) % 2
...         return np.full(observation.lights_shape, float(on))
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from sandbox.model import watchdog
from sandbox.model.config import Config

SENSES = frozenset({"boxes", "robots"})
#: How result files name the paper's controller in their ``controller`` field.
PAPER_CONTROLLER = "paper (open loop)"


def paper_controller_name(config: Config) -> str:
    """How result files name the paper's controller: with *chase* it senses the boxes."""
    return "paper (closed loop: chase)" if config.chase > 0 else PAPER_CONTROLLER


class ProgramError(ValueError):
    """A light program that cannot be used: the message says why, in one line."""


@dataclass(frozen=True)
class Observation:
    """What a light program is told at an update.

    Always: the step, the goal (``goal.centre``, ``goal.vertices`` - None for
    the circle -, ``goal.contains(points)``, ``goal.outline()``), the lights'
    centres (n, n, 2) and the current pattern. The boxes' and robots' state
    only to a program that declared it senses them."""

    step: int
    goal: Any
    light_centres: np.ndarray
    intensities: np.ndarray
    senses: frozenset
    _read: Callable[[str], np.ndarray]

    @property
    def lights_shape(self) -> tuple[int, int]:
        return self.intensities.shape

    def _sensed(self, what: str, name: str) -> np.ndarray:
        if what not in self.senses:
            raise ProgramError(f"this light program reads {name} but does not sense {what!r}: "
                               f"declare senses = {{{what!r}}}")
        return self._read(name)

    @property
    def box_positions(self) -> np.ndarray:
        return self._sensed("boxes", "box_positions")

    @property
    def robot_positions(self) -> np.ndarray:
        return self._sensed("robots", "robot_positions")

    @property
    def robot_charges(self) -> np.ndarray:
        return self._sensed("robots", "robot_charges")


class LightProgram:
    """Base class of a light program (see the module's docstring)."""

    senses: frozenset = frozenset()
    every: int | None = None

    def reset(self, config: Config, goal: Any) -> np.ndarray | None:
        self.config, self.goal = config, goal
        return None

    def update(self, observation: Observation) -> np.ndarray | None:
        raise NotImplementedError


def senses_of(program: Any) -> frozenset:
    """The program's declared senses, checked."""
    declared = getattr(program, "senses", frozenset()) or ()
    if isinstance(declared, str) or not isinstance(declared, (set, frozenset, list, tuple)):
        raise ProgramError(f"{type(program).__name__}.senses must be a set such as {{'boxes'}}, not {declared!r}")
    senses = frozenset(declared)
    unknown = senses - SENSES
    if unknown:
        raise ProgramError(f"{type(program).__name__}.senses: unknown {sorted(unknown)}; "
                           f"choose from {sorted(SENSES)}")
    return senses


def every_of(program: Any, default: int) -> int:
    """World steps between two calls of the program: its ``every`` (checked), else ``default``."""
    every = getattr(program, "every", None)
    if every is None or every == 0:
        return max(1, int(default))
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 0:
        raise ProgramError(f"{type(program).__name__}.every must be a whole number of world steps "
                           f"(0 or None: every update_every steps), not {every!r}")
    return int(every)


def source_of(program: Any) -> str | None:
    """The file the program's class was written in, if it has one (to say where it overran)."""
    try:
        return inspect.getsourcefile(type(program))
    except (TypeError, OSError):
        return None


def check_pattern(pattern: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    """The pattern as an (n, n) float array, or a ProgramError saying what is wrong with it."""
    try:
        array = np.asarray(pattern, dtype=float)
    except (TypeError, ValueError):
        raise ProgramError(f"{name} returned {type(pattern).__name__}, not an array of intensities") from None
    if array.size != shape[0] * shape[1] or array.ndim not in (1, 2) or (array.ndim == 2 and array.shape != shape):
        raise ProgramError(f"{name} returned a pattern of shape {array.shape}; expected {shape} "
                           f"(one intensity per light) or ({shape[0] * shape[1]},)")
    if not np.isfinite(array).all() or (array < 0).any():
        raise ProgramError(f"{name} returned negative or non-finite intensities")
    return array.reshape(shape)


def load_program(spec: str, *, time_limit: float = watchdog.DEFAULT_LIMIT) -> Any:
    """A light program from ``path/to/module.py:ClassName`` (or ``package.module:ClassName``),
    instantiated without arguments; a ProgramError in one line if it cannot be. Importing the
    module runs its code: that and the class's construction each have ``time_limit`` seconds, and
    nothing they raise (SystemExit included) gets past this function."""
    path, sep, class_name = str(spec).rpartition(":")
    if not sep or not path or not class_name:
        raise ProgramError(f"--controller {spec!r}: expected path/to/module.py:ClassName")
    try:
        module = watchdog.limited(_import, path, spec, limit=time_limit, what=f"importing {path}",
                                  source=path if path.endswith(".py") else None)
    except ProgramError:
        raise
    except BaseException as exc:  # a user's file: anything it does is a one-line message, never an exit
        raise ProgramError(f"--controller {spec!r}: cannot load it: {_one_line(exc)}") from None
    cls = getattr(module, class_name, None)
    if cls is None:
        raise ProgramError(f"--controller {spec!r}: {path} has no {class_name}")
    try:
        program = watchdog.limited(cls, limit=time_limit, what=f"{class_name}()",
                                   source=path if path.endswith(".py") else None)
    except BaseException as exc:
        raise ProgramError(f"--controller {spec!r}: {class_name}() failed: {_one_line(exc)}") from None
    if not callable(getattr(program, "update", None)):
        raise ProgramError(f"--controller {spec!r}: {class_name} has no update(observation) method")
    senses_of(program)
    every_of(program, 1)
    return program


def _import(path: str, spec: str) -> Any:
    if not path.endswith(".py"):
        return importlib.import_module(path)
    file = Path(path)
    if not file.is_file():
        raise ProgramError(f"--controller {spec!r}: no such file {path}")
    module_name = f"phototaxis_program_{abs(hash(str(file.resolve())))}"
    module_spec = importlib.util.spec_from_file_location(module_name, file)
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[module_name] = module  # so the class pickles to sweep's workers by reference
    try:
        module_spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(module_name, None)
        raise
    return module


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0][:300]}" if text else type(exc).__name__
