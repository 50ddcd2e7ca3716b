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
import multiprocessing
import os
import queue
import threading
import time
import traceback
from collections import deque
from typing import Any, Callable

import numpy as np

from sandbox.app.runner import Command, Runner, publish, wait_for
from sandbox.app.snapshot import Snapshot
from sandbox.model.config import Config
from sandbox.model.metrics import Sample

#: How long the parent waits for a new child's first snapshot (imports, numba cache, world building).
START_TIMEOUT = 120.0


class SimulationCrashed(RuntimeError):
    """The simulation process ended without being asked to."""


class ProcessRunner:
    """A :class:`Runner` in a child process (see the module docstring)."""

    def __init__(self, config: Config, *, shape: Any = "from-config", seed: int | None = None,
                 fps: float = 30.0, steps_per_frame: int = 10, playing: bool = True, chart_every: int = 100):
        self.fps = float(fps)
        self.steps_per_frame = int(steps_per_frame)
        self.playing = bool(playing)
        self.chart_every = int(chart_every)
        self.selected: int | None = None
        self._want_field = False
        self.errors: list[BaseException] = []
        self.restarts = 0
        self._listeners: list[Callable[[Snapshot], None]] = []
        self._crash_listeners: list[Callable[[str], None]] = []
        self._progress_listeners: list[Callable[[float | None], None]] = []
        self._callbacks: dict[int, tuple[Callable | None, Callable | None]] = {}
        self._ids = itertools.count()
        self._series: list[Sample] = []
        self._series_lock = threading.Lock()
        self._latest: Snapshot | None = None
        self._latest_ready = threading.Condition()
        self._stop = threading.Event()
        self._started = False
        self.frames_published = 0
        self.publish_times: deque = deque(maxlen=120)
        self._context = multiprocessing.get_context("spawn")  # fresh interpreter, same on every OS
        #: The goal as last given (a name, or vertices as drawn): a restarted child gets it back unchanged,
        #: since the program's largest outline depends on the size a shape was drawn at.
        self._shape = shape
        self._program: str | None = None  # a light program's path:Class; a restarted child gets it back
        self._launch(config, shape, seed)

    # ------------------------------------------------------------ process
    def _launch(self, config: Config, shape: Any, seed: int | None) -> None:
        self._commands = self._context.Queue()
        receive, send = self._context.Pipe(duplex=False)
        settings = dict(config=config, shape=shape, seed=seed, fps=self.fps, steps_per_frame=self.steps_per_frame,
                        playing=self.playing, chart_every=self.chart_every)
        self.process = self._context.Process(target=_child_main, args=(settings, self._commands, send),
                                             name="phototaxis-simulation", daemon=True)
        self.process.start()
        send.close()  # the child holds the sending end
        self._receive = receive
        with self._series_lock:
            self._series = []
        message = self._read(timeout=START_TIMEOUT)
        if message is None:
            self.process.kill()
            raise SimulationCrashed("the simulation process did not start")
        self._take(message)
        for name, value in (("selected", self.selected), ("want_field", self._want_field)):
            if value is not None and value is not False:
                self._control(name, value)
        if self._program:
            self._runner_call("set_program", None, None, self._program)
        if self._started:
            self._control("start")

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
            _, snap, samples, series_length = message
            with self._series_lock:
                if series_length < len(self._series) + len(samples):  # the child started a new series (reset)
                    self._series = self._series[: max(0, series_length - len(samples))]
                self._series.extend(samples)
            with self._latest_ready:
                self._latest = snap
                self._latest_ready.notify_all()
            self._publish(snap)
        elif kind == "done":
            _, ident, result = message
            on_done, _ = self._callbacks.pop(ident, (None, None))
            if on_done:
                on_done(result)
        elif kind == "progress":
            for listener in list(self._progress_listeners):
                listener(message[1])
        elif kind == "error":
            _, ident, exc = message
            _, on_error = self._callbacks.pop(ident, (None, None))
            if on_error:
                on_error(exc)
            else:
                self.errors.append(exc)

    def _publish(self, snap: Snapshot) -> None:
        publish(self, snap)

    def _receive_loop(self) -> None:
        while not self._stop.is_set():
            message = self._read(timeout=0.5)
            if message is not None:
                self._take(message)
            elif not self.process.is_alive() and not self._stop.is_set():
                self._recover()

    def _recover(self) -> None:
        """The child died: tell the listeners, fail what it was doing, start a new one."""
        code = self.process.exitcode
        why = f"the simulation process stopped (exit code {code}); restarted from the last settings"
        for _, on_error in self._callbacks.values():
            if on_error:
                on_error(SimulationCrashed(why))
        self._callbacks.clear()
        for listener in list(self._crash_listeners):
            try:
                listener(why)
            except Exception as exc:
                self.errors.append(exc)
        snap = self.latest
        self.restarts += 1
        try:
            self._launch(snap.config, self._shape, snap.seed)
        except Exception as exc:  # could not start again: keep the last picture, say so
            self.errors.append(exc)
            time.sleep(1.0)

    # ------------------------------------------------------------ control
    def start(self) -> "ProcessRunner":
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
        if self.process.is_alive():
            self.process.kill()
            self.process.join(timeout)
        if getattr(self, "_thread", None):
            self._thread.join(timeout)

    def on_crash(self, listener: Callable[[str], None]) -> None:
        self._crash_listeners.append(listener)

    def _control(self, *message: Any) -> None:
        self._commands.put(("control", *message))

    def post(self, command: Command, *, on_done: Callable[[Any], None] | None = None,
             on_error: Callable[[BaseException], None] | None = None) -> None:
        """Run ``command(sim)`` in the simulation process; ``command`` must be
        picklable (a module-level function or a ``functools.partial`` of one).
        The callbacks run here, on the receiving thread; keep them short."""
        ident = next(self._ids)
        self._callbacks[ident] = (on_done, on_error)
        self._commands.put(("command", ident, command))

    def update_config(self, changes: dict[str, Any], *, on_done: Callable[[Any], None] | None = None,
                      on_error: Callable[[BaseException], None] | None = None) -> None:
        """As :meth:`Runner.update_config`, run by the child's runner (which keeps the waiting changes)."""
        self._runner_call("update_config", on_done, on_error, dict(changes))

    def call(self, command: Command, timeout: float = 10.0) -> Any:
        return wait_for(self.post, command, timeout)

    def subscribe(self, listener: Callable[[Snapshot], None]) -> None:
        self._listeners.append(listener)

    def set_playing(self, playing: bool) -> None:
        self.playing = bool(playing)
        self._control("playing", self.playing)

    def set_speed(self, steps_per_frame: int) -> None:
        self.steps_per_frame = max(1, int(steps_per_frame))
        self._control("speed", self.steps_per_frame)

    def select(self, index: int | None) -> None:
        self.selected = index
        self._control("selected", index)

    @property
    def want_field(self) -> bool:
        return self._want_field

    @want_field.setter
    def want_field(self, value: bool) -> None:
        self._want_field = bool(value)
        self._control("want_field", self._want_field)

    def step_once(self, n: int = 1) -> None:
        self._control("step", int(n))

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
        def used(name: Any) -> None:
            self._program = spec
            if on_done:
                on_done(name)

        self._runner_call("set_program", used, on_error, spec)

    def _runner_call(self, method: str, on_done: Callable | None, on_error: Callable | None, *args: Any) -> None:
        """Call one of the child's Runner methods that report back (reset, set_shape, update_config)."""
        ident = next(self._ids)
        self._callbacks[ident] = (on_done, on_error)
        self._commands.put(("runner_call", ident, method, args))

    # -------------------------------------------------------------- state
    @property
    def latest(self) -> Snapshot:
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

    def frames_per_second(self) -> float:
        if len(self.publish_times) < 2:
            return 0.0
        span = self.publish_times[-1] - self.publish_times[0]
        return (len(self.publish_times) - 1) / span if span > 0 else 0.0


# ------------------------------------------------------------------ child
def _child_main(settings: dict, commands: Any, send: Any) -> None:
    """The simulation process: an ordinary Runner, driven by the queue."""
    runner = Runner(**settings)
    sent = {"series": 0}
    lock = threading.Lock()

    def send_message(message: tuple) -> None:
        with lock:
            try:
                send.send(message)
            except (BrokenPipeError, EOFError, OSError):
                runner._stop.set()  # the parent is gone

    def on_frame(snap: Snapshot) -> None:
        series = runner.series()
        start = sent["series"] if sent["series"] <= len(series) else 0
        sent["series"] = len(series)
        send_message(("frame", snap, series[start:], len(series)))

    def reply(ident: int):
        return (lambda result: send_message(("done", ident, _picklable(result))),
                lambda exc: send_message(("error", ident, _picklable_error(exc))))

    on_frame(runner.latest)
    runner.subscribe(on_frame)
    runner.on_progress(lambda fraction: send_message(("progress", fraction)))
    parent = os.getppid()
    while True:
        try:
            message = commands.get(timeout=1.0)
        except queue.Empty:
            if os.getppid() != parent or runner._stop.is_set():  # orphaned, or the parent stopped listening
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
    elif name == "selected":
        runner.select(args[0])
    elif name == "want_field":
        runner.want_field = args[0]
        runner._wake.set()
    elif name == "step":
        runner.step_once(args[0])
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
