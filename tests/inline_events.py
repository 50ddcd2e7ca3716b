"""The app's event queue in tests.

:class:`InlineEvents` stands in for it: every event runs at once, on the thread that posts it; timers
wait until the test says time has passed (:meth:`InlineEvents.pass_time`). The panel and the view take
the app's event queue (:mod:`sandbox.app.web.events`) as the only way in; a test that builds one of
them without a server passes this instead. It has the queue's methods and nothing else: a folder that
works with it works with the queue, in the order it posts.

:class:`OnEvents` is the other way round: a live app's folder, driven by a test on the app's own event
thread, which owns it, as a page's clicks are."""

from __future__ import annotations

import functools
import inspect
from concurrent.futures import Future
from typing import Any, Callable, Hashable

from sandbox.app.web.events import Timer


class InlineEvents:
    """:class:`~sandbox.app.web.events.EventQueue`'s methods, run inline (see the module's docstring).
    Its clock (:attr:`now`, seconds) moves only when the test says: :meth:`pass_time`."""

    def __init__(self):
        self.now = 0.0
        #: The timers set and not yet run (their ``due`` on :attr:`now`'s clock), in the order set.
        self.timers: list[Timer] = []

    def post(self, fn: Callable, *args: Any) -> None:
        fn(*args)

    def post_latest(self, key: Hashable, fn: Callable, *args: Any) -> None:
        fn(*args)

    def submit(self, fn: Callable, *args: Any) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args))
        except Exception as exc:  # noqa: BLE001 - the future holds it, as the queue's would
            future.set_exception(exc)
        return future

    def call(self, fn: Callable, *args: Any, timeout: float = 10.0) -> Any:
        return fn(*args)

    def on_event_thread(self) -> bool:
        return True

    def after(self, seconds: float, fn: Callable, *args: Any) -> Timer:
        timer = Timer(self.now + seconds, None, fn, args)
        self.timers.append(timer)
        return timer

    def every(self, seconds: float, fn: Callable, *args: Any) -> Timer:
        if seconds <= 0:
            raise ValueError("a period must be positive")
        timer = Timer(self.now + seconds, seconds, fn, args)
        self.timers.append(timer)
        return timer

    def pass_time(self, seconds: float | None = None) -> int:
        """The clock moves on by ``seconds`` (None: until every timer set is due), then the timers due by
        then run, in the order they fell due, a periodic one as often as it fell due. Returns how many ran."""
        if seconds is not None:
            self.now += seconds
        else:
            self.now = max([self.now, *(t.due for t in self.timers if not t.cancelled)])
        ran = 0
        while due := [t for t in self.timers if not t.cancelled and t.due <= self.now]:
            timer = min(due, key=lambda t: t.due)
            self.timers.remove(timer)
            timer.fn(*timer.args)
            ran += 1
            if timer.period is not None and not timer.cancelled:
                timer.due += timer.period
                self.timers.append(timer)
        self.timers = [t for t in self.timers if not t.cancelled]
        return ran


class OnEvents:
    """``obj`` (a live app's folder) as a test drives it: each of its methods called through this runs as
    an event on ``events`` (the test waits for it and gets what it returns); its attributes are read as
    they stand between events."""

    def __init__(self, obj: Any, events: Any):
        self._obj, self._events = obj, events

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._obj, name)
        if inspect.ismethod(value):
            return lambda *args, **kwargs: self._events.call(functools.partial(value, *args, **kwargs))
        return value
