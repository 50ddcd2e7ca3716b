"""How much each page may send, applied as its messages are read: one :class:`Flow` per connection.
Runs on viser's event loop, as each connection's messages are read.

viser read each connection's messages as fast as they came, and made every one of them work: two tasks
on the server's event loop and, for a camera or a control, a callback on the app's one event queue,
where the frames wait their turn too. One watcher sending 12,500 cameras a second took another page
from 30 to 4.7 frames a second; a page with the token sending values, to 1-2, with 1.5 GB queued
(issue 54, F). :func:`consume` now reads each connection's messages instead of viser's loop
(:func:`sandbox.app.web.viser_seam.read_messages_through`), within the connection's budgets, each a
token bucket (:class:`Bucket`: a rate a second and a burst):

- **Reading** (:data:`READING`, :data:`WATCH_READING` for a page without the token): every message,
  before it is read off the connection, let alone decoded. Once it is spent, the next message is not
  read until the budget allows it: the page's messages wait in its socket, then in the page, whose
  sends then wait. Not reading costs the server nothing, so however fast a page sends, the server
  does the work of at most this many of its messages a second. A page that presses against this
  budget for :data:`FLOOD_SECONDS` without a pause, which no page of ours does, is disconnected (close
  code 1008, one line in the log).
- **Cameras** (:data:`CAMERA`) and **controls** (:data:`CONTROLS`: values, clicks, keyboard commands,
  clicks and drags in the scene), counted once decoded. Over them a message waits, and only the newest
  of each kind and control does: a newer camera replaces the waiting one, a slider's newer value its
  older one (what viser's client does itself between two sends). It goes when the budget allows. At
  most :data:`MOST_WAITING` wait per page; beyond them a message is dropped.

The rates are from what viser's client sends (1.1.1, ``makeThrottledMessageSender``): its camera at
most every 20 ms (50 a second), a control's value at most every 50 ms (20 a second), clicks in the
scene every 20 ms, drags every 50 ms; a click on a button goes at once, at the pace of a hand. Each
budget has room over that: a page of ours never meets one.

A message that is not one a page sends, or has a field out of place (:mod:`sandbox.app.web.well_formed`),
is refused: a line in the log at most once a second per page (:class:`sandbox.app.web.refusals.RefusalLog`),
and the connection goes on. Everything here runs on the server's event loop; it costs a message a
clock reading and a few additions.
"""

from __future__ import annotations

import asyncio
import logging
import time
import weakref
from collections import Counter
from dataclasses import dataclass
from typing import Any, Callable

from sandbox.app.web.refusals import RefusalLog
from sandbox.app.web.well_formed import Malformed, decode

log = logging.getLogger("sandbox.app.web.rates")


@dataclass(frozen=True)
class Budget:
    """So many messages a second, and so many at once after a pause."""

    rate: float
    burst: float


#: Messages read a second from a page with the token: its camera, its controls and the parts of an upload.
READING = Budget(rate=240.0, burst=480.0)
#: From a page without the token (it sends its camera; a click it tries is refused, but still read).
WATCH_READING = Budget(rate=120.0, burst=240.0)
#: Cameras applied a second (viser's client sends at most 50).
CAMERA = Budget(rate=60.0, burst=60.0)
#: Values, clicks and commands applied a second (viser's client: a value every 50 ms, clicks as they come).
CONTROLS = Budget(rate=30.0, burst=60.0)
#: Seconds a page may press against its reading budget without a pause before it is disconnected.
FLOOD_SECONDS = 5.0
#: Messages that may wait for a budget per page, the newest of each kind and control.
MOST_WAITING = 16
#: Seconds a disconnected flooding page has to answer the close before its socket is cut.
CLOSE_WAIT = 1.0

CAMERA_KIND = "ViewerCameraMessage"
CONTROL_KINDS = ("GuiUpdateMessage", "GuiButtonHoldMessage", "CommandTriggerMessage", "ScenePointerMessage",
                 "SceneNodeClickMessage", "SceneNodeDragMessage", "TransformControlsUpdateMessage",
                 "TransformControlsDragStartMessage", "TransformControlsDragEndMessage")


class Bucket:
    """A token bucket: :meth:`take` one message's token if there is one."""

    __slots__ = ("rate", "burst", "level", "when")

    def __init__(self, budget: Budget, now: float):
        self.rate, self.burst = budget.rate, budget.burst
        self.level, self.when = budget.burst, now

    def _fill(self, now: float) -> None:
        self.level = min(self.burst, self.level + (now - self.when) * self.rate)
        self.when = now

    def take(self, now: float) -> bool:
        self._fill(now)
        if self.level < _WHOLE:
            return False
        self.level -= 1.0
        return True

    def wait(self, now: float) -> float:
        """Seconds until a token is there (0: one is)."""
        self._fill(now)
        return 0.0 if self.level >= _WHOLE else (1.0 - self.level) / self.rate


#: A token, give or take the rounding of the time's arithmetic (which would make a token due now wait ever
#: smaller times).
_WHOLE = 1.0 - 1e-9


class Flow:
    """One connection's budgets, the messages waiting for them, and what became of its messages
    (:attr:`counts`: read, applied, replaced, dropped, malformed)."""

    def __init__(self, controls: bool, now: float | None = None):
        now = time.monotonic() if now is None else now
        self.client_id: int | None = None  # known once viser counts the connection
        self.reading = Bucket(READING if controls else WATCH_READING, now)
        camera, control = Bucket(CAMERA, now), Bucket(CONTROLS, now)
        self.buckets = {CAMERA_KIND: camera, **{kind: control for kind in CONTROL_KINDS}}
        self.waiting: dict[tuple, tuple[Bucket, Any]] = {}  # the newest of each kind and control, in order
        self.pressing_since: float | None = None
        self.counts: Counter = Counter()
        self.refusals = RefusalLog(log)  # (its own: client ids are counted per server)
        self.handle: Callable[[Any], None] | None = None
        self._wake: asyncio.TimerHandle | None = None

    # --------------------------------------------------------------- reading
    def wait_to_read(self, now: float) -> float:
        """Seconds to wait before the next message may be read (0: now). Notes since when the page has
        pressed against its budget: until it pauses long enough for the budget to fill half again."""
        delay = self.reading.wait(now)
        if delay == 0.0 and self.reading.level >= self.reading.burst / 2:
            self.pressing_since = None
        elif delay > 0.0 and self.pressing_since is None:
            self.pressing_since = now
        return delay

    def floods(self, now: float) -> bool:
        """Whether the page has pressed against its reading budget for :data:`FLOOD_SECONDS`."""
        return self.pressing_since is not None and now - self.pressing_since >= FLOOD_SECONDS

    def read(self, raw: Any, now: float) -> None:
        """A message read off the connection: decoded and applied, or waiting, or refused."""
        self.reading.take(now)
        self.counts["read"] += 1
        try:
            message = decode(raw)
        except Malformed as why:
            self.counts["malformed"] += 1
            self.refusals.refused(self.client_id, str(why))
            return
        self.offer(message, now)

    # -------------------------------------------------------------- applying
    def offer(self, message: Any, now: float) -> None:
        """Apply ``message`` now if its budget allows and none of its kind waits; else let it wait."""
        kind = type(message).__name__
        bucket = self.buckets.get(kind)
        if bucket is None or (not self._any_waiting_for(bucket) and bucket.take(now)):
            self._apply(message)
            return
        key = (kind, getattr(message, "uuid", None), getattr(message, "name", None),
               getattr(message, "phase", None))
        if key in self.waiting:
            self.counts["replaced"] += 1
        elif len(self.waiting) >= MOST_WAITING:
            self.counts["dropped"] += 1
            return
        self.waiting[key] = (bucket, message)
        self._wake_in(bucket.wait(now))

    def _any_waiting_for(self, bucket: Bucket) -> bool:
        return any(waiting is bucket for waiting, _ in self.waiting.values())

    def _apply(self, message: Any) -> None:
        self.counts["applied"] += 1
        if self.handle is not None:
            self.handle(message)

    def _wake_in(self, seconds: float) -> None:
        if self._wake is None:
            self._wake = asyncio.get_running_loop().call_later(seconds, self._release)

    def _release(self) -> None:
        """The waiting messages whose budget allows them now go, in order."""
        self._wake, now = None, time.monotonic()
        for key, (bucket, message) in list(self.waiting.items()):
            if bucket.take(now):
                del self.waiting[key]
                self._apply(message)
        if self.waiting:
            self._wake_in(min(bucket.wait(now) for bucket, _ in self.waiting.values()))

    def close(self) -> None:
        """The connection ended: nothing waiting goes."""
        if self._wake is not None:
            self._wake.cancel()
            self._wake = None
        self.waiting.clear()
        self.handle = None
        self.refusals.forget(self.client_id)


# -------------------------------------------------------------- connections
_flows: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # raw websockets connection -> Flow


def track(connection: Any, controls: bool) -> Flow:
    """The budgets of a connection the gate let in (``controls``: with the token)."""
    flow = _flows[connection] = Flow(controls)
    return flow


def flow_of(connection: Any) -> Flow | None:
    return _flows.get(connection)


async def consume(connection: Any, handle: Callable[[Any], None], message_class: Any) -> None:
    """Read ``connection``'s messages within its budgets and ``handle`` those that pass, until it closes
    (viser's reading loop, :func:`sandbox.app.web.viser_seam.read_messages_through`). ``message_class`` is
    viser's; the page's messages are decoded by :func:`sandbox.app.web.well_formed.decode`."""
    flow = _flows.get(connection)
    if flow is None:  # not let in by a gate (it refuses such a connection at once): a watcher's budget
        flow = track(connection, controls=False)
    flow.handle = handle
    try:
        while True:
            now = time.monotonic()
            delay = flow.wait_to_read(now)
            if flow.floods(now):
                await _disconnect(connection, flow)
                break
            if delay > 0:
                await asyncio.sleep(delay)
            flow.read(await connection.recv(), time.monotonic())
        while True:  # disconnected: what it sent before is dropped, until websockets raises ConnectionClosed
            await connection.recv()
    finally:
        flow.close()


async def _disconnect(connection: Any, flow: Flow) -> None:
    budget = flow.reading.rate
    log.warning("closed connection %s: it sent more than %.0f messages a second for %.0f s", flow.client_id,
                budget, FLOOD_SECONDS)
    connection.close_timeout = CLOSE_WAIT
    await connection.close(1008, f"more than {budget:.0f} messages a second")
