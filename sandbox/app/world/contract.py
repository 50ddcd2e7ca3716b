"""What the app asks of a simulation runner, written once for both runners.

The app (server, scene, panel, recorder) drives a simulation only through
:class:`SimulationRunner`. Two classes are one:
:class:`~sandbox.app.world.runner.Runner` (the simulation in a thread of this
process: tests, headless recording) and
:class:`~sandbox.app.world.child.ProcessRunner` (in a process of its own: the
live app). Each method the app calls builds a command
(:mod:`sandbox.app.world.orders`) and hands it to :meth:`SimulationRunner.submit`,
the one thing each runner does its own way; it returns a
:class:`concurrent.futures.Future` of the answer, and the ``on_done`` /
``on_error`` callbacks hear it too. Both publish frames through
:class:`FramePublisher`, which owns the listeners, counts the frames and
keeps one broken listener from silencing the others.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, Callable, Iterable

from sandbox.app.world.orders import (Apply, CancelBuild, Command, Controls, Follow, Hold, Reset, RunnerStopped,
                                  RunTo, SetLamp, SetOutline, SetPlaying, SetProgram, SetShape, SetSpeed,
                                  ShowEvery, SkipAhead, StepOnce, UpdateConfig, WantField, WorldSpec, DesignOf,
                                  PlayDesign)
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


def answer(future: Future, timeout: float) -> Any:
    """The future's result within ``timeout`` seconds (raises its exception)."""
    try:
        return future.result(timeout)
    except FutureTimeout:
        raise TimeoutError("the simulation did not answer in time") from None


class SimulationRunner(FramePublisher):
    """The simulation as the app drives it (see the module docstring).

    Commands run between steps; controls (play, speed, follow, hold, cancel) act at once. Each method
    returns the command's future; ``on_done`` (or ``on_error``) hears its answer (or what it raised) on
    the runner's thread, or through ``deliver``. A stopped runner fails every command it had not
    carried out with :class:`~sandbox.app.world.orders.RunnerStopped`: nobody waits forever.

    A runner provides :meth:`submit`, :meth:`start`, :meth:`stop`, :attr:`latest`, :meth:`series`
    and :meth:`on_progress`, and keeps :attr:`controls` (what the controls set)."""

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
        """``listener(fraction)`` hears how far building a world has got; None when it is over."""
        raise NotImplementedError

    # ------------------------------------------------- written once for both
    def ask(self, command: Command, on_done: Callable[[Any], None] | None = None,
            on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Submit ``command``; ``on_done`` hears its answer, ``on_error`` what it raised (without
        ``on_error``, that is kept in :attr:`errors`)."""
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

    def post(self, command: Callable, *, on_done: Callable[[Any], None] | None = None,
             on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Run ``command(sim)`` between steps (for a process runner, ``command`` must pickle: a
        module-level function or a ``functools.partial`` of one). Callbacks: keep them short."""
        return self.ask(Apply(command), on_done, on_error)

    def call(self, command: Callable, timeout: float = 10.0) -> Any:
        """Post a command and wait for its result (raises its exception)."""
        return answer(self.submit(Apply(command)), timeout)

    def reset(self, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Rebuild the world with the waiting changes; ``seed`` None keeps the current seed. ``on_done``
        gets the new world's key (its frames' ``world_key``: a frame of an older world may still come
        after the answer, from a reset asked for earlier). Building reports to the :meth:`on_progress`
        listeners and stops at :meth:`cancel_build` (BuildCancelled; the old world goes on)."""
        return self.ask(Reset(seed), on_done, on_error)

    def update_config(self, changes: dict[str, Any], *, on_done: Callable[[Any], None] | None = None,
                      on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Change parameters: the live ones at once, the others at the next :meth:`reset`. ``on_done``
        receives (names waiting for a reset, the settings with them)."""
        return self.ask(UpdateConfig(dict(changes)), on_done, on_error)

    def set_shape(self, vertices: Any, name: str, *, on_done: Callable[[Any], None] | None = None,
                  on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Change the goal; ``on_done`` gets the notes about its fit, ``on_error`` a refusal."""
        return self.ask(SetShape(vertices, name), on_done, on_error)

    def set_program(self, spec: str | None, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Light the floor with a program loaded from ``path.py:Class`` (None: the paper's controller
        again), keeping the world. A program that cannot be loaded or started is refused and the
        running one stays."""
        return self.ask(SetProgram(spec), on_done, on_error)

    def set_outline(self, outline: str, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Choose the outline family; ``on_done`` gets the notes about the goal, ``on_error`` a refusal."""
        return self.ask(SetOutline(outline), on_done, on_error)

    def world_spec(self, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> Future:
        """(config, seed, goal vertices as given or None) of the running world: what builds it again
        elsewhere (a challenge's reference run)."""
        return self.ask(WorldSpec(), on_done, on_error)

    def set_lamp(self, centre: tuple[float, float] | None, radius: float | None = None, mode: str = "lamp", *,
                 on_done: Callable[[Any], None] | None = None,
                 on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Be the light: a click at ``centre`` moves the lamp there (the lights within ``radius`` metres
        on, the others off), or paints or erases the lights there (``mode``: see
        :mod:`sandbox.model.lamp`), keeping the world; None gives the lights back to the paper's
        controller."""
        return self.ask(SetLamp(centre, radius, mode), on_done, on_error)

    def step_once(self, n: int = 1) -> Future:
        """Advance ``n`` steps now (used while paused)."""
        return self.ask(StepOnce(int(n)))

    def run_to(self, step: int) -> Future:
        """Step until the world's step count is ``step`` (nothing if it is there or past): two paused
        worlds in compare mode end on the same step."""
        return self.ask(RunTo(int(step)))

    def set_playing(self, playing: bool) -> Future:
        return self.submit(SetPlaying(bool(playing)))

    def set_speed(self, steps_per_frame: int) -> Future:
        return self.submit(SetSpeed(int(steps_per_frame)))

    def follow(self, indices: Iterable[int]) -> Future:
        """Carry these robots' photocells, commands and charge in the snapshots (the inspectors' robots)."""
        return self.submit(Follow(tuple(int(i) for i in indices)))

    def show_every(self, frames: int) -> Future:
        """A snapshot at every ``frames``-th frame only (1: every frame); the speed is unchanged."""
        return self.submit(ShowEvery(max(1, int(frames))))

    def hold(self, step: int | None) -> Future:
        """Playing, step no further than ``step`` (None: no limit)."""
        return self.submit(Hold(None if step is None else int(step)))

    def skip_ahead(self, step: int, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> Future:
        """Run to ``step`` without frames, as fast as headless (*Run to the end*); the progress listeners
        hear the fraction done, :meth:`cancel_build` stops it. ``on_done`` gets an :class:`Arrival`."""
        return self.ask(SkipAhead(int(step)), on_done, on_error)

    def design(self, *, on_done: Callable[[Any], None] | None = None,
               on_error: Callable[[BaseException], None] | None = None) -> Future:
        """The running world's design (sandbox.model.design.Design): goal, settings, seed, light program."""
        return self.ask(DesignOf(), on_done, on_error)

    def play_design(self, design: Any, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> Future:
        """A new world from ``design``, lit by its recorded light program (``serve --design``)."""
        return self.ask(PlayDesign(design), on_done, on_error)

    def cancel_build(self) -> Future:
        """Stop a world being built by :meth:`reset`, or a :meth:`skip_ahead` (safe from any thread)."""
        return self.submit(CancelBuild())

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

    @want_field.setter
    def want_field(self, on: bool) -> None:
        self.submit(WantField(bool(on)))

    def steps_per_second(self) -> float:
        """The speed the world ran at, as its newest frame measured it (in the simulation's thread:
        read here, it cannot race a reset)."""
        return self.latest.steps_per_second
