"""A trial: one simulation run of one case with one seed.

:func:`run_sweep_trial` is a top-level function of plain data, so it can be
shipped to local worker processes or to a Dask cluster alike (see
:mod:`.executors`); :mod:`.storage` keeps what it returns.
"""

from __future__ import annotations

import re
import socket
import time
from dataclasses import dataclass, field

import numpy as np

from sandbox.model.config import Config

METRICS = ("fraction_in_goal", "mean_outside_distance")


class SweepError(Exception):
    """A problem with a sweep a user can fix (shown as one line)."""


def run_sweep_trial(config: dict, seed: int, steps: int, shape: list | None, controller: str | None = None,
                    program_time_limit: float | None = None) -> dict:
    """Run one trial and return its samples, configuration and final layout.

    ``config`` is a full configuration as from ``Config.to_dict()``; ``shape``
    the goal polygon's vertices (None for the circle), resolved by the caller
    so workers need not see the user's shape files; ``controller`` a light
    program as ``path.py:ClassName`` (loaded in the worker), None for the paper's.
    """
    from sandbox.model.programs import load_program, paper_controller_name
    from sandbox.model.simulation import Simulation  # only in the worker: the parent need not load numba

    cfg = Config(**config).replace(seed=int(seed), steps=int(steps))
    start, cpu = time.perf_counter(), time.process_time()
    program = load_program(controller) if controller else None
    sim = Simulation(cfg, shape=None if shape is None else np.asarray(shape, dtype=float), program=program)
    sim.step(cfg.steps)
    if sim.has_nan():
        raise RuntimeError(f"the simulation produced NaN (seed {seed})")
    samples = [s.to_dict() for s in sim.history]
    if samples[-1]["step"] != sim.steps_done:
        samples.append(sim.measure().to_dict())
    return {
        "config": cfg.to_dict(),
        "seed": cfg.seed,
        "steps": cfg.steps,
        "seconds": round(time.perf_counter() - start, 3),
        "cpu_seconds": round(time.process_time() - cpu, 3),
        "host": socket.gethostname(),
        "controller": controller or paper_controller_name(cfg),
        "outline": sim.goal.family,  # the family the goal took (config's outline may say 'auto')
        "outline_reason": sim.goal.family_reason,  # why, and what it does with the goal's notches
        "senses": sorted(sim.senses),  # what the light program looked at
        "light_energy": round(sim.light_energy, 3),  # sum of all intensities over all steps
        "samples": samples,
        "final": {
            "box_positions": np.round(sim.box_positions, 4).tolist(),
            "box_angles": np.round(sim.box_angles, 4).tolist(),
            "box_in_goal": sim.box_in_goal.astype(int).tolist(),
            "robot_positions": np.round(sim.robot_positions, 4).tolist(),
            "goal_outline": np.round(sim.goal.outline(), 5).tolist(),
        },
    }


def check_program(trial: "Trial") -> None:
    """Start the trial's light program on its world and let it light the first update, here and
    now: a program that fails or overruns at once is a one-line SweepError before any worker starts."""
    from sandbox.model import watchdog
    from sandbox.model.programs import ProgramError, load_program
    from sandbox.model.simulation import Simulation

    limit = watchdog.DEFAULT_LIMIT if trial.program_time_limit is None else trial.program_time_limit
    cfg = Config(**trial.config)
    try:
        program = load_program(trial.controller, time_limit=limit)
        sim = Simulation(cfg, shape=None if trial.shape is None else np.asarray(trial.shape, dtype=float),
                         program=program, program_time_limit=limit)
        sim.step(1)
    except ProgramError as exc:
        raise SweepError(f"trial {trial.name}: {exc}") from None


@dataclass(frozen=True)
class Trial:
    case: str
    seed: int
    config: dict = field(compare=False, hash=False)  # full config dict, seed and steps included
    shape: list | None = field(default=None, compare=False, hash=False)
    controller: str | None = field(default=None, compare=False, hash=False)  # a light program's path:Class
    program_time_limit: float | None = field(default=None, compare=False, hash=False)

    @property
    def name(self) -> str:
        return f"{self.case} seed {self.seed}"


def slug(label: str) -> str:
    """A file-system-safe folder name for a case label."""
    return re.sub(r"[^A-Za-z0-9._=+-]+", "_", label).strip("_") or "case"
