"""The simulation thread: the only code that touches the :class:`Simulation`.

pymunk and the simulation are not thread-safe, and viser runs GUI and pointer
callbacks on its own threads. So callbacks never touch the simulation: they
submit a command (:mod:`sandbox.app.world.orders`) that the simulation loop
carries out between steps, in :meth:`Runner.handle`. After every frame's
worth of steps the loop copies what a viewer needs into an immutable
:class:`Snapshot`; a second thread hands the newest snapshot to the
listeners (the scene, the panel) at the frame rate, dropping stale ones, so
a slow browser never slows physics.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
import time
from collections import deque
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any, Callable, Iterator

import numpy as np

from sandbox.app.world.orders import (Apply, Arrival, CancelBuild, Command, Controls, Reset, RunnerStopped, RunTo,
                                  SetLamp, SetOutline, SetProgram, SetShape, Setting, SkipAhead, Start, StepOnce,
                                  UpdateConfig, WorldSpec, DesignOf, PlayDesign)
from sandbox.app.world.contract import Deliver, SimulationRunner, answer
from sandbox.app.world.snapshot import LAMP_PROGRAM, PAPER_PROGRAM, RobotView, Snapshot
from sandbox.model.design import MAX_PATTERNS, PatternRecorder

#: What lights the floor while a design's recorded light program plays (serve --design).
DESIGN_PROGRAM = "the design's recorded light program"
#: The goal :meth:`Runner.on_build` names for a world built around the running goal.
SAME_GOAL = "the running goal"
from sandbox.model import watchdog
from sandbox.model.config import Config
from sandbox.model.metrics import Sample

if TYPE_CHECKING:  # imported where a Runner is built: the web server itself never steps a world
    from sandbox.model.simulation import Simulation

#: The top of the speed slider means "as fast as the machine can": the loop
#: steps in chunks of FASTEST_CHUNK until the next frame is due.
FASTEST = 100
FASTEST_CHUNK = 10

#: How far (s) the world may fall behind its speed setting and still catch up. A frame that is late
#: (the machine busy with a browser, a garbage collection, steps that cost more) takes the steps of the
#: frames it missed too, and one snapshot: so a speed setting is the rate the world runs at, and a
#: loop short of time spends it on steps, not on pictures nobody sees. The default world's dense
#: phases (robots and boxes packed where the band closes) step at 620-840 steps/s on one core of the
#: test machine (seed 0, headless), under the default speed's 750: the world falls behind there for
#: 2-4 s at a time, and makes it up in the open phases that follow (4,000-11,000 steps/s). Further
#: behind (a machine that cannot keep up at all) the rest is let go, as a game's fixed-step loop caps
#: the time it catches up on, rather than racing.
BEHIND_AT_MOST = 2.0
#: How much (s) one frame catches up beyond its own steps: 3 frames' more at 30 frames/s, so that
#: catching up shows as a brief fast-forward, never as one long frame with no picture.
CATCH_UP_PER_FRAME = 0.1

log = logging.getLogger("sandbox.app.world.runner")


def frames_owed(due: float, now: float, interval: float, most_behind: float) -> int:
    """How many frames' steps the frame that was ``due`` takes, at ``now``: its own, and one for each
    whole ``interval`` it is late by, counting at most ``most_behind`` seconds of lateness."""
    late = min(max(now - due, 0.0), most_behind)
    return 1 + int(late // interval)


def next_frame_due(due: float, now: float, interval: float, most_behind: float) -> float:
    """When the frame after the one that was ``due`` is due, at ``now``: one ``interval`` after it,
    but never more than ``most_behind`` seconds in the past (the rest of a longer delay is let go)."""
    return max(due + interval, now - most_behind)


def wait_for(post: Callable, command: Any, timeout: float) -> Any:
    """``post(command)`` (a runner method, which returns the command's future), and its answer within
    ``timeout`` seconds (raises its exception). The future itself, not a callback: a callback may be
    delivered on the very thread that waits here."""
    return answer(post(command), timeout)


#: Which Runner method carries out each kind of command (filled by :func:`handles`).
HANDLERS: dict[type, Callable[["Runner", Any], Any]] = {}


def handles(kind: type) -> Callable:
    """Register the decorated Runner method as what carries out commands of ``kind``."""

    def register(method: Callable) -> Callable:
        HANDLERS[kind] = method
        return method

    return register


#: Patterns a live world's design keeps: as many as a design file holds (10,000 on the default grid,
#: ten default runs of the paper's controller; fewer on a larger grid), 5 MB kept as bits.
MOST_PATTERNS = MAX_PATTERNS
#: Steps between two progress reports of a skip ahead: 0.2-0.5 s of stepping; each report costs a message.
SKIP_CHUNK = 2000


class BuildCancelled(Exception):
    """Building a new world was stopped by the user."""


class Runner(SimulationRunner):
    """Owns the simulation and runs it in its own thread (a :class:`SimulationRunner`).

    ``fps`` is the frame rate the loop paces itself to; ``steps_per_frame`` the
    speed. Listeners receive snapshots on the publisher thread; ``deliver``: see
    :class:`~sandbox.app.world.contract.FramePublisher`.
    """

    def __init__(self, config: Config, *, shape: Any = "from-config", seed: int | None = None,
                 fps: float = 30.0, steps_per_frame: int = 10, playing: bool = True, chart_every: int = 100,
                 program_time_limit: float = watchdog.DEFAULT_LIMIT, deliver: Deliver | None = None,
                 first_world_key: int = 0):
        """``first_world_key``: the key of the first world's frames (a simulation process restarted after
        a crash goes on from its predecessor's keys: a key names one world, and later worlds have
        larger keys)."""
        #: Seconds a light program's import, reset or update may take (then the paper's controller takes over).
        self.program_time_limit = float(program_time_limit)
        from sandbox.model.simulation import Simulation  # with numba's compiled kernels: see the top

        # A live run has no last step.
        self.sim = Simulation(config, seed=seed, shape=shape, open_ended=True, program_time_limit=program_time_limit)
        #: The light program the world runs, kept for *Download design* (every change, up to a cap).
        self._recorder = PatternRecorder(most=MOST_PATTERNS).attach(self.sim)
        SimulationRunner.__init__(self, Controls(playing=bool(playing), steps_per_frame=max(1, int(steps_per_frame))),
                                  deliver)
        self.fps = float(fps)
        self.chart_every = int(chart_every)
        self.program_name = PAPER_PROGRAM
        self.program_error: tuple[int, str] | None = None
        self.shape_name = config.shape
        #: Changes that need a new world, kept until the next reset (the simulation holds only the
        #: configuration its world was built with).
        self.pending: dict[str, Any] = {}
        self._commands: queue.SimpleQueue = queue.SimpleQueue()  # (command, future), for the loop
        self._closing = threading.Lock()  # a command is queued before the runner closes, or refused
        self._closed = False
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._new_frame = threading.Condition()
        self._latest: Snapshot | None = None
        self._published = -1
        self._frame = 0  # snapshots taken
        self._frames_run = 0  # frames of the schedule run, snapshot or not
        self._goal_key = 0
        self._world_key = int(first_world_key)
        self._step_times: deque = deque(maxlen=120)  # (wall time, steps_done), of the simulation thread only
        self._restart_schedule = False  # set by a command whose time the world does not owe (the loop's)
        self._series_lock = threading.Lock()
        self._series: list[Sample] = []
        self._threads: list[threading.Thread] = []
        self._cancel = threading.Event()
        self._progress_listeners: list[Callable[[float | None], None]] = []
        self._build_listeners: list[Callable[[tuple | None], None]] = []
        self._record_series(force=True)
        self._snapshot()

    # ------------------------------------------------------------ control
    def start(self) -> "Runner":
        if self._threads:
            return self
        for target, name in ((self._loop, "simulation"), (self._publish_loop, "publisher")):
            t = threading.Thread(target=target, name=f"phototaxis-{name}", daemon=True)
            t.start()
            self._threads.append(t)
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """End the loops; every command not yet carried out fails with RunnerStopped."""
        self._stop.set()
        self._wake.set()
        with self._new_frame:
            self._new_frame.notify_all()
        for t in self._threads:
            if t is not threading.current_thread():  # a callback on the loop's own thread may stop it
                t.join(timeout)
        self._threads = []
        self._close(RunnerStopped("the simulation was stopped"))

    def submit(self, command: Command) -> Future:
        """Carry out ``command``: a control now, on this thread; any other in the simulation thread
        before the next step (or at the next :meth:`advance` of a runner that was not started)."""
        future: Future = Future()
        if command.at_once:
            self._carry_out(command, future)
            return future
        with self._closing:
            refused = self._closed
            if not refused:
                self._commands.put((command, future))
        if refused:
            future.set_exception(RunnerStopped("the simulation was stopped"))
        else:
            self._wake.set()
        return future

    def _close(self, why: RunnerStopped) -> None:
        """Refuse new commands and fail the waiting ones: whoever waits on one hears ``why``."""
        with self._closing:
            self._closed = True
        while True:
            try:
                _, future = self._commands.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_exception(why)

    def call(self, command: Command, timeout: float = 10.0) -> Any:
        """Post a command and wait for its result (raises its exception)."""
        if not self._threads:
            # Not started (tests, headless use): run inline.
            result = command(self.sim)
            self._snapshot()
            return result
        return answer(self.submit(Apply(command)), timeout)

    def advance(self, n: int) -> Snapshot:
        """Headless use (no threads): step ``n`` steps and take a snapshot."""
        assert not self._threads, "advance() is for a runner that was not started"
        self._run_commands()
        self._step(n)
        self._record_series()
        self._snapshot()
        return self.latest

    @property
    def settings(self) -> Config:
        """The running configuration with the changes waiting for a reset."""
        return self.sim.config.replace(**self.pending)

    def on_progress(self, listener: Callable[[float | None], None]) -> None:
        """``listener(fraction)`` hears how far building a world has got; None when it is over."""
        self._progress_listeners.append(listener)

    def on_build(self, listener: Callable[[tuple | None], None]) -> None:
        """``listener((config, goal, seed))`` hears what a new world or goal is built from as its building
        starts (the goal as given: vertices, None for the circle, or SAME_GOAL), and ``listener(None)``
        when it is over, built or not: a process runner tells the settings that killed a process from
        those that ran."""
        self._build_listeners.append(listener)

    @contextlib.contextmanager
    def _announcing(self, config: Config, goal: Any, seed: int | None) -> Iterator[None]:
        """Within: a world or goal is being built from these settings (see :meth:`on_build`)."""
        for listener in list(self._build_listeners):
            self._deliver(listener, (config, goal, seed))
        try:
            yield
        finally:
            for listener in list(self._build_listeners):
                self._deliver(listener, None)

    def _building(self, fraction: float) -> None:
        if self._cancel.is_set():
            raise BuildCancelled("building the world was cancelled; the previous world goes on")
        self._report_progress(fraction)

    def _report_progress(self, fraction: float | None) -> None:
        for listener in list(self._progress_listeners):
            self._deliver(listener, fraction)  # a broken listener must not stop the build

    @property
    def latest(self) -> Snapshot:
        assert self._latest is not None
        return self._latest

    def series(self) -> list[Sample]:
        with self._series_lock:
            return list(self._series)

    def series_of_world(self) -> tuple[int, list[Sample]]:
        """The running world's key and its samples, read together: a reset changes both at once."""
        with self._series_lock:
            return self._world_key, list(self._series)

    @property
    def stopped(self) -> bool:
        return self._stop.is_set()

    def wake(self) -> None:
        """Run the loop now (a paused runner otherwise waits a frame's time)."""
        self._wake.set()

    def _measured_speed(self) -> float:
        """Steps per second over the last frames (the simulation thread's own record)."""
        if len(self._step_times) < 2:
            return 0.0
        (t0, s0), (t1, s1) = self._step_times[0], self._step_times[-1]
        return (s1 - s0) / (t1 - t0) if t1 > t0 else 0.0

    # ------------------------------------------------------------ commands
    def _run_commands(self) -> int:
        """Carry out the waiting commands; how many there were."""
        count = 0
        while True:
            try:
                command, future = self._commands.get_nowait()
            except queue.Empty:
                return count
            count += 1
            if future.set_running_or_notify_cancel():  # not cancelled by whoever submitted it
                self._carry_out(command, future)

    def _carry_out(self, command: Command, future: Future) -> None:
        """Handle one command; its future gets the answer. Nothing a command raises stops the loop, but
        SystemExit and KeyboardInterrupt go on up (the caller hears that the loop ended)."""
        try:
            result = self.handle(command)
        except Exception as exc:  # noqa: BLE001 - reported to whoever submitted it
            future.set_exception(exc)
        else:
            future.set_result(result)
        finally:
            if not future.done():
                future.set_exception(RunnerStopped("the simulation stopped while carrying this out"))

    def handle(self, command: Command) -> Any:
        """Carry out one command (the one place each command's meaning lives; :meth:`submit` decides
        on which thread and when): the handler of its type, or of the nearest base that has one."""
        kind = type(command)
        handler = HANDLERS.get(kind) or next((HANDLERS[k] for k in kind.__mro__ if k in HANDLERS), None)
        if handler is None:
            raise TypeError(f"the simulation does not know the command {command!r}")
        return handler(self, command)

    @handles(Setting)
    def _setting(self, command: Setting) -> None:
        command.settle(self.controls)
        if command.wakes:
            self._wake.set()

    @handles(Start)
    def _start(self, command: Start) -> None:
        self.start()

    @handles(CancelBuild)
    def _cancel_build(self, command: CancelBuild) -> None:
        self._cancel.set()

    @handles(Apply)
    def _apply(self, command: Apply) -> Any:
        return command.function(self.sim)

    @handles(StepOnce)
    def _step_once(self, command: StepOnce) -> None:
        self._step(command.n)

    @handles(RunTo)
    def _run_to(self, command: RunTo) -> None:
        if self.sim.steps_done < command.step:
            self._step(command.step - self.sim.steps_done)

    @handles(SkipAhead)
    def _skip_ahead(self, command: SkipAhead) -> Arrival:
        """Step in chunks of :data:`SKIP_CHUNK` with no snapshot between them (the chart's samples are kept),
        telling the progress listeners after each; stop early when cancelled (a cancel that came while
        it waited its turn counts: the page's Cancel shows from the moment it is asked)."""
        start, target = self.sim.steps_done, int(command.step)
        cancelled = False
        # The state it starts from, shown while it runs: after a reset taken in the same turn (Use and run to
        # the end), the pages would otherwise show the old world until the end.
        self._snapshot()
        try:
            while self.sim.steps_done < target:
                if self._cancel.is_set():
                    cancelled = True
                    break
                chunk_end = min(self.sim.steps_done + SKIP_CHUNK, target)
                while self.sim.steps_done < chunk_end:  # the chart's samples as a live run takes them
                    self._step(min(self.chart_every, chunk_end - self.sim.steps_done))
                    self._record_series()
                self._report_progress((self.sim.steps_done - start) / max(target - start, 1))
        finally:
            self._cancel.clear()
            self._report_progress(None)
        self._record_series(force=True)
        self._restart_schedule = True  # it ran ahead: its time is not owed
        return Arrival(self.sim.steps_done, cancelled, self._world_key)

    @handles(UpdateConfig)
    def _update_config(self, command: UpdateConfig) -> tuple[list[str], Config]:
        changes = command.changes
        deferred = self.sim.update_config(**changes)
        # Checked together with what is already waiting (a profile change resets the values it bundles).
        settings = self.sim.config.replace(**{**self.pending, **{k: changes[k] for k in deferred}})
        self.pending = {k: getattr(settings, k) for k in {*self.pending, *deferred}}
        return sorted(self.pending), settings

    @handles(Reset)
    def _reset(self, command: Reset) -> int:
        self._cancel.clear()
        settings = self.settings
        seed = settings.seed if command.seed is None else int(command.seed)
        try:
            with self._announcing(settings, SAME_GOAL, seed):
                self.sim.reset(command.seed, config=settings, progress=self._building)
        finally:
            self._report_progress(None)
        self.pending = {}
        self._new_world()
        return self._world_key

    def _new_world(self) -> None:
        """The simulation was rebuilt: a new goal, new speeds, a new world and its new series."""
        self._goal_key += 1
        self._restart_schedule = True  # the new world starts on the clock: the build's time is not owed
        self._step_times.clear()  # speeds are measured within one world
        with self._series_lock:  # a new world and its new series, together (see series_of_world)
            self._world_key += 1
            self._series = []
        self._record_series(force=True)

    @handles(SetShape)
    def _set_shape(self, command: SetShape) -> list[str]:
        with self._announcing(self.sim.config, command.vertices, self.sim.seed):
            notes = self.sim.set_shape(command.vertices, name=command.name)
        self.shape_name = command.name
        self._goal_key += 1
        return notes

    @handles(SetOutline)
    def _set_outline(self, command: SetOutline) -> list[str]:
        with self._announcing(self.sim.config.replace(outline=command.outline), SAME_GOAL, self.sim.seed):
            notes = self.sim.set_outline(command.outline)
        self._goal_key += 1  # an offset goal may have moved
        return notes

    @handles(SetProgram)
    def _set_program(self, command: SetProgram) -> str:
        from sandbox.model.programs import load_program

        spec = command.spec
        self.sim.use_program(load_program(spec, time_limit=self.program_time_limit) if spec else None)
        self.program_name = spec or PAPER_PROGRAM
        return self.program_name

    @handles(SetLamp)
    def _set_lamp(self, command: SetLamp) -> str:
        from sandbox.model.lamp import Lamp

        sim = self.sim
        lamp = sim.user_program if isinstance(sim.user_program, Lamp) else None
        if command.centre is None:
            if lamp is not None:
                sim.use_program(None)
                self.program_name = PAPER_PROGRAM
            return self.program_name
        if lamp is None:
            lamp = Lamp()
            sim.use_program(lamp)
            self.program_name = LAMP_PROGRAM
        lamp.aim(*command.centre, command.radius, command.mode)
        return self.program_name

    @handles(DesignOf)
    def _design_of(self, command: DesignOf) -> Any:
        return self._recorder.design(self.sim, controller=self.program_name)

    @handles(PlayDesign)
    def _play_design(self, command: PlayDesign) -> str:
        from sandbox.model.design import Replay

        design = command.design
        with self._announcing(design.config, design.shape, design.seed):
            self.sim.set_shape(design.shape, name=design.config.shape)
            self.sim.use_program(Replay(design))
            self.pending = {}
            self.sim.reset(design.seed, config=design.config)
        self.shape_name = design.config.shape
        self.program_name = DESIGN_PROGRAM
        self._new_world()
        return self.program_name

    @handles(WorldSpec)
    def _world_spec(self, command: WorldSpec) -> tuple:
        sim = self.sim
        shape = None if sim.shape_vertices is None else sim.shape_vertices.copy()
        return sim.config, sim.seed, shape

    # -------------------------------------------------------------- loops
    def _step(self, n: int | None = None, deadline: float | None = None) -> None:
        """Step; a light program that fails while running hands the lights back to the paper's controller."""
        from sandbox.model.programs import ProgramError

        try:
            if deadline is not None:
                self._step_for(deadline)
            else:
                self.sim.step(n)
        except ProgramError as exc:
            self.sim.use_program(None)
            self.program_name = PAPER_PROGRAM
            count = self.program_error[0] + 1 if self.program_error else 1
            self.program_error = (count, str(exc))

    def _loop(self) -> None:
        try:
            self._run_frames()
        finally:  # stopped, or SystemExit / KeyboardInterrupt on their way up: nobody waits on a command
            self._close(RunnerStopped("the simulation loop ended"))

    def _run_frames(self) -> None:
        interval = 1.0 / self.fps
        due = time.perf_counter()  # when the next frame's steps are due
        while not self._stop.is_set():
            if time.perf_counter() < due:
                due = self._commands_between_frames(due)
            else:
                due = self._frame_on_schedule(due, interval)
            delay = due - time.perf_counter()
            if delay > 0:  # sleep until the next frame is due, or a command arrives
                self._wake.wait(delay)
                self._wake.clear()

    def _commands_between_frames(self, due: float) -> float:
        """Woken before a frame is due (a command came): carry the commands out and show their effect,
        but step on the schedule only (a page sending commands faster than frames, as a drag does,
        made the world run faster). The next frame's time: still ``due``, or now if a command started
        a new world or ran ahead."""
        self._restart_schedule = False
        if self._run_commands():
            self._snapshot()
        return max(due, time.perf_counter()) if self._restart_schedule else due

    def _frame_on_schedule(self, due: float, interval: float) -> float:
        """The frame that was ``due``, with the steps of those it missed; the next frame's time."""
        fastest = self.controls.steps_per_frame >= FASTEST
        frames = 1 if fastest else frames_owed(due, time.perf_counter(), interval, CATCH_UP_PER_FRAME)
        self._restart_schedule = False
        try:
            playing = self._frame_of_steps(due + interval, frames)
        except Exception as exc:  # noqa: BLE001 - a bug: pause and say so rather than freeze the page
            self.errors.append(exc)
            log.exception("the simulation loop failed; paused")
            self.controls.playing = playing = False
        return next_frame_due(due + (frames - 1) * interval, time.perf_counter(), interval,
                              most_behind=self._may_fall_behind(fastest, playing, interval))

    def _may_fall_behind(self, fastest: bool, playing: bool, interval: float) -> float:
        """How far behind its schedule the next frame may be due (s). Nothing is owed for time the world
        was paused, or spent on a command that built a new world or ran ahead (a new world starts on the
        clock). A world held by compare mode's lockstep owes its time: when its partner has caught up,
        both catch up together. The fastest setting catches up one frame only (its frames fill their
        time)."""
        if self._restart_schedule or not playing:
            return 0.0
        return interval if fastest else BEHIND_AT_MOST

    def _frame_of_steps(self, deadline: float, frames: int = 1) -> bool:
        """One frame: the waiting commands, ``frames`` frames' steps (if playing), the series and a
        snapshot. ``deadline``: when the fastest setting stops stepping. True if the world was playing."""
        self._run_commands()
        controls = self.controls
        allowed = self._steps_allowed(controls.steps_per_frame * frames)
        if controls.playing and allowed > 0:
            if controls.steps_per_frame >= FASTEST:
                self._step(deadline=deadline)  # as many steps as fit in one frame
            else:
                self._step(allowed)
            self._record_series()
        self._step_times.append((time.perf_counter(), self.sim.steps_done))
        self._frames_run += 1
        if self._frames_run % controls.show_every == 0:  # (a command that wakes the loop shows at once)
            self._snapshot()
        return controls.playing

    def _step_for(self, deadline: float) -> None:
        """Step in small chunks until ``deadline`` (at least one chunk) or the held step."""
        while (n := self._steps_allowed(FASTEST_CHUNK)) > 0:
            self.sim.step(n)
            if time.perf_counter() >= deadline or self._stop.is_set() or not self._commands.empty():
                return

    def _steps_allowed(self, n: int) -> int:
        """``n``, or fewer if the world is held (:meth:`hold`)."""
        hold = self.controls.hold_at
        return n if hold is None else max(0, min(n, hold - self.sim.steps_done))

    def _publish_loop(self) -> None:
        while not self._stop.is_set():
            with self._new_frame:
                while self._latest is None or self._latest.frame == self._published:
                    if self._stop.is_set():
                        return
                    self._new_frame.wait(0.5)
                snap = self._latest
            self._published = snap.frame
            self._publish(snap)

    # ---------------------------------------------------------- snapshots
    def _record_series(self, force: bool = False) -> None:
        sim = self.sim
        with self._series_lock:
            last = self._series[-1].step if self._series else None
        if force or last is None or sim.steps_done - last >= self.chart_every:
            sample = sim.measure()
            with self._series_lock:
                self._series.append(sample)

    def _snapshot(self) -> None:
        sim = self.sim
        self._frame += 1
        followed = tuple(RobotView(
            index=i,
            position=sim.robot_positions[i].copy(),
            heading=float(sim.robot_headings[i]),
            sensors=sim.robot_sensors[i].copy(),
            sensor_points=sim.sensor_points(i).copy(),
            command=sim.robot_commands[i].copy(),
            applied=sim.robot_velocities[i].copy(),
            charge=float(sim.robot_charges[i]),
        ) for i in self.controls.followed if 0 <= i < sim.world.n_robots)
        in_goal = sim.box_in_goal
        # The light field counts its pattern changes: a new count means new lights.
        lights_key = (self._world_key, id(sim.lights), sim.lights.rebuilds)
        prev = self._latest
        same_lights = prev is not None and prev.lights_key == lights_key
        intensities = prev.intensities if same_lights else sim.light_intensities.copy()
        field = None
        if self.controls.want_field:
            if same_lights and prev.field is not None:
                field = prev.field
            else:
                field = sim.lights.display_grid(per_pitch=4).astype(np.float32)
        if prev is not None and prev.goal_key == self._goal_key:
            goal_outline, goal_vertices = prev.goal_outline, prev.goal_vertices
        else:
            goal_outline = sim.goal.outline().copy()
            goal_vertices = None if sim.goal.vertices is None else sim.goal.vertices.copy()
        snap = Snapshot(
            frame=self._frame,
            step=sim.steps_done,
            time=sim.time,
            phase=sim.phase_said,
            cycle=sim.cycle,
            seed=sim.seed,
            shape_name=self.shape_name,
            world_config=sim.config,
            config=self.settings,
            robot_positions=sim.robot_positions.copy(),
            robot_headings=sim.robot_headings.copy(),
            robot_charges=sim.robot_charges.copy(),
            box_positions=sim.box_positions.copy(),
            box_angles=sim.box_angles.copy(),
            box_in_goal=np.asarray(in_goal).copy(),
            lights_key=lights_key,
            intensities=intensities,
            field=field,
            outline=sim.outline.copy(),
            goal_key=self._goal_key,
            goal_outline=goal_outline,
            goal_vertices=goal_vertices,
            sample=self._series[-1] if self._series else sim.measure(),
            strategies=dict(sim.controller.strategies),
            playing=self.controls.playing,
            steps_per_frame=self.controls.steps_per_frame,
            steps_per_second=self._measured_speed(),
            followed=followed,
            program=self.program_name,
            program_error=self.program_error,
            world_key=self._world_key,
            family=sim.goal.family,
            family_reason=sim.goal.family_reason,
            gathering=sim.gathering,
        )
        with self._new_frame:
            self._latest = snap
            self._new_frame.notify_all()
