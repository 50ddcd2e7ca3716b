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
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

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
    senses = frozenset(getattr(program, "senses", frozenset()) or ())
    unknown = senses - SENSES
    if unknown:
        raise ProgramError(f"{type(program).__name__}.senses: unknown {sorted(unknown)}; "
                           f"choose from {sorted(SENSES)}")
    return senses


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


def load_program(spec: str) -> Any:
    """A light program from ``path/to/module.py:ClassName`` (or ``package.module:ClassName``),
    instantiated without arguments; a ProgramError in one line if it cannot be."""
    path, sep, class_name = str(spec).rpartition(":")
    if not sep or not path or not class_name:
        raise ProgramError(f"--controller {spec!r}: expected path/to/module.py:ClassName")
    try:
        if path.endswith(".py"):
            file = Path(path)
            if not file.is_file():
                raise ProgramError(f"--controller {spec!r}: no such file {path}")
            module_name = f"phototaxis_program_{abs(hash(str(file.resolve())))}"
            module_spec = importlib.util.spec_from_file_location(module_name, file)
            module = importlib.util.module_from_spec(module_spec)
            sys.modules[module_name] = module  # so the class pickles to sweep's workers by reference
            module_spec.loader.exec_module(module)
        else:
            module = importlib.import_module(path)
    except ProgramError:
        raise
    except Exception as exc:  # a user's file: any error in it is a one-line message
        raise ProgramError(f"--controller {spec!r}: cannot load it: {type(exc).__name__}: {exc}") from None
    cls = getattr(module, class_name, None)
    if cls is None:
        raise ProgramError(f"--controller {spec!r}: {path} has no {class_name}")
    try:
        program = cls()
    except Exception as exc:
        raise ProgramError(f"--controller {spec!r}: {class_name}() failed: {type(exc).__name__}: {exc}") from None
    if not callable(getattr(program, "update", None)):
        raise ProgramError(f"--controller {spec!r}: {class_name} has no update(observation) method")
    senses_of(program)
    return program
