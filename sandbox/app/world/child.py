"""The simulation in its own process, behind the same interface as :class:`~sandbox.app.world.runner.Runner`.
Its proxy is called from the app's event thread; one receiving thread per child reads the child's messages and settles the futures; the child runs the loop.

In one process the web server (viser's event loop, scene and panel updates)
and the simulation share the GIL, and the live app stepped at less than half
of the headless speed. :class:`ProcessRunner` runs an ordinary
:class:`Runner` in a child process instead, so the two use two cores:

- commands (:mod:`sandbox.app.world.orders`) go to the child as they are,
  through a queue, each in an :class:`Order` with an id; the child's Runner
  carries them out and answers :class:`Done` (or :class:`Failed`) for that
  id, which settles the command's future here. Controls go without an id:
  they act here at once (this side keeps a copy of the controls) and there
  when they arrive;
- the child's answers are typed messages through a pipe, one class each
  (:class:`Frame`, :class:`Done`, :class:`Failed`, :class:`Progress`,
  :class:`Building`, :class:`Halted`, :class:`LastWords`), each taken here by
  one method (``ProcessRunner._take``). Every snapshot the child publishes
  (the newest one only, at the frame rate) comes back in a :class:`Frame`
  with the metric samples recorded since the last one, and reaches this
  side's listeners;
- if the child dies, what it owed fails (SimulationCrashed), listeners of
  :meth:`ProcessRunner.on_crash` hear why, and a new child starts from the
  settings that stand (:mod:`sandbox.app.world.standing`): those of the running
  world if they ran, else the last that ran, which the listeners of
  :meth:`ProcessRunner.on_settings_back` hear. A change of settings submitted
  meanwhile waits for the new child; any other command goes to the new child
  once it is spawned, or fails at once: none is lost. Five crashes with no
  world running in between, or five within a minute, and it gives up;
- stopped, a child that is not running yet (building its first world) is
  killed at once, a running one after STOP_GRACE at most.

One lock guards the child (the process, its channels, the answers it owes
and the runner's state): a restart and :meth:`ProcessRunner.stop` each
take it, so a child spawned while stopping is stopped too.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import multiprocessing
import os
import pickle
import queue
import signal
import threading
import time
import traceback
from collections import deque
from concurrent.futures import Future
from typing import Any, Callable, NamedTuple

import numpy as np

from sandbox.app.world import faults
from sandbox.app.world.orders import (SAME_GOAL, Command, Controls, RunnerStopped, Setting, SetShape, Start,
                                      UpdateConfig)
from sandbox.app.world.contract import Deliver, SimulationRunner
from sandbox.app.world.runner import Runner
from sandbox.app.world.snapshot import Snapshot
from sandbox.app.world.standing import PROVEN_SECONDS, PROVEN_STEPS, Settings, Standing, changed, gone_back
from sandbox.model import watchdog
from sandbox.model.config import Config
from sandbox.model.metrics import Sample
from sandbox.processes import simulation_context

#: How long the parent waits for a new child's first snapshot (imports, numba cache, world building).
START_TIMEOUT = 120.0
#: After a crash the child is restarted after this pause, doubled for each crash within CRASH_WINDOW seconds
#: or since a world last ran.
RESTART_PAUSE = 1.0
CRASH_WINDOW = 60.0
#: This many crashes within CRASH_WINDOW, or with no world running in between however far apart, and the
#: app stops restarting the simulation.
CRASHES_BEFORE_GIVING_UP = 5
#: Stopped, a running child is given this long (s) to end by itself, then killed: a serve stopped at any
#: moment ends within 2 s (a child busy building a world does not read its queue).
STOP_GRACE = 0.5
#: A child's exit code when a light program would not stop (it said why just before).
STUCK_EXIT = 75

#: The runner's states: a child spawned (its first frame not yet here), running, none (crashed, being
#: replaced, or given up), stopped. Commands reach a child only while it is starting or running.
STARTING, RUNNING, DOWN, STOPPED = "starting", "running", "down", "stopped"

log = logging.getLogger("sandbox.app.world.child")


class SimulationCrashed(RuntimeError):
    """The simulation process ended without being asked to."""


# ------------------------------------------------------------------ messages
# Named tuples: typed, immutable and the cheapest class to pickle (a frame's comes 30 times a second).
class Order(NamedTuple):
    """To the child: carry out ``command``; answer for ``ident`` (None: a control, no answer)."""

    ident: int | None
    command: Command


class Frame(NamedTuple):
    """From the child: a snapshot, with the metric samples of world ``world`` recorded since the last."""

    snap: Snapshot
    samples: list
    world: int


class Done(NamedTuple):
    """From the child: the answer of the command ``ident``."""

    ident: int
    result: Any


class Failed(NamedTuple):
    """From the child: what the command ``ident`` raised."""

    ident: int
    error: BaseException


class Progress(NamedTuple):
    """From the child: how far a build has got (None: it is over)."""

    fraction: float | None


class Building(NamedTuple):
    """From the child: the (config, goal, seed) a new world or goal is built from (None: over)."""

    settings: tuple | None


class Halted(NamedTuple):
    """From the child: a frame failed and the world stepped no more (Runner.on_halt)."""

    why: str


class LastWords(NamedTuple):
    """From the child, before it ends itself: why (a first world it cannot build, a stuck program)."""

    why: str


class Child:
    """One simulation process and its two channels: the queue it takes commands from, the pipe it
    answers on."""

    def __init__(self, context: Any, settings: dict):
        self.commands = context.Queue()
        self.receive, send = context.Pipe(duplex=False)
        self.process = context.Process(target=_child_main, args=(settings, self.commands, send),
                                       name="phototaxis-simulation", daemon=True)
        self.process.start()
        send.close()  # the child holds the sending end

    def send(self, message: Any) -> bool:
        """Queue a message; False when the queue is closed (the child ended)."""
        try:
            self.commands.put(message)
            return True
        except (OSError, ValueError, AssertionError):
            return False

    def read(self, timeout: float) -> Any:
        """The next message within ``timeout`` seconds, or None (none came, or the pipe is closed)."""
        try:
            if self.receive.poll(timeout):
                return self.receive.recv()
        except (EOFError, OSError):
            pass
        return None

    def end(self, kill: bool = False, timeout: float = 5.0) -> None:
        """Reap the process (killing it first if asked) and close its pipe and queue."""
        if kill and self.process.is_alive():
            self.process.kill()
        self.process.join(timeout)
        for close in (self.receive.close, self.commands.close, self.commands.cancel_join_thread):
            try:
                close()
            except (OSError, ValueError):
                pass


class ProcessRunner(SimulationRunner):
    """A :class:`Runner` in a child process (see the module docstring); a generic proxy: every
    command is sent as it is and its future settled by the child's answer."""

    def __init__(self, config: Config, *, shape: Any = "from-config", seed: int | None = None,
                 fps: float = 30.0, steps_per_frame: int = 10, playing: bool = True, chart_every: int = 100,
                 program_time_limit: float = watchdog.DEFAULT_LIMIT, wait: bool = True,
                 deliver: Deliver | None = None):
        SimulationRunner.__init__(self, Controls(playing=bool(playing), steps_per_frame=max(1, int(steps_per_frame))),
                                  deliver)
        self.fps = float(fps)
        self.chart_every = int(chart_every)
        self.program_time_limit = float(program_time_limit)
        self.restarts = 0
        #: Why the simulation cannot run any more (too many crashes in a row), or None.
        self.failed: str | None = None
        #: Seconds before the first restart after a crash (doubled for each crash within ``crash_window``
        #: or since a world last ran), and how many such crashes make it give up.
        self.restart_pause, self.crashes_before_giving_up = RESTART_PAUSE, CRASHES_BEFORE_GIVING_UP
        self.crash_window = CRASH_WINDOW
        #: A world ran once it took this many steps, or stepped for this long (s) (sandbox.app.world.standing).
        self.proven_steps, self.proven_seconds = PROVEN_STEPS, PROVEN_SECONDS
        self._crash_times: deque = deque(maxlen=64)
        self._last_words: str | None = None  # what a dying child said last (a program that would not stop)
        self._crash_listeners: list[Callable[[str], None]] = []
        self._back_listeners: list[Callable[[Config], None]] = []
        #: The settings that stand (the last that ran) and the crashes since; what the child was spawned
        #: with, what it is building now (None: nothing), whether it has sent a frame, and the world being
        #: watched to see whether it runs: ((world key, goal key), since, first step, ran). All but the
        #: first two are the receiving thread's.
        self._standing = Standing(Settings(config, shape, seed))
        self._spawned = self._standing.settings
        self._building: Settings | None = None
        self._framed = False
        self._trial: tuple | None = None
        #: Changes of settings submitted while no child could take them, for the next child (command, future).
        self._waiting: list[tuple[UpdateConfig, Future]] = []
        self._progress_listeners: list[Callable[[float | None], None]] = []
        self._halt_listeners: list[Callable[[str], None]] = []
        #: Who takes each kind of message from the child (on the receiving thread).
        self._takers: dict[type, Callable[[Any], None]] = {
            Frame: self._take_frame, Done: self._take_done, Failed: self._take_failed,
            Progress: self._take_progress, Building: self._take_building, Halted: self._take_halted,
            LastWords: self._take_last_words}
        self._ids = itertools.count()
        self._series: list[Sample] = []
        self._series_world: int | None = None  # the world key of the samples in _series
        # shared by the receiver thread (appends each sample) and the event thread (reads the series, and
        # empties it with a new child)
        self._series_lock = threading.Lock()
        self._latest: Snapshot | None = None
        self._stop = threading.Event()
        # shared by the threads that may wait for the first frame: the main thread at start-up, a worker
        # starting a compared world, the event thread
        self._ready_lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._context = simulation_context()  # a fork of a warmed-up server, else a fresh interpreter
        #: The goal as last given (a name, or vertices as drawn): a restarted child gets it back unchanged,
        #: since the program's largest outline depends on the size a shape was drawn at.
        self._shape = shape
        # One owner of the child: the lock guards it, the state, the futures it owes (with their
        # commands), the changes waiting for it and _started; shared by the event thread (submits), the
        # receiver thread (settles, restarts a crashed child) and the main thread (stops).
        self._child_lock = threading.Lock()
        self._owed: dict[int, tuple[Future, Command]] = {}
        self._started = False
        self._state = DOWN
        with self._child_lock:
            self._spawn(self._standing.settings)
        if wait:
            self.ready()

    def ready(self) -> None:
        """Wait for the child's first frame. Built with ``wait=False``, a runner starts its child and
        returns at once, so that the caller can build other things while the child starts (it loads
        numba's compiled kernels and builds the world: about a second); call this before using it."""
        with self._ready_lock:
            if self._latest is None:
                self._await_first_frame()

    @property
    def process(self) -> Any:
        """The simulation process (the newest: a crashed one is replaced)."""
        return self._child.process

    # ------------------------------------------------------------ process
    def _spawn(self, world: Settings) -> None:
        """Start a child with these settings and this side's controls, then the changes waiting for it
        (the caller holds the child lock: a control submitted meanwhile reaches the child, a stop stops
        it). A child never gets a light program back: whatever ran before a crash may have caused it."""
        settings = dict(config=world.config, shape=world.shape, seed=world.seed, fps=self.fps,
                        steps_per_frame=self.controls.steps_per_frame, playing=self.controls.playing,
                        chart_every=self.chart_every, program_time_limit=self.program_time_limit,
                        first_world_key=0 if self._latest is None else self._latest.world_key + 1,
                        faults=faults.from_environment())
        self._child = self._new_child(settings)
        self._spawned, self._shape, self._building, self._framed = world, world.shape, None, False
        for setting in self.controls.settings():  # the robots followed, the heat map, the hold
            self._child.send(Order(None, setting))
        waiting, self._waiting = self._waiting, []
        for command, future in waiting:
            ident = next(self._ids)
            self._owed[ident] = (future, command)
            self._child.send(Order(ident, command))
        if self._started:
            self._child.send(Order(None, Start()))
        with self._series_lock:
            self._series, self._series_world = [], None
        self._state = STARTING

    def _new_child(self, settings: dict) -> "Child":
        """A simulation process for ``settings`` (a hosted runner takes a slot in a shared host instead:
        sandbox.app.world.hosted)."""
        return Child(self._context, settings)

    def _await_first_frame(self) -> None:
        """Read the new child's messages until its first frame; if none comes, end it and raise."""
        child = self._child
        message = child.read(timeout=START_TIMEOUT)
        while message is not None and not isinstance(message, Frame):  # its last words, say
            self._take_guarded(message)
            message = child.read(timeout=START_TIMEOUT)
        if message is None:
            child.process.join(1.0)  # its pipe closes a moment before its exit code is known
            ended = child.process.exitcode
            child.end(kill=True)
            raise SimulationCrashed(self._last_words or (_ended(ended) if ended is not None else
                                                         "the simulation process did not start in time"))
        self._take(message)
        with self._child_lock:
            if self._state == STARTING and self._child is child:
                self._state = RUNNING

    def _take(self, message: Any) -> None:
        """Take one message of the child's (on the receiving thread)."""
        self._takers[type(message)](message)

    def _take_frame(self, message: Frame) -> None:
        snap = message.snap
        if snap.intensities is None and self._latest is not None and self._latest.lights_key == snap.lights_key:
            snap = dataclasses.replace(snap, intensities=self._latest.intensities)  # sent once per lights
        with self._series_lock:
            if message.world != self._series_world:  # a new world: its samples start a new series
                self._series, self._series_world = [], message.world
            self._series.extend(message.samples)
        self._latest = snap
        self._framed = True
        self._watch_run(snap)
        self._publish(snap)

    def _take_done(self, message: Done) -> None:
        future = self._take_owed(message.ident)
        if future is not None:
            future.set_result(message.result)

    def _take_failed(self, message: Failed) -> None:
        future = self._take_owed(message.ident)
        if future is not None:
            future.set_exception(message.error)

    def _take_progress(self, message: Progress) -> None:
        for listener in list(self._progress_listeners):
            self._deliver(listener, message.fraction)

    def _take_building(self, message: Building) -> None:
        self._building = None if message.settings is None else self._settings_built(*message.settings)

    def _take_halted(self, message: Halted) -> None:
        for listener in list(self._halt_listeners):
            self._deliver(listener, message.why)

    def _take_last_words(self, message: LastWords) -> None:
        self._last_words = message.why

    def _settings_built(self, config: Config, goal: Any, seed: int | None) -> Settings:
        """What the child said it builds, with its goal as this side keeps goals."""
        if isinstance(goal, str) and goal == SAME_GOAL:
            goal = self._shape
        elif goal is not None:
            goal = np.asarray(goal, dtype=float)
        return Settings(config, goal, seed)

    def _watch_run(self, snap: Snapshot) -> None:
        """A world (and goal) that took ``proven_steps`` steps, or stepped for ``proven_seconds``, ran:
        its settings stand (sandbox.app.world.standing)."""
        key, now = (snap.world_key, snap.goal_key), time.monotonic()
        if self._trial is None or self._trial[0] != key:
            self._trial = (key, now, snap.step, False)
            return
        _, since, first, ran = self._trial
        stepped = snap.step - first
        if not ran and (stepped >= self.proven_steps or (stepped > 0 and now - since >= self.proven_seconds)):
            self._trial = (key, since, first, True)
            self._standing.ran(Settings(snap.world_config, self._shape, snap.seed))

    def _take_guarded(self, message: Any) -> None:
        try:
            self._take(message)
        except Exception as exc:  # noqa: BLE001 - this thread alone reads frames and notices crashes
            self.errors.append(exc)
            log.exception("a message from the simulation process could not be handled")

    def _take_owed(self, ident: int) -> Future | None:
        with self._child_lock:
            future, _ = self._owed.pop(ident, (None, None))
            return future

    def _fail_owed(self, why: BaseException, keep_changes: bool = False) -> None:
        """Fail every future the child owes (it died, or the runner stopped). ``keep_changes``: changes of
        settings it owed wait for the next child instead (it died before its first frame: they never
        reached a world)."""
        with self._child_lock:
            owed, self._owed = list(self._owed.values()), {}
            if keep_changes:
                self._waiting[:0] = [(c, f) for f, c in owed if isinstance(c, UpdateConfig)]
                owed = [(f, c) for f, c in owed if not isinstance(c, UpdateConfig)]
        for future, _ in owed:
            future.set_exception(why)

    def _fail_waiting(self, why: BaseException) -> None:
        """Fail the changes waiting for a next child: there will be none (given up, or stopped)."""
        with self._child_lock:
            waiting, self._waiting = self._waiting, []
        for _, future in waiting:
            future.set_exception(why)

    def _receive_loop(self) -> None:
        while not self._stop.is_set():
            child = self._child
            message = child.read(timeout=0.5)
            if message is not None:
                self._take_guarded(message)
            elif self.failed is not None:
                self._stop.wait(0.5)  # given up: nothing to read, nothing to restart
            elif not child.process.is_alive() and not self._stop.is_set():
                try:
                    self._recover(child)
                except Exception as exc:  # noqa: BLE001 - never let this thread die
                    self.errors.append(exc)
                    log.exception("recovering the simulation process failed")

    def _recover(self, child: Child) -> None:
        """The child died: fail what it owed, end any progress shown, reap it, tell the listeners, and
        start a new one with the paper's controller after a growing pause, from the settings that stand
        (sandbox.app.world.standing); after too many crashes, give up and say so."""
        with self._child_lock:
            if self._state == STOPPED or self._child is not child:
                return
            self._state = DOWN  # from here on, changes wait and other commands fail until a new child
        while (message := child.read(timeout=0)) is not None:  # what it managed to say before dying
            self._take_guarded(message)
        cause = self._last_words or _ended(child.process.exitcode)
        self._last_words = None
        self._fail_owed(SimulationCrashed(cause), keep_changes=not self._framed)
        for listener in list(self._progress_listeners):
            self._deliver(listener, None)
        child.end()
        failed = self._failed_settings()
        restart = self._standing.crashed(failed)
        now = time.monotonic()
        self._crash_times.append(now)
        recent = sum(now - t <= self.crash_window for t in self._crash_times)
        crashes = max(recent, self._standing.crashes)
        if crashes >= self.crashes_before_giving_up:
            self._give_up(recent, cause)
            return
        pause = self.restart_pause * 2 ** (crashes - 1)
        if restart.went_back:
            for listener in list(self._back_listeners):
                self._deliver(listener, restart.settings.config)
            self._tell_crash(gone_back(cause, failed, restart.settings))
        else:
            self._keep_waiting_changes(failed)
            self._tell_crash(f"{cause}; restarting in {pause:g} s from the last settings, with the paper's "
                             f"controller")
        if self._stop.wait(pause):
            return
        with self._child_lock:
            if self._state == STOPPED:  # stopped during the pause: no new child
                return
            self.restarts += 1
            self._spawn(restart.settings)
        try:
            self._await_first_frame()
        except Exception as exc:  # could not start again: keep the last picture; the loop tries again
            if not self._stop.is_set():
                self.errors.append(exc)
                log.warning("the simulation process did not restart: %s", exc)

    def _failed_settings(self) -> Settings:
        """What the dead child was building (a new world or goal), or else running."""
        if self._building is not None:
            return self._building
        snap = self._latest
        if not self._framed or snap is None:  # it died building its first world
            return self._spawned
        return Settings(snap.world_config, self._shape, snap.seed)

    def _keep_waiting_changes(self, failed: Settings) -> None:
        """The dead child's changes waiting for a reset wait in the next child, which starts from
        ``failed`` (the world the dead one ran; not when it went back: they may be what failed)."""
        snap = self._latest
        if not self._framed or snap is None:
            return
        changes = {name: getattr(snap.config, name) for name in changed(snap.config, failed.config)}
        if changes:
            with self._child_lock:
                self._waiting.insert(0, (UpdateConfig(changes), Future()))

    def _give_up(self, recent: int, cause: str) -> None:
        if recent >= self.crashes_before_giving_up:
            self.failed = f"the simulation cannot start: it stopped {recent} times within a minute (last: {cause})"
        else:
            self.failed = (f"the simulation cannot start: it stopped {self._standing.crashes} times with no world "
                           f"running in between (last: {cause})")
        self._fail_waiting(SimulationCrashed(self.failed))  # no child will take them
        self._tell_crash(self.failed)

    def _tell_crash(self, why: str) -> None:
        for listener in list(self._crash_listeners):
            self._deliver(listener, why)

    # ------------------------------------------------------------ control
    def start(self) -> "ProcessRunner":
        self.ready()
        self._thread = threading.Thread(target=self._receive_loop, name="phototaxis-receiver", daemon=True)
        self._thread.start()
        with self._child_lock:
            self._started = True  # a child spawned from now on is told to start
        self.submit(Start())
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """End the child and the receiver; every command not answered yet fails with RunnerStopped. A
        running child may end by itself within STOP_GRACE s (or ``timeout``, if shorter); one still
        building its first world, or busy, is killed."""
        self._stop.set()
        with self._child_lock:  # after this no child is spawned, and the one there is is ours to end
            running = self._state == RUNNING
            self._state = STOPPED
            child = self._child
            if running:
                child.send(None)  # the child's loop ends
        self._fail_owed(RunnerStopped("the simulation was stopped"))
        self._fail_waiting(RunnerStopped("the simulation was stopped"))
        if running:
            child.process.join(min(timeout, STOP_GRACE))
        child.end(kill=True, timeout=timeout)
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def on_crash(self, listener: Callable[[str], None]) -> None:
        """``listener(why)`` hears each crash of the child: what happened, and what comes next."""
        self._crash_listeners.append(listener)

    def on_settings_back(self, listener: Callable[[Config], None]) -> None:
        """``listener(config)`` hears that after a crash the new child starts from other settings than
        the dead one's, the last that ran (the panel shows them again; nothing waits for a reset)."""
        self._back_listeners.append(listener)

    @property
    def standing(self) -> Settings:
        """The settings that stand: the last that ran (sandbox.app.world.standing)."""
        return self._standing.settings

    def on_progress(self, listener: Callable[[float | None], None]) -> None:
        self._progress_listeners.append(listener)

    def on_halt(self, listener: Callable[[str], None]) -> None:
        self._halt_listeners.append(listener)

    def submit(self, command: Command) -> Future:
        """Send ``command`` to the child. A control acts on this side's copy of the controls at once
        and its future is done when it is sent (or, with no child, kept for the next one); any other
        command's future is settled by the child's answer. Between a crash and the restart, a change of
        settings (UpdateConfig) waits for the next child (the teacher can always set values back); any
        other command fails at once when no child can take it (then, after giving up, or stopped)."""
        future: Future = Future()
        if not command.at_once:
            unsendable = _unpicklable(command)
            if unsendable is not None:
                future.set_exception(unsendable)
                return future
        with self._child_lock:
            if isinstance(command, Setting):
                command.settle(self.controls)  # what a new child gets, if this one does not take it
            sent = False
            if self._state in (STARTING, RUNNING):
                ident = None if command.at_once else next(self._ids)
                if ident is not None:
                    self._owed[ident] = (future, command)
                sent = self._child.send(Order(ident, command))
                if not sent and ident is not None:
                    self._owed.pop(ident, None)
            elif self._state == DOWN and self.failed is None and isinstance(command, UpdateConfig):
                self._waiting.append((command, future))
                sent = True  # to the next child
            refusal = None if sent or command.at_once else self._refusal()
        if refusal is not None:
            future.set_exception(refusal)
        elif command.at_once:
            future.set_result(None)
        elif isinstance(command, SetShape):
            future.add_done_callback(lambda done: self._remember_shape(command, done))
        return future

    def _refusal(self) -> BaseException:
        """Why no child can take a command now (the caller holds the child lock)."""
        if self._state == STOPPED:
            return RunnerStopped("the simulation was stopped")
        return SimulationCrashed(self.failed or "the simulation is restarting; try again")

    def _remember_shape(self, command: SetShape, future: Future) -> None:
        """A goal the child took is what a restarted child gets back."""
        if not future.cancelled() and future.exception() is None:
            self._shape = None if command.vertices is None else np.asarray(command.vertices, dtype=float)

    # -------------------------------------------------------------- state
    @property
    def latest(self) -> Snapshot:
        if self._latest is None:
            self.ready()  # built with wait=False and not yet asked
        assert self._latest is not None
        return self._latest

    def series(self) -> list[Sample]:
        with self._series_lock:
            return list(self._series)


def _ended(exitcode: int | None) -> str:
    """Why a child ended, from its exit code: killed outright (SIGKILL) is most often the kernel's
    out-of-memory killer."""
    if exitcode == -signal.SIGKILL:
        return f"the simulation process was killed, most likely out of memory (exit code {exitcode})"
    return f"the simulation process stopped (exit code {exitcode})"


def _not_built(exc: Exception) -> str:
    """Why a simulation process could not build its first world, in a line."""
    said = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    if isinstance(exc, MemoryError) or "bad_alloc" in said:  # numpy's, or a C++ library's (GEOS)
        return f"the simulation process ran out of memory building the world ({said})"
    return f"the world could not be built ({type(exc).__name__}: {said})"


def _unpicklable(command: Command) -> BaseException | None:
    """Why ``command`` cannot be sent to the child, or None. Checked here: the queue pickles on a thread
    of its own, where a failure would only be printed, and the command's future would wait forever."""
    try:
        pickle.dumps(command)
    except Exception as exc:  # noqa: BLE001 - any reason pickle gives
        return TypeError(f"{command!r} cannot be sent to the simulation process: {exc}")
    return None


# ------------------------------------------------------------------ child
class FrameSamples:
    """Makes a runner's :class:`Frame` messages: each with the metric samples of its world the parent has
    not had yet (a new world starts its series again), and without the lights' intensities when the
    parent has them (the same lights as the frame before: 33 of the paper's world's 58 KB a frame; the
    parent puts them back, :meth:`ProcessRunner._take_frame`). One per runner, on the thread that sends
    its frames."""

    def __init__(self) -> None:
        self._world: int | None = None
        self._count = 0
        self._lights: tuple | None = None  # the lights_key of the frame sent last

    def frame(self, runner: Runner, snap: Snapshot) -> Frame:
        world, series = runner.series_of_world()
        start = self._count if self._world == world else 0
        self._world, self._count = world, len(series)
        if snap.lights_key == self._lights:
            snap = dataclasses.replace(snap, intensities=None)
        self._lights = snap.lights_key
        return Frame(snap, series[start:], world)


def _child_main(settings: dict, commands: Any, send: Any) -> None:
    """The simulation process: an ordinary Runner, driven by the queue (an :class:`Order` each; None ends
    it), answering with the typed messages above."""
    # Ctrl-C in a terminal reaches every process of the group: it is for the app, which stops this
    # one (before, each Ctrl-C printed this process's KeyboardInterrupt traceback under "stopped").
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    faults.install(settings.pop("faults", None))
    # shared by the child's threads that send on its pipe: the simulation and publisher threads
    lock = threading.Lock()
    try:
        runner = Runner(**settings)
    except Exception as exc:  # noqa: BLE001 - its first world cannot be built: say why in a line
        send.send(LastWords(_not_built(exc)))
        os._exit(1)
    samples = FrameSamples()

    def send_message(message: Any) -> None:
        with lock:
            try:
                send.send(message)
            except (BrokenPipeError, EOFError, OSError):
                runner.stop(timeout=0)  # the parent is gone

    def on_frame(snap: Snapshot) -> None:
        send_message(samples.frame(runner, snap))

    def answer(ident: int, future: Future) -> None:
        exc = future.exception()
        if exc is None:
            send_message(Done(ident, _picklable(future.result())))
        else:
            send_message(Failed(ident, _picklable_error(exc)))

    def stuck(why: str) -> None:  # a light program would not stop: say so, then end (no thread can unwind it)
        send_message(LastWords(f"{why}; the app restarts the simulation with the paper's controller"))
        os._exit(STUCK_EXIT)

    watchdog.on_stuck = stuck
    on_frame(runner.latest)
    runner.subscribe(on_frame)
    runner.on_progress(lambda fraction: send_message(Progress(fraction)))
    runner.on_build(lambda settings: send_message(Building(settings)))
    runner.on_halt(lambda why: send_message(Halted(why)))  # the parent owns play: it pauses
    app = multiprocessing.parent_process()  # the app's process (the fork server is only this one's parent)
    while True:
        try:
            message = commands.get(timeout=1.0)
        except queue.Empty:
            if not app.is_alive() or runner.stopped:  # the app is gone, or stopped listening
                break
            continue
        if message is None:
            break
        future = runner.submit(message.command)
        if message.ident is not None:
            future.add_done_callback(lambda done, ident=message.ident: answer(ident, done))
    runner.stop()
    send.close()


def _picklable(value: Any) -> Any:
    try:
        pickle.dumps(value)
        return value
    except Exception:
        return repr(value)


def _picklable_error(exc: BaseException) -> BaseException:
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:
        return RuntimeError("".join(traceback.format_exception_only(type(exc), exc)).strip())
