"""A world host: ONE child process that holds many worlds and steps them in turn, each at its own pace.
Its scheduler thread steps the worlds; a builder thread runs one long build at a time, in slices
(sandbox.app.world.baton); the app's side is sandbox.app.world.pool.

Each world is an ordinary :class:`~sandbox.app.world.runner.Runner` that starts no thread of its own
(:class:`HostedWorld`): the host's scheduler runs its frames (``Runner._frame_on_schedule``, the same
frame a started runner's loop runs: its commands, its frame's steps at its fps x steps_per_frame, a
snapshot) whenever the world whose frame is due soonest is due. The host speaks the child's protocol
(sandbox.app.world.child), each message tagged with the world's key: ``(key, Order)`` in, ``(key,
visit, Frame)``, ``Done``, ``Failed``, ``Progress``, ``Building``, ``Halted``, ``LastWords`` out; and a few of
its own (below): a world is opened (:class:`Open`, built or :class:`Found` again by its key), left
(:class:`Leave`: the proxy stopped; the world pauses), watched or not (:class:`Watch`), and freed (:class:`Freed`) after
``free_after`` seconds left alone.

- A world steps and sends frames only while a proxy is attached, started and watching: a world nobody
  watches pauses and costs nothing but its memory.
- Fairness: a :class:`~sandbox.app.world.orders.Build` (a reset, a run to the end) does not run in the
  scheduler's turn. It joins the host's queue of builds; the world's later commands wait behind it (the
  world goes on meanwhile); each waiting build hears its place (:class:`Queued`). The build under way
  runs in the time no frame is due, and at least :data:`MIN_SLICE` every :data:`BUILD_EVERY` when
  frames are always due, so the other worlds keep their pace and no build starves.
- A frame that raises halts its world only (Runner: ``Halted``); a command that raises fails its own
  future. A host that dies takes its worlds with it: each proxy restarts its world from the settings
  that stand, as a process runner does.
"""

from __future__ import annotations

import dataclasses
import logging
import multiprocessing
import os
import queue
import signal
import threading
import time
from collections import deque
from concurrent.futures import Future
from typing import Any, NamedTuple

from sandbox.app.world import faults
from sandbox.app.world.baton import Baton
from sandbox.app.world.child import (STUCK_EXIT, Building, Done, Failed, FrameSamples, Halted, LastWords, Order,
                                     Progress, _not_built, _picklable, _picklable_error)
from sandbox.app.world.orders import Build, Controls
from sandbox.app.world.runner import Runner
from sandbox.model import watchdog

#: A world nobody has watched for this long (s) is freed; a reopen before finds it again.
FREE_AFTER = 600.0
#: With frames always due (a host that cannot keep up), a build still runs MIN_SLICE seconds every
#: BUILD_EVERY seconds: it is slowed, never stopped.
MIN_SLICE = 0.005
BUILD_EVERY = 0.025
#: The longest slice a build is given at a time (s): the host reads its orders (a cancel) between slices.
MAX_SLICE = 0.05
#: Steps a build takes between two turning points: about 1-10 ms of the paper's world.
BUILD_CHUNK = 10
#: How often (s) the host frees the worlds left too long and looks whether the app is still there.
HOUSEKEEPING_EVERY = 1.0

log = logging.getLogger("sandbox.app.world.host")


# ------------------------------------------------------------------ its own messages
class Open(NamedTuple):
    """To the host: attach a proxy to the world (the key it is sent with), built from ``settings`` (a
    :class:`Runner`'s keywords) unless the host holds it still. ``visit``: which proxy (a later one
    takes the world over; an earlier one's leaving then leaves it alone)."""

    settings: dict
    visit: int


class Leave(NamedTuple):
    """To the host: the proxy of ``visit`` stopped: the world pauses, and is kept free_after seconds (or
    freed at once with ``free``: nobody will come back for it)."""

    visit: int
    free: bool = False


class Watch(NamedTuple):
    """To the host: someone watches the world (it steps and sends frames) or nobody does (it pauses)."""

    on: bool


class Queued(NamedTuple):
    """From the host: the world's build waits in the host's queue, ``place``-th (the build under way is
    the first); None: its turn has come (its progress follows)."""

    place: int | None


class Found(NamedTuple):
    """From the host, before the first frame of a world found again: the controls it ran with (playing,
    speed, ...), which the new proxy takes rather than its own."""

    controls: Controls


class Closed(NamedTuple):
    """From the host: the world is gone (it could not be built: its LastWords said why); exit code 1."""

    why: str


class Freed(NamedTuple):
    """From the host: the world was left alone for ``free_after`` seconds and is freed."""


# ------------------------------------------------------------------ one world
class HostedWorld(Runner):
    """A Runner that a host's scheduler steps, with no thread of its own. Its frames, commands and
    snapshots are the Runner's own; the host adds where it stands (attached, started, watched, busy with
    a build) and the turning points where a build gives the host back."""

    def __init__(self, key: str, baton: Baton, settings: dict):
        settings = dict(settings)
        settings.pop("faults", None)  # the host's, installed once for all its worlds
        super().__init__(**settings)
        self.key = key
        self._baton = baton
        self.attached = False  # a proxy is attached
        self.started = False  # and has started it (Start)
        self.watched = True  # and someone watches (Watch)
        self.busy = False  # its build runs: the scheduler leaves it alone
        self.blocked = False  # a build of its own waits or runs: later commands wait behind it
        self.held: deque = deque()  # those commands (Orders), in order
        self.left_at: float | None = None  # when its proxy left (for freeing)
        self.visit = -1  # the proxy attached last
        self.woken = False  # a command came: carry it out before the next frame
        self.due = time.perf_counter()
        self.samples = FrameSamples()
        self.sent = -1  # the frame number last sent

    @property
    def stepping(self) -> bool:
        """Whether it runs frames: someone watches, and no build of its own runs."""
        return self.attached and self.started and self.watched and not self.busy

    # the Runner's threads are the host's
    def start(self) -> "HostedWorld":
        self.started = True
        self.due = time.perf_counter()
        return self

    def wake(self) -> None:
        self.woken = True

    # turning points of a build (nothing on the scheduler's own frames)
    def step(self, n: int | None = None, deadline: float | None = None) -> None:
        if n is None or not self._baton.on_builder():
            super().step(n, deadline)
            return
        while n > 0:
            chunk = min(n, BUILD_CHUNK)
            super().step(chunk)
            n -= chunk
            self._baton.turning_point()

    def report_progress(self, fraction: float | None) -> None:
        super().report_progress(fraction)
        self._baton.turning_point()

    # what the host uses of the Runner's loop (the same pieces a started runner's loop runs)
    def frame(self) -> None:
        self.due = self._frame_on_schedule(self.due, 1.0 / self.fps)

    def between_frames(self) -> None:
        self.woken = False
        self.due = self._commands_between_frames(self.due)

    def expect(self, build: int) -> None:
        self._expect(build)

    def run_waiting_commands(self) -> None:
        self._run_commands()

    def carry_out(self, command: Any, future: Future) -> None:
        self._carry_out(command, future)


# ------------------------------------------------------------------ the host
class Host:
    """The scheduler of one host process (its main thread), and the builds' queue."""

    def __init__(self, send: Any, free_after: float = FREE_AFTER):
        self._pipe = send
        # shared by the threads that send on the pipe: the scheduler thread and the builder thread
        self._send_lock = threading.Lock()
        self.free_after = float(free_after)
        self.worlds: dict[str, HostedWorld] = {}
        self.baton = Baton()
        self.builds: deque = deque()  # (world, Order) waiting their turn
        self.under_way: tuple[HostedWorld, Order] | None = None
        self._last_slice = time.perf_counter()
        self._places: dict[int, int] = {}  # build id -> the place last said
        self.ended = False

    # ------------------------------------------------------------ sending
    def send(self, key: str | None, message: Any, visit: int | None = None) -> None:
        """Send ``(key, visit, message)``: the visit is the proxy's the world has now (or ``visit``), so
        that a message sent to a proxy that has left never reaches the one that took the world over."""
        if visit is None and key is not None and (world := self.worlds.get(key)) is not None:
            visit = world.visit
        with self._send_lock:
            try:
                self._pipe.send((key, visit, message))
            except (BrokenPipeError, EOFError, OSError):
                self.ended = True  # the app is gone

    def send_frame(self, world: HostedWorld, force: bool = False) -> None:
        """The world's newest snapshot, if it is new and someone watches (or ``force``: a proxy's first)."""
        snap = world.latest
        if force or (snap.frame != world.sent and world.attached and world.watched):
            world.sent = snap.frame
            self.send(world.key, world.samples.frame(world, snap))

    def answer(self, key: str, ident: int, future: Future) -> None:
        exc = future.exception()
        if exc is None:
            self.send(key, Done(ident, _picklable(future.result())))
        else:
            self.send(key, Failed(ident, _picklable_error(exc)))

    # ------------------------------------------------------------ orders
    def take(self, key: str | None, message: Any) -> None:
        """One message from the app."""
        if key is None:  # the host itself ends
            self.ended = True
        elif isinstance(message, Open):
            self.open(key, message.settings, message.visit)
        elif (world := self.worlds.get(key)) is None:
            return  # a world freed, or never built: its proxy hears nothing more
        elif isinstance(message, Leave):
            if message.visit == world.visit:
                self.leave(world, message.free)
        elif isinstance(message, Watch):
            world.watched = bool(message.on)
            world.due = time.perf_counter()
        else:
            self.order(world, message)

    def open(self, key: str, settings: dict, visit: int) -> None:
        """Attach a proxy to the world ``key``: the one the host holds (left less than free_after ago),
        else one built from ``settings``. The proxy's first frame follows at once."""
        world = self.worlds.get(key)
        if world is not None:
            self.send(key, Found(dataclasses.replace(world.controls)), visit)
        else:
            try:
                world = self._build(key, settings)
            except Exception as exc:  # noqa: BLE001 - this world cannot be built; the others go on
                self.send(key, LastWords(_not_built(exc)), visit)
                self.send(key, Closed(_not_built(exc)), visit)
                return
            self.worlds[key] = world
        world.attached, world.started, world.watched, world.left_at = True, False, True, None
        world.visit = visit
        world.samples = FrameSamples()  # the new proxy has the whole series
        self.send_frame(world, force=True)

    def _build(self, key: str, settings: dict) -> HostedWorld:
        world = HostedWorld(key, self.baton, settings)
        world.on_progress(lambda fraction: self.send(key, Progress(fraction)))
        world.on_build(lambda built: self.send(key, Building(built)))
        world.on_halt(lambda why: self.send(key, Halted(why)))
        return world

    def leave(self, world: HostedWorld, free: bool = False) -> None:
        """Its proxy stopped: the world pauses and is kept free_after seconds (``free``: freed at the next
        housekeeping, once no build of its own waits or runs)."""
        world.attached = world.started = False
        world.left_at = -float("inf") if free else time.monotonic()

    def order(self, world: HostedWorld, order: Order) -> None:
        """A command for ``world``: a control at once; a build to the queue; any other to the world,
        carried out before its next frame; all in order behind a build of its own that waits or runs."""
        command = order.command
        if command.at_once:
            world.submit(command)
        elif world.blocked:
            world.held.append(order)
        elif isinstance(command, Build):
            world.expect(command.build)  # a cancel counts from now on, while it waits its turn too
            world.blocked = True
            self.builds.append((world, order))
            self._tell_places()
        else:
            future = world.submit(command)
            if order.ident is not None:
                future.add_done_callback(lambda done, ident=order.ident: self.answer(world.key, ident, done))
            world.woken = True

    # ------------------------------------------------------------ builds
    def _tell_places(self) -> None:
        """Each waiting build's place (the build under way is the first), when it changed."""
        ahead = 1 if self.under_way is not None else 0
        for index, (world, order) in enumerate(self.builds):
            place = ahead + index + 1
            build = order.command.build
            if place >= 2 and self._places.get(build) != place:
                self._places[build] = place
                self.send(world.key, Queued(place))

    def _next_build(self) -> None:
        """Start the first waiting build on the builder thread (it runs in the slices it is given)."""
        world, order = self.under_way = self.builds.popleft()
        if self._places.pop(order.command.build, None) is not None:
            self.send(world.key, Queued(None))
        self._tell_places()
        world.busy = True

        def build() -> None:
            world.run_waiting_commands()  # what came before it, first
            future: Future = Future()
            future.set_running_or_notify_cancel()
            world.carry_out(order.command, future)
            if order.ident is not None:
                self.answer(world.key, order.ident, future)

        self.baton.begin(build)

    def _build_over(self) -> None:
        """The build under way is over: its world steps again from now (the build's time is not owed),
        shows where it is, and takes the commands that waited behind it."""
        world, _ = self.under_way
        self.under_way = None
        world.busy = world.blocked = False
        world.due = time.perf_counter()
        world.snapshot()
        self.send_frame(world)
        while world.held and not world.blocked:
            self.order(world, world.held.popleft())

    def give_slice(self, next_due: float | None) -> None:
        """Let the build under way run until the next frame is due (at least MIN_SLICE, at most MAX_SLICE)."""
        now = time.perf_counter()
        until = now + MAX_SLICE if next_due is None else min(max(next_due, now + MIN_SLICE), now + MAX_SLICE)
        self._last_slice = now
        if self.baton.give(until):
            self._build_over()
        elif self.under_way is not None:
            self.send_frame(self.under_way[0])  # a run to the end shows where it starts

    # ------------------------------------------------------------ the loop
    def next_world(self) -> HostedWorld | None:
        """The stepping world whose frame is due soonest."""
        stepping = [world for world in self.worlds.values() if world.stepping]
        return min(stepping, key=lambda world: world.due) if stepping else None

    def run(self, orders: Any) -> None:
        app = multiprocessing.parent_process()
        housekeeping = time.monotonic()
        while not self.ended:
            self._take_waiting(orders)
            if self.ended:
                break
            self._between_frames()
            if self.under_way is None and self.builds:
                self._next_build()
            now = time.perf_counter()
            world = self.next_world()
            building = self.under_way is not None
            if world is not None and world.due <= now and not (building and now - self._last_slice > BUILD_EVERY):
                world.frame()
                self.send_frame(world)
            elif building:
                self.give_slice(None if world is None else world.due)
            else:
                self._wait_for_orders(orders, 0.5 if world is None else world.due - now)
            if time.monotonic() - housekeeping >= HOUSEKEEPING_EVERY:
                housekeeping = time.monotonic()
                self._free_left_alone()
                if app is not None and not app.is_alive():
                    break

    def _take_waiting(self, orders: Any) -> None:
        while not self.ended:
            try:
                key, message = orders.get_nowait()
            except queue.Empty:
                return
            self.take(key, message)

    def _wait_for_orders(self, orders: Any, timeout: float) -> None:
        try:
            key, message = orders.get(timeout=max(timeout, 0.0))
        except queue.Empty:
            return
        self.take(key, message)

    def _between_frames(self) -> None:
        """Carry out the commands that came (a started runner's loop wakes for them)."""
        for world in list(self.worlds.values()):
            if world.woken and world.attached and world.started and not world.busy:
                world.between_frames()
                self.send_frame(world)

    def _free_left_alone(self) -> None:
        now = time.monotonic()
        for key, world in list(self.worlds.items()):
            if world.left_at is not None and now - world.left_at >= self.free_after and not world.busy \
                    and not world.blocked:
                del self.worlds[key]
                self.send(key, Freed())


def host_main(settings: dict, orders: Any, send: Any) -> None:
    """The host process: its scheduler, driven by the queue of ``(key, message)``; ``(None, None)`` ends
    it. ``settings``: ``free_after`` and the tests' ``faults``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is for the app, which stops the host
    faults.install(settings.get("faults"))
    host = Host(send, free_after=settings.get("free_after", FREE_AFTER))

    def stuck(why: str) -> None:  # a light program would not stop: every world of the host restarts
        host.send(None, LastWords(f"{why}; the app restarts the simulation with the paper's controller"))
        os._exit(STUCK_EXIT)

    watchdog.on_stuck = stuck
    try:
        host.run(orders)
    finally:
        send.close()
