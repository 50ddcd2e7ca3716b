"""The simulation: a seeded, resettable, steppable state machine (Gymnasium-style).

>>> sim = Simulation(Config(robots=20, boxes=30), seed=1)
>>> sim.step(100)
>>> sim.robot_positions.shape
(20, 2)

Everything a viewer needs is exposed as read-only numpy arrays. Nothing here
imports a GUI library. Not thread-safe: drive it from one thread.
"""

from __future__ import annotations

import hashlib
import time
from typing import Any, Callable

import numpy as np

from sandbox.model import budget, kernels, metrics, robots, watchdog
from sandbox.model.chase import ChaseController
from sandbox.model.config import STRATEGY_NAMES, Config, param
from sandbox.model.controller import Controller
from sandbox.model.family import make_goal
from sandbox.model.goal import Goal
from sandbox.model.lights import LightField, light_centres
from sandbox.model.programs import Observation, ProgramError, check_pattern, every_of, senses_of, source_of
from sandbox.model.world import World
from sandbox.shapes import ShapeError, shape_vertices


def _controller(config: Config, goal: Goal) -> Controller:
    """The controller for a goal, or a ShapeError naming the goal if it cannot fit the arena."""
    try:
        return ChaseController(config, goal)  # the paper's, with chase to switch on live
    except ShapeError as exc:
        raise ShapeError(f"{config.shape}: {exc}") from None


def _goal(config: Config, vertices: np.ndarray | None) -> Goal:
    """The goal fitted to this world, or a ShapeError naming it if it cannot be built here."""
    try:
        return make_goal(config, vertices)
    except ShapeError as exc:
        raise ShapeError(f"{config.shape}: {exc}") from None


def _read_only(a: np.ndarray) -> np.ndarray:
    v = a.view()
    v.flags.writeable = False
    return v


class Simulation:
    """The paper's model, headless.

    ``shape`` overrides ``config.shape``: polygon vertices (any position, size
    or orientation) or None for the circle. Without it, ``config.shape`` is
    resolved (a builtin name or a polygon file).

    :attr:`config` is the configuration the running world was built with,
    with the live changes made since (gains, energy, controller values,
    strategies, shape). A change that needs a new world (populations, sizes,
    the seed...) is not kept here: whoever asks for it keeps it and calls
    :meth:`reset` with ``config=`` (as the app's runner does).
    """

    def __init__(self, config: Config | None = None, *, seed: int | None = None,
                 shape: np.ndarray | None | str = "from-config", program: Any = None, open_ended: bool = False,
                 program_time_limit: float = watchdog.DEFAULT_LIMIT):
        self.config = config or Config()
        #: Seconds a user's light program may take for one reset or update (then: ProgramError).
        self.program_time_limit = program_time_limit
        #: Whether the run goes on past ``config.steps`` (the live app): then no controller
        #: plans for the run's end.
        self.open_ended = open_ended
        #: A light program of the user's (see sandbox.model.programs); None: the paper's controller.
        self.user_program = program
        if isinstance(shape, str):
            shape = shape_vertices(self.config.shape if shape == "from-config" else shape)
        self.shape_vertices = None if shape is None else np.asarray(shape, dtype=float)
        self.history: list[metrics.Sample] = []
        #: Told the start pattern at each reset (``start``) and every change of the lit pattern (``change``),
        #: each with its step: a :class:`sandbox.model.design.PatternRecorder`, or None.
        self.pattern_recorder: Any = None
        kernels.warm_up()
        self.reset(self.config.seed if seed is None else seed)

    # ------------------------------------------------------------------ life
    def reset(self, seed: int | None = None, config: Config | None = None,
              progress: Callable[[float], None] | None = None) -> None:
        """Rebuild the world, from ``config`` if given (else the current one). Same seed, same run.
        ``progress(fraction)`` hears how the building goes; if it raises, the
        exception propagates and the simulation is left as it was."""
        cfg = config or self.config
        if seed is not None:
            cfg = cfg.replace(seed=int(seed))
        # Every Config is checked against the memory budget when it is made; again here, where every world
        # is built, for one that came another way (unpickled from another process, made under a larger budget).
        budget.check_settings(cfg)
        rng = np.random.default_rng(cfg.seed)
        goal = _goal(cfg, self.shape_vertices)
        controller = self._new_controller(cfg, goal)  # first: a goal that cannot fit stops here
        world = World(cfg, rng, progress, goal)
        # The light field too (its largest arrays: settings too big for memory fail here, with a
        # MemoryError, and leave the running world as it was).
        lights = LightField(cfg)
        centres = _read_only(light_centres(cfg))  # the pitch and arena only change with a new world
        # Built: from here on nothing can fail halfway.
        self.config, self.seed, self.world, self.goal, self.controller = cfg, cfg.seed, world, goal, controller
        self.lights, self._centres = lights, centres
        self._start_program()
        if self.pattern_recorder is not None:  # a new world: its light program starts afresh
            self.pattern_recorder.start(0, self.lights.intensities, paper=self.user_program is None)
        self._layout = kernels.sample_layout(self.lights)
        self._robot_params = kernels.robot_params(cfg)
        n = cfg.robots
        self.steps_done = 0
        self._charge = np.full(n, float(cfg.start_charge))
        self._readings = np.zeros((n, 4))
        self._command = np.zeros((n, 2))  # (v, w) held between refreshes
        self._applied = np.zeros((n, 2))  # what the robot actually did (0 when empty)
        self._writes = np.zeros((2 * n, 4))  # (robot, vx, vy, w) rows for the 'set-once' motor
        # Each robot refreshes its command at its own random phase; robots due
        # at step s are those with (s + phase) % period == 0, listed per residue.
        phase = rng.integers(0, cfg.command_period, n)
        self._due = [np.flatnonzero((r + phase) % cfg.command_period == 0) for r in range(cfg.command_period)]
        self._fresh = True
        self.history = []
        #: Sum of all intensities over all steps so far (intensity x steps): the light energy spent.
        self.light_energy = 0.0
        #: Wall seconds spent in pymunk's Space.step, in light-pattern changes
        #: (controller redraw + field update) and in metrics, for `bench`.
        self.timings = {"physics": 0.0, "lights": 0.0, "metrics": 0.0}
        self._record()

    def _new_controller(self, config: Config, goal: Goal) -> Controller:
        controller = _controller(config, goal)
        controller.open_ended = self.open_ended
        return controller

    def step(self, n: int = 1) -> None:
        """Advance ``n`` world steps."""
        every = self.config.metrics_every
        for _ in range(int(n)):
            self._step_once()
            if self.steps_done % every == 0:
                self._record()
        self._sync()

    def _step_once(self) -> None:
        cfg = self.config
        state = self._sync()
        self._until_program -= 1
        if self._until_program <= 0:
            t0 = time.perf_counter()
            self._until_program = self._program_every
            pattern = self._call_program(self.program.update, self._observation())
            if pattern is not None:
                self.set_pattern(pattern)
                self.timings["lights"] += time.perf_counter() - t0
        self.light_energy += self._pattern_sum
        world = self.world
        if world.n_robots:
            # Photocells, commands, energy and velocities: SPEC §4 and §9, compiled.
            due = self._due[self.steps_done % cfg.command_period]
            if cfg.motor == "continuous":
                kernels.robot_step_continuous(
                    state, world.n_robots, due, self.lights.values_flat, self._layout, self._robot_params,
                    1.0 / world.damping_per_step, self._command, self._readings, self._charge, self._applied,
                    world.velocities)
                world.push_velocities()
            else:
                count = kernels.robot_step_set_once(
                    state, world.n_robots, due, self.lights.values_flat, self._layout, self._robot_params,
                    self._command, self._readings, self._charge, self._applied, self._writes)
                if count:
                    world.set_robot_velocities(self._writes, count)
        t0 = time.perf_counter()
        world.step()
        self.timings["physics"] += time.perf_counter() - t0
        self.steps_done += 1
        self._fresh = False

    def _sync(self) -> np.ndarray:
        if not self._fresh:
            self.world.read()
            self._fresh = True
        return self.world.state

    # ------------------------------------------------------ light programs
    @property
    def program(self) -> Any:
        """What decides the lights: the user's program, else the paper's controller."""
        return self.user_program if self.user_program is not None else self.controller

    @property
    def senses(self) -> frozenset:
        """What the light program may look at (recorded with the results)."""
        return senses_of(self.program)

    def use_program(self, program: Any) -> None:
        """Hand the lights to ``program`` (None: back to the paper's controller), keeping the world.
        If the program fails to start, the previous one stays (the ProgramError propagates)."""
        previous = self.user_program
        self.user_program = program
        try:
            senses_of(self.program)
            self._start_program()
        except Exception:
            self.user_program = previous
            self._start_program()
            raise
        if (previous is not None or program is not None) and self.pattern_recorder is not None:
            self.pattern_recorder.cycles_lost()  # the controller's cycle no longer counts the whole run

    def _start_program(self) -> None:
        program = self.program
        if program is self.controller:
            first = self.controller.intensities
        else:  # what reset returned, else dark until the first update
            reset = getattr(program, "reset", None)
            first = self._call_program(reset, self.config, self.goal) if callable(reset) else None
            if first is None:
                first = np.zeros_like(self.controller.intensities)
        self._program_every = self._program_period()  # read after reset, which may set ``every``
        self._until_program = 1  # asked at the first step
        self.set_pattern(first)

    def _program_period(self) -> int:
        """World steps between two calls of the program: its ``every``, else ``update_every``."""
        return every_of(self.program, self.config.update_every)

    def _call_program(self, method: Callable, *args: Any) -> Any:
        """The light program's method. A user's program runs within its time limit, and whatever goes
        wrong in it (an exception, an overrun, even SystemExit) is a one-line ProgramError; the paper's
        controller is ours, called directly (a bug in it is a bug, with its traceback)."""
        if self.user_program is None:
            return method(*args)
        name = f"{type(self.program).__name__}.{method.__name__}"
        try:
            return watchdog.limited(method, *args, limit=self.program_time_limit, what=name,
                                    source=source_of(self.program))
        except ProgramError:
            raise
        except watchdog.ProgramTimeout as exc:
            raise ProgramError(f"{exc}{self._when(method)}") from None
        except BaseException as exc:
            raise ProgramError(f"{name} failed{self._when(method)}: {type(exc).__name__}: {exc}") from exc

    def _when(self, method: Callable) -> str:
        return f" at step {self.steps_done}" if getattr(method, "__name__", "") == "update" else ""

    def set_pattern(self, pattern: Any) -> None:
        """Light this pattern now (one intensity per light, [ix, iy]); the light program may change it at
        its next update."""
        if self.program is not self.controller:
            who = f"{type(self.program).__name__}.update"
            pattern = check_pattern(pattern, self.controller.intensities.shape, who)
        changed = self.lights.set_intensities(pattern)
        self._pattern_sum = float(np.sum(pattern))
        self._pattern_seen = _read_only(self.lights.intensities)  # what observations show, until the next
        if changed and self.pattern_recorder is not None:
            self.pattern_recorder.change(self.steps_done, self.lights.intensities)

    def _observation(self) -> Observation:
        # Asked every step by the paper's controller: the pattern's view is made when it changes.
        # The senses are asked each time: chase's change with its strategy.
        return Observation(self.steps_done, self.goal, self._centres, self._pattern_seen, self.senses,
                           self._sensed)

    def _sensed(self, name: str) -> np.ndarray:
        return np.array(getattr(self, name))  # a copy: the program cannot move anything

    # ------------------------------------------------------------ changes
    def set_strategies(self, **values: float) -> None:
        """Change flare / switch / no_corners live; applied at the next controller update."""
        self.config = self.config.replace(**values)
        self.controller.set_strategies(**values)

    def update_config(self, **changes) -> list[str]:
        """Change parameters of the running simulation: every value is checked;
        the live ones apply now (strategies at the next controller update; gains,
        energy and other controller values at once). Returns the names of the
        others, which need a new world: they are *not* applied or kept here; pass
        them to :meth:`reset` in ``config=`` when the time comes."""
        self.config.replace(**changes)  # validates everything first
        deferred = [k for k in changes if param(k).rebuild]
        live = {k: v for k, v in changes.items() if k not in deferred}
        if "shape" in live:
            name = str(live.pop("shape"))
            self.set_shape(shape_vertices(name), name=name)
        if "outline" in live:
            self.set_outline(live.pop("outline"))
        strategies = {k: live.pop(k) for k in STRATEGY_NAMES if k in live}
        if live:
            # The controller takes the new values and keeps its place in the cycle.
            self.config = self.config.replace(**live)
            self._robot_params = kernels.robot_params(self.config)
            self.controller.reconfigure(self.config)
            # A program without its own ``every`` follows update_every, from its next call.
            self._program_every = self._program_period()
            self._until_program = min(self._until_program, self._program_every)
        if strategies:
            self.set_strategies(**strategies)
        return deferred

    def set_shape(self, vertices: np.ndarray | None, name: str | None = None) -> list[str]:
        """Change the goal (None = circle) without touching robots or boxes.
        The new outline starts contracting from its largest size. A goal that
        does not fit the arena is refused (ShapeError) and nothing changes;
        returns what there is to say about the fit (see Controller.notes)."""
        shape = None if vertices is None else np.asarray(vertices, dtype=float)
        config = self.config if name is None else self.config.replace(shape=name)
        goal = _goal(config, shape)
        controller = self._new_controller(config, goal)
        controller.set_strategies(**{name_: getattr(config, name_) for name_ in STRATEGY_NAMES})
        self.shape_vertices, self.config, self.goal, self.controller = shape, config, goal, controller
        if self.pattern_recorder is not None:
            self.pattern_recorder.cycles_lost()  # the new controller counts its cycles from 0
        self._start_program()
        return controller.notes

    def set_outline(self, outline: str) -> list[str]:
        """Choose the outline family ('auto', 'scaled' or 'offset'): the goal is fitted again (an offset
        goal may move inside the construction wall) and its outline starts from its largest size.
        Returns the notes about the goal; nothing changes if it is refused (ShapeError)."""
        previous = self.config
        self.config = self.config.replace(outline=outline)
        try:
            return self.set_shape(self.shape_vertices)
        except BaseException:
            self.config = previous
            raise

    # ------------------------------------------------------------- state
    @property
    def robot_positions(self) -> np.ndarray:
        return _read_only(self.world.state[: self.world.n_robots, 0:2])

    @property
    def robot_headings(self) -> np.ndarray:
        return _read_only(self.world.state[: self.world.n_robots, 2])

    @property
    def robot_charges(self) -> np.ndarray:
        return _read_only(self._charge)

    @property
    def robot_sensors(self) -> np.ndarray:
        """Photocell readings (front, back, left, right) at each robot's last refresh."""
        return _read_only(self._readings)

    @property
    def robot_commands(self) -> np.ndarray:
        """Held (forward speed, turn rate) commands, shape (n, 2)."""
        return _read_only(self._command)

    @property
    def robot_velocities(self) -> np.ndarray:
        """What each robot is actually doing: its command, or zero when out of charge."""
        return _read_only(self._applied)

    @property
    def box_positions(self) -> np.ndarray:
        return _read_only(self.world.state[self.world.n_robots : -1, 0:2])

    @property
    def box_angles(self) -> np.ndarray:
        return _read_only(self.world.state[self.world.n_robots : -1, 2])

    @property
    def box_in_goal(self) -> np.ndarray:
        return self.goal.contains(self.box_positions)

    @property
    def light_intensities(self) -> np.ndarray:
        return _read_only(self.lights.intensities)

    @property
    def phase(self) -> str:
        return self.controller.phase

    @property
    def phase_said(self) -> str:
        """The phase in words, and what the band does in it beyond the paper's (a light program: its phase)."""
        return getattr(self.controller, "phase_said", self.controller.phase)

    @property
    def gathering(self) -> str:
        """The goal's sides beside which alone the band is lit now ('' the whole band, or a light program)."""
        return getattr(self.controller, "gathering", "")

    @property
    def cycle(self) -> int:
        return self.controller.cycle

    @property
    def outline(self) -> np.ndarray:
        return _read_only(self.controller.outline)

    @property
    def time(self) -> float:
        return self.steps_done * self.config.dt

    def sensor_points(self, index: int) -> np.ndarray:
        """Where robot ``index``'s four photocells are now, shape (4, 2)."""
        cfg = self.config
        return robots.sensor_points(self.robot_positions[index : index + 1], self.robot_headings[index : index + 1],
                                    cfg.sensor_offset, cfg.photocells)[0]

    # ----------------------------------------------------------- metrics
    def measure(self) -> metrics.Sample:
        boxes = self.box_positions
        in_goal = self.goal.contains(boxes)
        cfg = self.config
        return metrics.Sample(
            step=self.steps_done,
            fraction_in_goal=metrics.fraction_in_goal(in_goal),
            mean_outside_distance=metrics.mean_outside_distance(boxes, self.goal, in_goal),
            boxes_escaped=int(metrics.escaped(boxes, cfg.centre, cfg.construction_size).sum()),
            charged_robots=int((self._charge > 0).sum()),
            cycle=self.controller.cycle,
            phase=self.controller.phase,
        )

    def _record(self) -> None:
        t0 = time.perf_counter()
        self._sync()
        self.history.append(self.measure())
        self.timings["metrics"] += time.perf_counter() - t0

    def state_digest(self) -> str:
        """A short fingerprint of everything that evolves: bodies (positions, angles, velocities),
        charges, held commands, the lit pattern and the step. Same seed and settings, same digest;
        golden tests keep it from moving unnoticed."""
        self._sync()
        digest = hashlib.sha256()
        for array in (self.world.state, self._charge, self._command, self.lights.intensities):
            digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        digest.update(str(self.steps_done).encode())
        return digest.hexdigest()[:16]

    def has_nan(self) -> bool:
        return not (np.isfinite(self.world.state).all() and np.isfinite(self._charge).all())
