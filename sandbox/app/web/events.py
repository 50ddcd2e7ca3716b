"""The app's one event queue: every change of the app's state runs here, one at a time.
Its thread, ``phototaxis-events``, runs every event; any thread may post.

viser's callbacks (controls, clicks on the floor, cameras, pages arriving and
leaving), the runner's answers and frames, and the app's timers are all
*events*: functions put on one queue and run, in order, by one thread. So
two of them never run at once, none runs before the app is built (the queue
is served only from :meth:`EventQueue.open`), and no state the app owns
needs a lock. See docs/code.md, "Threads".

An event must not wait for another event (it would wait for itself): work
that blocks (a process starting, a trial run) goes to a thread of its own,
which puts its result back on the queue with :meth:`EventQueue.post`.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import queue
import threading
import time
from collections import deque
from concurrent.futures import Future
from typing import Any, Callable, Hashable

log = logging.getLogger("sandbox.app")


class QueueStopped(RuntimeError):
    """The event queue stopped before this event ran."""


class Timer:
    """An event due later (:meth:`EventQueue.after`, :meth:`EventQueue.every`); ``cancel()`` drops it."""

    __slots__ = ("due", "period", "fn", "args", "cancelled")

    def __init__(self, due: float, period: float | None, fn: Callable, args: tuple):
        self.due, self.period, self.fn, self.args = due, period, fn, args
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


_STOP = object()


class EventQueue:
    """One queue of events and the one thread that runs them.

    ``post`` (no answer), ``submit`` (a :class:`~concurrent.futures.Future`), ``post_latest`` (only
    the newest of a kind waits: frames), ``after`` and ``every`` (timers, run on the same thread).
    Any thread may call them. An event that raises is logged and kept in :attr:`errors`; the
    others go on."""

    def __init__(self, name: str = "phototaxis-events"):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._timers: list[tuple[float, int, Timer]] = []  # a heap, touched on the event thread only
        self._order = itertools.count()
        self._latest: dict[Hashable, tuple[Callable, tuple]] = {}
        # Shared by the thread that posts each new frame (a runner's receiver, or its publisher thread in
        # process) and the event thread, which takes it (_run_latest): _latest.
        self._latest_lock = threading.Lock()
        self._thread = threading.Thread(target=self._serve, name=name, daemon=True)
        self._stopped = False
        # Shared by every thread that puts an event (the main thread, viser's event loop, the event thread,
        # a runner's receiver or its threads in process, workers) and stop(), so that none slips in after
        # the queue stopped: _stopped.
        self._put_lock = threading.Lock()
        #: What went wrong in events (logged too); the queue went on.
        self.errors: deque = deque(maxlen=100)

    # ------------------------------------------------------------ putting events
    def submit(self, fn: Callable, *args: Any) -> Future:
        """Run ``fn(*args)`` on the event thread; the future holds what it returns or raises. (This
        is also what viser's callbacks are handed to: :func:`sandbox.app.web.viser_seam.route_callbacks`.)"""
        future: Future = Future()
        if not self._put((fn, args, future)):
            future.set_exception(QueueStopped("the app is stopping"))
        return future

    def post(self, fn: Callable, *args: Any) -> None:
        """Run ``fn(*args)`` on the event thread; nobody waits for it."""
        self._put((fn, args, None))

    def _put(self, item: tuple) -> bool:
        """Queue ``item`` unless the queue stopped (under the lock, so none slips in after the
        waiting ones were failed)."""
        with self._put_lock:
            if self._stopped:
                return False
            self._queue.put(item)
            return True

    def post_latest(self, key: Hashable, fn: Callable, *args: Any) -> None:
        """Run ``fn(*args)`` on the event thread, unless a newer event of the same ``key`` comes first:
        then only the newer runs (a frame not yet drawn when the next one comes is not drawn)."""
        with self._latest_lock:
            waiting = key in self._latest
            self._latest[key] = (fn, args)
        if not waiting:
            self.post(self._run_latest, key)

    def after(self, seconds: float, fn: Callable, *args: Any) -> Timer:
        """Run ``fn(*args)`` on the event thread in ``seconds`` (unless cancelled)."""
        timer = Timer(time.monotonic() + max(0.0, seconds), None, fn, args)
        self.post(self._add_timer, timer)
        return timer

    def every(self, seconds: float, fn: Callable, *args: Any) -> Timer:
        """Run ``fn(*args)`` on the event thread every ``seconds``, the first time in ``seconds``."""
        if seconds <= 0:
            raise ValueError("a period must be positive")
        timer = Timer(time.monotonic() + seconds, seconds, fn, args)
        self.post(self._add_timer, timer)
        return timer

    def call(self, fn: Callable, *args: Any, timeout: float = 10.0) -> Any:
        """Run ``fn(*args)`` on the event thread and return what it returns (inline when called from
        an event). For tests and start-up: an event must not wait on the queue."""
        if self.on_event_thread():
            return fn(*args)
        return self.submit(fn, *args).result(timeout)

    def on_event_thread(self) -> bool:
        return threading.current_thread() is self._thread

    # ------------------------------------------------------------ life
    @property
    def stopping(self) -> bool:
        return self._stopped

    @property
    def serving(self) -> bool:
        return self._thread.is_alive()

    def open(self) -> "EventQueue":
        """Start running events (those put before wait until now)."""
        if not self._thread.is_alive() and not self._stopped:
            self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Run no more events: the one running finishes; those waiting fail with :class:`QueueStopped`."""
        with self._put_lock:
            if self._stopped:
                return
            self._stopped = True
            self._queue.put(_STOP)
        if self._thread.is_alive() and not self.on_event_thread():
            self._thread.join(timeout)
        self._fail_waiting()

    # ------------------------------------------------------------ the event thread
    def _serve(self) -> None:
        while True:
            try:
                item = self._queue.get(timeout=self._until_next_timer())
            except queue.Empty:
                item = None
            if item is _STOP or self._stopped:  # what still waits is failed by stop()
                if item not in (None, _STOP):
                    self._fail(item)
                return
            if item is not None:
                self._run(*item)
            self._run_due_timers()

    def _run(self, fn: Callable, args: tuple, future: Future | None) -> None:
        if future is not None and not future.set_running_or_notify_cancel():
            return
        try:
            result = fn(*args)
        except Exception as exc:  # noqa: BLE001 - one broken event must not stop the app's others
            self.errors.append(exc)
            log.exception("an event of the app failed: %r", fn)
            if future is not None:
                future.set_exception(exc)
        else:
            if future is not None:
                future.set_result(result)

    def _run_latest(self, key: Hashable) -> None:
        with self._latest_lock:
            fn, args = self._latest.pop(key)
        self._run(fn, args, None)

    def _add_timer(self, timer: Timer) -> None:
        heapq.heappush(self._timers, (timer.due, next(self._order), timer))

    def _until_next_timer(self) -> float | None:
        while self._timers and self._timers[0][2].cancelled:
            heapq.heappop(self._timers)
        if not self._timers:
            return None
        return max(0.0, self._timers[0][0] - time.monotonic())

    def _run_due_timers(self) -> None:
        now = time.monotonic()
        while self._timers and self._timers[0][0] <= now:
            _, _, timer = heapq.heappop(self._timers)
            if timer.cancelled:
                continue
            self._run(timer.fn, timer.args, None)
            if timer.period is not None and not timer.cancelled:
                # The next one a period after this one was due (or from now, if far behind): no burst.
                timer.due = max(timer.due + timer.period, now)
                self._add_timer(timer)

    def _fail_waiting(self) -> None:
        while True:
            try:
                item = self._queue.get_nowait()
            except queue.Empty:
                return
            if item is not _STOP:
                self._fail(item)

    @staticmethod
    def _fail(item: tuple) -> None:
        future = item[2]
        if future is not None and not future.done():
            future.set_exception(QueueStopped("the app stopped before this ran"))
