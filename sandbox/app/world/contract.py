"""What the app asks of a simulation runner, written once for both runners.
Callers submit from any thread; futures are settled on the runner's thread.

The app (server, scene, panel, recorder) drives a simulation only through
:class:`SimulationRunner`. Two classes are one:
:class:`~sandbox.app.world.runner.Runner` (the simulation in a thread of this
process: tests, headless recording) and
:class:`~sandbox.app.world.child.ProcessRunner` (in a process of its own: the
live app), of which :class:`~sandbox.app.world.hosted.HostedRunner` (one of
the many worlds of a shared host process: a class's) is one kind. A caller
makes a command (:mod:`sandbox.app.world.orders`, where each command says
what it does) and hands it to :meth:`SimulationRunner.submit`,
the one thing each runner does its own way; it returns a
:class:`concurrent.futures.Future` of the answer. :meth:`SimulationRunner.ask`
adds callbacks that hear the answer on the app's thread;
:func:`wait_for` is the one way to wait for it. Both publish frames through
:class:`FramePublisher`, which owns the listeners, counts the frames and
keeps one broken listener from silencing the others.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, Callable

from sandbox.app.world.orders import Command, Controls, RunnerStopped
from sandbox.app.world.snapshot import Snapshot
from sandbox.model.metrics import Sample

log = logging.getLogger("sandbox.app")

Callback = Callable[[Any], None] | None
#: Where callbacks run: ``deliver(thunk)`` calls ``thunk()`` later, on a thread of the app's choosing.
Deliver = Callable[[Callable[[], None]], None]


class FramePublisher:
    """Listeners of frames, guarded callbacks, and the frame rate they were handed at.

    ``deliver``: when given, every callback but the frame listeners (``on_done``, ``on_error``, the
    progress and crash listeners) is handed to it as a thunk instead of being called on the runner's
    own thread; frames are always handed over at once (the hot path)."""

    def __init__(self, deliver: Deliver | None = None) -> None:
        self._listeners: list[Callable[[Snapshot], None]] = []
        self._hand_over = deliver
        #: What went wrong in a listener or a callback (logged too); the simulation went on.
        self.errors: list[BaseException] = []
        self.frames_published = 0
        self.publish_times: deque = deque(maxlen=120)

    def subscribe(self, listener: Callable[[Snapshot], None]) -> None:
        self._listeners.append(listener)

    def _publish(self, snap: Snapshot) -> None:
        """Hand a frame to every listener (a broken one must not stop the others) and count it."""
        for listener in list(self._listeners):
            self._call_guarded(listener, snap)
        self.frames_published += 1
        self.publish_times.append(time.perf_counter())

    def _deliver(self, callback: Callable[[Any], None], value: Any) -> None:
        """Call a callback with ``value``: through ``deliver`` when the runner was given one, else now."""
        if self._hand_over is None:
            self._call_guarded(callback, value)
        else:
            self._hand_over(lambda: self._call_guarded(callback, value))

    def _call_guarded(self, callback: Callable[[Any], None], value: Any) -> None:
        """Call one listener or callback; one that raises is logged and kept in :attr:`errors`."""
        try:
            callback(value)
        except Exception as exc:  # noqa: BLE001 - the simulation and the other listeners go on
            self.errors.append(exc)
            log.exception("a listener of the simulation failed")

    def frames_per_second(self) -> float:
        if len(self.publish_times) < 2:
            return 0.0
        span = self.publish_times[-1] - self.publish_times[0]
        return (len(self.publish_times) - 1) / span if span > 0 else 0.0


def wait_for(future: Future, timeout: float) -> Any:
    """The answer in ``future`` within ``timeout`` seconds (raises what the command raised): the one way
    to wait for a command. The future itself, not a callback: a callback may be delivered on the very
    thread that waits here (the app's event thread), and must never be waited for there."""
    try:
        return future.result(timeout)
    except FutureTimeout:
        raise TimeoutError("the simulation did not answer in time") from None


class SimulationRunner(FramePublisher):
    """The simulation as the app drives it (see the module docstring).

    Commands run between steps; controls (play, speed, follow, hold, cancel) act at once. :meth:`submit`
    returns the command's future; :meth:`ask` adds ``on_done`` (or ``on_error``), which hear its answer
    (or what it raised) on the runner's thread, or through ``deliver``. A stopped runner fails every
    command it had not carried out with :class:`~sandbox.app.world.orders.RunnerStopped`: nobody
    waits forever.

    A runner provides :meth:`submit`, :meth:`start`, :meth:`stop`, :attr:`latest`, :meth:`series`,
    :meth:`on_progress` and :meth:`on_halt`, and keeps :attr:`controls` (what the settings set; only
    they write it)."""

    controls: Controls
    fps: float

    def __init__(self, controls: Controls, deliver: Deliver | None = None) -> None:
        FramePublisher.__init__(self, deliver)
        self.controls = controls

    # ------------------------------------------------- what each runner does
    def submit(self, command: Command) -> Future:
        """Carry out ``command``: a control at once, any other between steps. Never raises; the future
        says how it went."""
        raise NotImplementedError

    def start(self) -> Any:
        raise NotImplementedError

    def stop(self, timeout: float = 5.0) -> None:
        raise NotImplementedError

    @property
    def latest(self) -> Snapshot:
        raise NotImplementedError

    def series(self) -> list[Sample]:
        """The metric samples of the running world only (a reset starts a new list)."""
        raise NotImplementedError

    def on_progress(self, listener: Callable[[float | None], None]) -> None:
        """``listener(fraction)`` hears how far a build (a new world, a run to the end) has got; None
        when it is over."""
        raise NotImplementedError

    def on_halt(self, listener: Callable[[str], None]) -> None:
        """``listener(why)`` hears that a frame failed (a bug): the world steps no more and its frames say
        paused until the next SetPlaying. The listener owns play: the app pauses, as Pause does."""
        raise NotImplementedError

    # ------------------------------------------------- written once for both
    def ask(self, command: Command, on_done: Callable[[Any], None] | None = None,
            on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Submit ``command``; ``on_done`` hears its answer, ``on_error`` what it raised (without
        ``on_error``, that is kept in :attr:`errors`). Callbacks: keep them short."""
        future = self.submit(command)
        future.add_done_callback(lambda done: self._hear(done, on_done, on_error))
        return future

    def _hear(self, future: Future, on_done: Callable | None, on_error: Callable | None) -> None:
        if future.cancelled():
            return
        exc = future.exception()
        if exc is None:
            if on_done:
                self._deliver(on_done, future.result())
        elif on_error:
            self._deliver(on_error, exc)
        elif not isinstance(exc, RunnerStopped):  # stopping is no error of the command's
            self.errors.append(exc)

    def call(self, command: Command, timeout: float = 10.0) -> Any:
        """Submit ``command`` and wait for its answer (raises what it raised): :func:`wait_for`. Never on
        the thread its callbacks are delivered on."""
        return wait_for(self.submit(command), timeout)

    # ------------------------------------------------------------ read-outs
    @property
    def playing(self) -> bool:
        return self.controls.playing

    @property
    def steps_per_frame(self) -> int:
        return self.controls.steps_per_frame

    @property
    def followed(self) -> tuple[int, ...]:
        """The robots the viewers follow: the snapshots carry their photocells (``Snapshot.followed``)."""
        return self.controls.followed

    @property
    def hold_at(self) -> int | None:
        return self.controls.hold_at

    @property
    def want_field(self) -> bool:
        return self.controls.want_field

    def steps_per_second(self) -> float:
        """The speed the world ran at, as its newest frame measured it (in the simulation's thread:
        read here, it cannot race a reset)."""
        return self.latest.steps_per_second
