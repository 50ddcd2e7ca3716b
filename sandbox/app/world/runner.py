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

from sandbox.app.world.contract import Deliver, SimulationRunner, wait_for
from sandbox.app.world.orders import Build, BuildCancelled, Command, Controls, RunnerStopped
from sandbox.app.world.snapshot import PAPER_PROGRAM, RobotView, Snapshot
from sandbox.model import watchdog
from sandbox.model.config import Config
from sandbox.model.design import MAX_PATTERNS, PatternRecorder
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


#: Patterns a live world's design keeps: as many as a design file holds (10,000 on the default grid,
#: ten default runs of the paper's controller; fewer on a larger grid), 5 MB kept as bits.
MOST_PATTERNS = MAX_PATTERNS


class Runner(SimulationRunner):
    """Owns the simulation and runs it in its own thread (a :class:`SimulationRunner`).

    ``fps`` is the frame rate the loop paces itself to; ``steps_per_frame`` the
    speed. Listeners receive snapshots on the publisher thread; ``deliver``: see
    :class:`~sandbox.app.world.contract.FramePublisher`.

    Who writes what: the controls only the settings, on the thread that submits them; the world, the
    snapshots and everything under "for the commands" only the simulation thread (the commands' own
    thread in a runner that was not started); the builds' cancels (:meth:`cancel`) any thread.
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
        self.recorder = PatternRecorder(most=MOST_PATTERNS).attach(self.sim)
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
        self._settings_of: tuple | None = None  # (config, pending, the settings they make): see settings
        self._commands: queue.SimpleQueue = queue.SimpleQueue()  # (command, future), for the loop
        # a command is queued before the runner closes, or refused: shared by the threads that submit
        # (the event thread, workers, main) and the one that stops it
        self._closing = threading.Lock()
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
        # shared by the simulation thread (appends samples, starts a new series) and the threads that read
        # the series (the event thread, the publisher in a child process)
        self._series_lock = threading.Lock()
        self._series: list[Sample] = []
        self._threads: list[threading.Thread] = []
        # The builds submitted and not over, each with whether a cancel named it: shared by the threads
        # that submit (a cancel comes on the event thread) and the simulation thread (runs the build).
        self._builds_lock = threading.Lock()
        self._builds: dict[int, bool] = {}
        #: Set by the loop when a frame failed: it steps no more, and its frames say paused, until the
        #: next SetPlaying (the owner of play heard of it: :meth:`on_halt`). The loop writes no control.
        self._halted = threading.Event()
        self._halt_listeners: list[Callable[[str], None]] = []
        self._progress_listeners: list[Callable[[float | None], None]] = []
        self._build_listeners: list[Callable[[tuple | None], None]] = []
        self.record_series(force=True)
        self.snapshot()

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
        before the next step (or at the next :meth:`advance` or :meth:`call` of a runner that was not
        started)."""
        future: Future = Future()
        if command.at_once:
            self._carry_out(command, future)
            return future
        if isinstance(command, Build):
            self._expect(command.build)  # from now on a cancel of it counts, even before it starts
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
                break
            if future.set_running_or_notify_cancel():
                future.set_exception(why)
        with self._builds_lock:
            self._builds.clear()

    def call(self, command: Command, timeout: float = 10.0) -> Any:
        """Submit ``command`` and wait for its answer (raises what it raised). A runner that was not
        started (tests, headless use) carries out what waits, this command too, here and now."""
        future = self.submit(command)
        if not self._threads and not self._closed:
            self._run_commands()
            self.snapshot()
        return wait_for(future, timeout)

    def advance(self, n: int) -> Snapshot:
        """Headless use (no threads): step ``n`` steps and take a snapshot."""
        assert not self._threads, "advance() is for a runner that was not started"
        self._run_commands()
        self.step(n)
        self.record_series()
        self.snapshot()
        return self.latest

    @property
    def settings(self) -> Config:
        """The running configuration with the changes waiting for a reset. Kept while neither changes: every
        snapshot reads it, and building a Config checks every value (a quarter of a class world's frame)."""
        key = (self.sim.config, self.pending)
        if self._settings_of is None or self._settings_of[0] is not key[0] or self._settings_of[1] is not key[1]:
            self._settings_of = (*key, self.sim.config.replace(**self.pending) if self.pending else self.sim.config)
        return self._settings_of[2]

    def on_progress(self, listener: Callable[[float | None], None]) -> None:
        """``listener(fraction)`` hears how far building a world has got; None when it is over."""
        self._progress_listeners.append(listener)

    def on_build(self, listener: Callable[[tuple | None], None]) -> None:
        """``listener((config, goal, seed))`` hears what a new world or goal is built from as its building
        starts (the goal as given: vertices, None for the circle, or SAME_GOAL), and ``listener(None)``
        when it is over, built or not: a process runner tells the settings that killed a process from
        those that ran."""
        self._build_listeners.append(listener)

    def on_halt(self, listener: Callable[[str], None]) -> None:
        self._halt_listeners.append(listener)

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
        """Carry out one command now, on this thread (:meth:`submit` decides on which thread and when;
        what it does, the command says: :meth:`Command.carry_out <sandbox.app.world.orders.Command.carry_out>`)."""
        return command.carry_out(self)

    # ------------------------------------------------------------ for the commands
    @contextlib.contextmanager
    def announcing(self, config: Config, goal: Any, seed: int | None) -> Iterator[None]:
        """Within: a world or goal is being built from these settings (see :meth:`on_build`)."""
        for listener in list(self._build_listeners):
            self._deliver(listener, (config, goal, seed))
        try:
            yield
        finally:
            for listener in list(self._build_listeners):
                self._deliver(listener, None)

    @contextlib.contextmanager
    def under_way(self, build: int) -> Iterator[Callable[[float], None]]:
        """Within: the build ``build`` is carried out. Yields its progress report, ``progress(fraction)``,
        which raises :class:`BuildCancelled` once a cancel named it. On the way out the progress
        listeners hear that it is over, and a cancel of it does nothing any more."""

        def progress(fraction: float) -> None:
            self.stop_if_cancelled(build)
            self.report_progress(fraction)

        self._expect(build)  # carried out without being submitted (a test driving handle())
        try:
            yield progress
        finally:
            with self._builds_lock:
                self._builds.pop(build, None)
            self.report_progress(None)

    def _expect(self, build: int) -> None:
        with self._builds_lock:
            self._builds.setdefault(build, False)

    def cancel(self, build: int) -> None:
        """Cancel the build ``build`` if it waits or runs (any thread); one that is over stays over."""
        with self._builds_lock:
            if build in self._builds:
                self._builds[build] = True

    def cancelled(self, build: int) -> bool:
        with self._builds_lock:
            return self._builds.get(build, False)

    def stop_if_cancelled(self, build: int) -> None:
        if self.cancelled(build):
            raise BuildCancelled("building the world was cancelled; the previous world goes on")

    def report_progress(self, fraction: float | None) -> None:
        for listener in list(self._progress_listeners):
            self._deliver(listener, fraction)  # a broken listener must not stop the build

    def new_world(self) -> int:
        """The simulation was rebuilt: a new goal, new speeds, a new world and its new series. Returns
        the new world's key."""
        self._goal_key += 1
        self._restart_schedule = True  # the new world starts on the clock: the build's time is not owed
        self._step_times.clear()  # speeds are measured within one world
        with self._series_lock:  # a new world and its new series, together (see series_of_world)
            self._world_key += 1
            self._series = []
        self.record_series(force=True)
        return self._world_key

    def new_goal(self) -> None:
        """The goal changed (its outline is drawn again)."""
        self._goal_key += 1

    def ran_ahead(self) -> None:
        """The world ran ahead of its schedule (a skip): the time that took is not owed."""
        self._restart_schedule = True

    @property
    def world_key(self) -> int:
        return self._world_key

    def lift_halt(self) -> None:
        """Step again after a failed frame (a SetPlaying came: whoever owns play has decided)."""
        self._halted.clear()

    # -------------------------------------------------------------- loops
    def step(self, n: int | None = None, deadline: float | None = None) -> None:
        """Step ``n`` steps (or, with ``deadline``, as many as fit before it); a light program that fails while running hands the lights back to the paper's controller."""
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
            self.snapshot()
        return max(due, time.perf_counter()) if self._restart_schedule else due

    def _frame_on_schedule(self, due: float, interval: float) -> float:
        """The frame that was ``due``, with the steps of those it missed; the next frame's time."""
        fastest = self.controls.steps_per_frame >= FASTEST
        frames = 1 if fastest else frames_owed(due, time.perf_counter(), interval, CATCH_UP_PER_FRAME)
        self._restart_schedule = False
        try:
            playing = self._frame_of_steps(due + interval, frames)
        except Exception as exc:  # noqa: BLE001 - a bug: stop and say so rather than freeze the page
            self._halt(exc)
            playing = False
        return next_frame_due(due + (frames - 1) * interval, time.perf_counter(), interval,
                              most_behind=self._may_fall_behind(fastest, playing, interval))

    def _halt(self, exc: Exception) -> None:
        """A frame failed (a bug): step no more, and say paused, until the next SetPlaying; tell the
        :meth:`on_halt` listeners, which own play (the app pauses, as a page's Pause does)."""
        self.errors.append(exc)
        log.exception("the simulation loop failed; halted until play is set again")
        self._halted.set()
        why = f"the simulation failed ({type(exc).__name__}: {exc}) and stopped stepping"
        for listener in list(self._halt_listeners):
            self._deliver(listener, why)

    def _playing(self) -> bool:
        """Whether the world steps: playing, and not halted by a failed frame."""
        return self.controls.playing and not self._halted.is_set()

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
        playing = self._playing()
        allowed = self._steps_allowed(controls.steps_per_frame * frames)
        if playing and allowed > 0:
            if controls.steps_per_frame >= FASTEST:
                self.step(deadline=deadline)  # as many steps as fit in one frame
            else:
                self.step(allowed)
            self.record_series()
        self._step_times.append((time.perf_counter(), self.sim.steps_done))
        self._frames_run += 1
        if self._frames_run % controls.show_every == 0:  # (a command that wakes the loop shows at once)
            self.snapshot()
        return playing

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
    def record_series(self, force: bool = False) -> None:
        sim = self.sim
        with self._series_lock:
            last = self._series[-1].step if self._series else None
        if force or last is None or sim.steps_done - last >= self.chart_every:
            sample = sim.measure()
            with self._series_lock:
                self._series.append(sample)

    def snapshot(self) -> None:
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
            playing=self._playing(),
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
