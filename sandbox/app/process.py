"""The simulation in its own process, behind the :class:`~sandbox.app.runner.Runner` API.

In one process the web server (viser's event loop, scene and panel updates)
and the simulation share the GIL, and the live app stepped at less than half
of the headless speed. :class:`ProcessRunner` runs an ordinary
:class:`Runner` in a child process instead, so the two use two cores:

- commands (picklable callables ``f(sim)``, and the runner's own controls)
  go to the child through a queue; their results or exceptions come back
  and reach the ``on_done`` / ``on_error`` callbacks in this process;
- every snapshot the child publishes (the newest one only, at the frame
  rate) comes back through a pipe with the metric samples recorded since
  the last one, and reaches this side's listeners;
- if the child dies, listeners of :meth:`on_crash` hear why, and a new child
  starts from the last known settings, shape and seed.

A :class:`Runner` in a thread of this process (what tests and headless
recording use) has the same API; the app takes either.
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import os
import queue
import signal
import threading
import time
import traceback
from collections import deque
from typing import Any, Callable, Iterable

import numpy as np

from sandbox.app.contract import FramePublisher
from sandbox.app.runner import Command, Runner, wait_for
from sandbox.app.snapshot import Snapshot
from sandbox.model import watchdog
from sandbox.model.config import Config
from sandbox.model.metrics import Sample
from sandbox.processes import simulation_context

#: How long the parent waits for a new child's first snapshot (imports, numba cache, world building).
START_TIMEOUT = 120.0
#: After a crash the child is restarted after this pause, doubled for each crash within CRASH_WINDOW seconds.
RESTART_PAUSE = 1.0
CRASH_WINDOW = 60.0
#: This many crashes within CRASH_WINDOW and the app stops restarting the simulation.
CRASHES_BEFORE_GIVING_UP = 5
#: A child's exit code when a light program would not stop (it said why just before).
STUCK_EXIT = 75

log = logging.getLogger("sandbox.app.process")


class SimulationCrashed(RuntimeError):
    """The simulation process ended without being asked to."""


class ProcessRunner(FramePublisher):
    """A :class:`Runner` in a child process (see the module docstring); a :class:`SimulationRunner`."""

    def __init__(self, config: Config, *, shape: Any = "from-config", seed: int | None = None,
                 fps: float = 30.0, steps_per_frame: int = 10, playing: bool = True, chart_every: int = 100,
                 program_time_limit: float = watchdog.DEFAULT_LIMIT, wait: bool = True):
        self.fps = float(fps)
        self.steps_per_frame = int(steps_per_frame)
        self.playing = bool(playing)
        self.chart_every = int(chart_every)
        self.program_time_limit = float(program_time_limit)
        FramePublisher.__init__(self)
        self.followed: tuple[int, ...] = ()
        self.hold_at: int | None = None
        self._want_field = False
        self.restarts = 0
        #: Why the simulation cannot run any more (too many crashes in a row), or None.
        self.failed: str | None = None
        #: Seconds before the first restart after a crash (doubled for each crash within CRASH_WINDOW),
        #: and how many crashes within CRASH_WINDOW make it give up.
        self.restart_pause, self.crashes_before_giving_up = RESTART_PAUSE, CRASHES_BEFORE_GIVING_UP
        self._crash_times: deque = deque(maxlen=64)
        self._last_words: str | None = None  # what a dying child said last (a program that would not stop)
        self._crash_listeners: list[Callable[[str], None]] = []
        self._progress_listeners: list[Callable[[float | None], None]] = []
        self._callbacks: dict[int, tuple[Callable | None, Callable | None]] = {}
        self._callbacks_lock = threading.Lock()  # written by viser's threads, read by the receiver
        self._ids = itertools.count()
        self._series: list[Sample] = []
        self._series_world: int | None = None  # the world key of the samples in _series
        self._series_lock = threading.Lock()
        self._latest: Snapshot | None = None
        self._latest_ready = threading.Condition()
        self._stop = threading.Event()
        self._ready_lock = threading.Lock()
        self._started = False
        self._context = simulation_context()  # a fork of a warmed-up server, else a fresh interpreter
        #: The goal as last given (a name, or vertices as drawn): a restarted child gets it back unchanged,
        #: since the program's largest outline depends on the size a shape was drawn at.
        self._shape = shape
        self._spawn(config, shape, seed)
        if wait:
            self.ready()

    def ready(self) -> None:
        """Wait for the child's first frame. Built with ``wait=False``, a runner starts its child and
        returns at once, so that the caller can build other things while the child starts (it loads
        numba's compiled kernels and builds the world: about a second); call this before using it."""
        with self._ready_lock:
            if self._awaiting_first_frame:
                self._await_first_frame()

    # ------------------------------------------------------------ process
    def _launch(self, config: Config, shape: Any, seed: int | None) -> None:
        """Start a child with these settings and wait for its first frame. A child never gets a
        light program back: whatever ran before a crash may have caused it."""
        self._spawn(config, shape, seed)
        self._await_first_frame()

    def _spawn(self, config: Config, shape: Any, seed: int | None) -> None:
        self._commands = self._context.Queue()
        receive, send = self._context.Pipe(duplex=False)
        settings = dict(config=config, shape=shape, seed=seed, fps=self.fps, steps_per_frame=self.steps_per_frame,
                        playing=self.playing, chart_every=self.chart_every,
                        program_time_limit=self.program_time_limit)
        self.process = self._context.Process(target=_child_main, args=(settings, self._commands, send),
                                             name="phototaxis-simulation", daemon=True)
        self.process.start()
        send.close()  # the child holds the sending end
        self._receive = receive
        with self._series_lock:
            self._series, self._series_world = [], None
        self._awaiting_first_frame = True

    def _await_first_frame(self) -> None:
        self._awaiting_first_frame = False
        message = self._read(timeout=START_TIMEOUT)
        while message is not None and message[0] != "frame":  # its last words, say
            self._take_guarded(message)
            message = self._read(timeout=START_TIMEOUT)
        if message is None:
            self._end_child(kill=True)
            raise SimulationCrashed(self._last_words or "the simulation process did not start")
        self._take(message)
        for name, value in (("followed", self.followed), ("want_field", self._want_field)):
            if value:  # what differs from a fresh runner's
                self._control(name, value)
        if self.hold_at is not None:
            self._control("hold", self.hold_at)
        if self._started:
            self._control("start")

    def _end_child(self, kill: bool = False, timeout: float = 5.0) -> None:
        """Reap the child (killing it first if asked) and close its pipe and queue."""
        if kill and self.process.is_alive():
            self.process.kill()
        self.process.join(timeout)
        for close in (self._receive.close, self._commands.close, self._commands.cancel_join_thread):
            try:
                close()
            except (OSError, ValueError):
                pass

    def _read(self, timeout: float) -> Any:
        try:
            if self._receive.poll(timeout):
                return self._receive.recv()
        except (EOFError, OSError):
            pass
        return None

    def _take(self, message: tuple) -> None:
        kind = message[0]
        if kind == "frame":
            _, snap, samples, world = message
            with self._series_lock:
                if world != self._series_world:  # a new world: its samples start a new series
                    self._series, self._series_world = [], world
                self._series.extend(samples)
            with self._latest_ready:
                self._latest = snap
                self._latest_ready.notify_all()
            self._publish(snap)
        elif kind == "done":
            _, ident, result = message
            on_done, _ = self._pop_callbacks(ident)
            if on_done:
                self._deliver(on_done, result)
        elif kind == "progress":
            for listener in list(self._progress_listeners):
                self._deliver(listener, message[1])
        elif kind == "error":
            _, ident, exc = message
            _, on_error = self._pop_callbacks(ident)
            if on_error:
                self._deliver(on_error, exc)
            else:
                self.errors.append(exc)
        elif kind == "last words":
            self._last_words = message[1]

    def _take_guarded(self, message: Any) -> None:
        try:
            self._take(message)
        except Exception as exc:  # noqa: BLE001 - this thread alone reads frames and notices crashes
            self.errors.append(exc)
            log.exception("a message from the simulation process could not be handled")

    def _pop_callbacks(self, ident: int) -> tuple[Callable | None, Callable | None]:
        with self._callbacks_lock:
            return self._callbacks.pop(ident, (None, None))

    def _receive_loop(self) -> None:
        while not self._stop.is_set():
            message = self._read(timeout=0.5)
            if message is not None:
                self._take_guarded(message)
            elif not self.process.is_alive() and not self._stop.is_set() and self.failed is None:
                try:
                    self._recover()
                except Exception as exc:  # noqa: BLE001 - never let this thread die
                    self.errors.append(exc)
                    log.exception("recovering the simulation process failed")

    def _recover(self) -> None:
        """The child died: fail what it was doing, end any progress shown, reap it, tell the
        listeners, and start a new one with the paper's controller after a growing pause; after
        too many crashes in a minute, give up and say so."""
        code = self.process.exitcode
        while (message := self._read(timeout=0)) is not None:  # what it managed to say before dying
            self._take_guarded(message)
        cause = self._last_words or f"the simulation process stopped (exit code {code})"
        self._last_words = None
        with self._callbacks_lock:
            pending, self._callbacks = list(self._callbacks.values()), {}
        for _, on_error in pending:
            if on_error:
                self._deliver(on_error, SimulationCrashed(cause))
        for listener in list(self._progress_listeners):
            self._deliver(listener, None)
        self._end_child()
        now = time.monotonic()
        self._crash_times.append(now)
        recent = [t for t in self._crash_times if now - t <= CRASH_WINDOW]
        if len(recent) >= self.crashes_before_giving_up:
            self.failed = (f"the simulation cannot start: it stopped {len(recent)} times within a minute "
                           f"(last: {cause})")
            self._tell_crash(self.failed)
            return
        pause = self.restart_pause * 2 ** (len(recent) - 1)
        self._tell_crash(f"{cause}; restarting in {pause:g} s from the last settings, with the paper's controller")
        if self._stop.wait(pause):
            return
        snap = self.latest
        self.restarts += 1
        try:
            self._launch(snap.config, self._shape, snap.seed)
        except Exception as exc:  # could not start again: keep the last picture; the loop tries again
            self.errors.append(exc)
            log.warning("the simulation process did not restart: %s", exc)

    def _tell_crash(self, why: str) -> None:
        for listener in list(self._crash_listeners):
            self._deliver(listener, why)

    # ------------------------------------------------------------ control
    def start(self) -> "ProcessRunner":
        self.ready()
        self._thread = threading.Thread(target=self._receive_loop, name="phototaxis-receiver", daemon=True)
        self._thread.start()
        self._started = True
        self._control("start")
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        try:
            self._commands.put(("stop",))
        except (OSError, ValueError):
            pass
        self.process.join(timeout)
        self._end_child(kill=True, timeout=timeout)
        if getattr(self, "_thread", None):
            self._thread.join(timeout)

    def on_crash(self, listener: Callable[[str], None]) -> None:
        self._crash_listeners.append(listener)

    def _control(self, *message: Any) -> None:
        self._send(("control", *message))

    def _send(self, message: tuple) -> bool:
        """Queue a message for the child; False when there is none to take it (between a crash and
        the restart, or after giving up)."""
        try:
            self._commands.put(message)
            return True
        except (OSError, ValueError, AssertionError):
            return False

    def post(self, command: Command, *, on_done: Callable[[Any], None] | None = None,
             on_error: Callable[[BaseException], None] | None = None) -> None:
        """Run ``command(sim)`` in the simulation process; ``command`` must be
        picklable (a module-level function or a ``functools.partial`` of one).
        The callbacks run here, on the receiving thread; keep them short."""
        self._queue_call(("command", command), on_done, on_error)

    def update_config(self, changes: dict[str, Any], *, on_done: Callable[[Any], None] | None = None,
                      on_error: Callable[[BaseException], None] | None = None) -> None:
        """As :meth:`Runner.update_config`, run by the child's runner (which keeps the waiting changes)."""
        self._runner_call("update_config", on_done, on_error, dict(changes))

    def call(self, command: Command, timeout: float = 10.0) -> Any:
        return wait_for(self.post, command, timeout)

    def set_playing(self, playing: bool) -> None:
        self.playing = bool(playing)
        self._control("playing", self.playing)

    def set_speed(self, steps_per_frame: int) -> None:
        self.steps_per_frame = max(1, int(steps_per_frame))
        self._control("speed", self.steps_per_frame)

    def follow(self, indices: Iterable[int]) -> None:
        self.followed = tuple(sorted({int(i) for i in indices}))
        self._control("followed", self.followed)

    @property
    def want_field(self) -> bool:
        return self._want_field

    @want_field.setter
    def want_field(self, value: bool) -> None:
        self._want_field = bool(value)
        self._control("want_field", self._want_field)

    def step_once(self, n: int = 1) -> None:
        self._control("step", int(n))

    def hold(self, step: int | None) -> None:
        self.hold_at = None if step is None else int(step)
        self._control("hold", self.hold_at)

    def run_to(self, step: int) -> None:
        self._control("run_to", int(step))

    def reset(self, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> None:
        self._runner_call("reset", on_done, on_error, seed)

    def cancel_build(self) -> None:
        self._control("cancel")

    def on_progress(self, listener: Callable[[float | None], None]) -> None:
        self._progress_listeners.append(listener)

    def set_shape(self, vertices: np.ndarray | None, name: str, *, on_done: Callable[[Any], None] | None = None,
                  on_error: Callable[[BaseException], None] | None = None) -> None:
        shape = None if vertices is None else np.asarray(vertices, dtype=float)

        def used(notes: Any) -> None:
            self._shape = shape  # what a restarted child gets back
            if on_done:
                on_done(notes)

        self._runner_call("set_shape", used, on_error, shape, name)

    def set_program(self, spec: str | None, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> None:
        self._runner_call("set_program", on_done, on_error, spec)

    def set_lamp(self, centre: tuple[float, float] | None, radius: float | None = None, mode: str = "lamp", *,
                 on_done: Callable[[Any], None] | None = None,
                 on_error: Callable[[BaseException], None] | None = None) -> None:
        self._runner_call("set_lamp", on_done, on_error, centre, radius, mode)

    def world_spec(self, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> None:
        self._runner_call("world_spec", on_done, on_error)

    def set_outline(self, outline: str, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> None:
        self._runner_call("set_outline", on_done, on_error, outline)

    def _runner_call(self, method: str, on_done: Callable | None, on_error: Callable | None, *args: Any) -> None:
        """Call one of the child's Runner methods that report back (reset, set_shape, update_config)."""
        self._queue_call(("runner_call", method, args), on_done, on_error)

    def _queue_call(self, message: tuple, on_done: Callable | None, on_error: Callable | None) -> None:
        """Send a call that reports back; if no child can take it, its on_error hears why at once."""
        ident = next(self._ids)
        with self._callbacks_lock:
            self._callbacks[ident] = (on_done, on_error)
        if self.failed is None and self._send((message[0], ident, *message[1:])):
            return
        self._pop_callbacks(ident)
        if on_error:
            self._deliver(on_error, SimulationCrashed(self.failed or "the simulation is restarting; try again"))

    # -------------------------------------------------------------- state
    @property
    def latest(self) -> Snapshot:
        if self._latest is None:
            self.ready()  # built with wait=False and not yet asked
        assert self._latest is not None
        return self._latest

    def wait_for_frame(self, after: int, timeout: float = 10.0) -> Snapshot:
        """The first snapshot newer than frame ``after``."""
        with self._latest_ready:
            self._latest_ready.wait_for(lambda: self._latest is not None and self._latest.frame > after, timeout)
        return self.latest

    def series(self) -> list[Sample]:
        with self._series_lock:
            return list(self._series)

    def steps_per_second(self) -> float:
        return self.latest.steps_per_second



# ------------------------------------------------------------------ child
def _child_main(settings: dict, commands: Any, send: Any) -> None:
    """The simulation process: an ordinary Runner, driven by the queue."""
    # Ctrl-C in a terminal reaches every process of the group: it is for the app, which stops this
    # one (before, each Ctrl-C printed this process's KeyboardInterrupt traceback under "stopped").
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    runner = Runner(**settings)
    sent = {"world": None, "count": 0}
    lock = threading.Lock()

    def send_message(message: tuple) -> None:
        with lock:
            try:
                send.send(message)
            except (BrokenPipeError, EOFError, OSError):
                runner.stop(timeout=0)  # the parent is gone

    def on_frame(snap: Snapshot) -> None:  # with the samples the parent has not had, of this world
        world, series = runner.series_of_world()
        start = sent["count"] if sent["world"] == world else 0
        sent.update(world=world, count=len(series))
        send_message(("frame", snap, series[start:], world))

    def reply(ident: int):
        return (lambda result: send_message(("done", ident, _picklable(result))),
                lambda exc: send_message(("error", ident, _picklable_error(exc))))

    def stuck(why: str) -> None:  # a light program would not stop: say so, then end (no thread can unwind it)
        send_message(("last words", f"{why}; the app restarts the simulation with the paper's controller"))
        os._exit(STUCK_EXIT)

    watchdog.on_stuck = stuck
    on_frame(runner.latest)
    runner.subscribe(on_frame)
    runner.on_progress(lambda fraction: send_message(("progress", fraction)))
    app = multiprocessing.parent_process()  # the app's process (the fork server is only this one's parent)
    while True:
        try:
            message = commands.get(timeout=1.0)
        except queue.Empty:
            if not app.is_alive() or runner.stopped:  # the app is gone, or stopped listening
                break
            continue
        kind = message[0]
        if kind == "stop":
            break
        if kind == "command":
            _, ident, command = message
            on_done, on_error = reply(ident)
            runner.post(command, on_done=on_done, on_error=on_error)
        elif kind == "runner_call":
            _, ident, method, args = message
            on_done, on_error = reply(ident)
            getattr(runner, method)(*args, on_done=on_done, on_error=on_error)
        elif kind == "control":
            _apply_control(runner, message[1], *message[2:])
    runner.stop()
    send.close()


def _apply_control(runner: Runner, name: str, *args: Any) -> None:
    if name == "start":
        runner.start()
    elif name == "playing":
        runner.set_playing(args[0])
    elif name == "speed":
        runner.set_speed(args[0])
    elif name == "followed":
        runner.follow(args[0])
    elif name == "want_field":
        runner.want_field = args[0]
        runner.wake()
    elif name == "step":
        runner.step_once(args[0])
    elif name == "hold":
        runner.hold(args[0])
    elif name == "run_to":
        runner.run_to(args[0])
    elif name == "cancel":
        runner.cancel_build()


def _picklable(value: Any) -> Any:
    import pickle

    try:
        pickle.dumps(value)
        return value
    except Exception:
        return repr(value)


def _picklable_error(exc: BaseException) -> BaseException:
    import pickle

    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:
        return RuntimeError("".join(traceback.format_exception_only(type(exc), exc)).strip())
