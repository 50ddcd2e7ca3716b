"""A time limit on the user's code: :func:`limited` runs a light program's
call (its import, construction, ``reset`` or ``update``) and stops it when it
overruns.

Python cannot kill a thread, but it can raise an exception in one
(``PyThreadState_SetAsyncExc``): a pure-Python loop takes it at its next
bytecode, and the call ends with :class:`ProgramTimeout`, which says where
the program was. It derives from BaseException, so a program's own
``except Exception`` does not swallow it. A call stuck where Python never
looks (a sleep, a lock, a long C routine) does not take it: after
:data:`GRACE` more seconds the process's :data:`on_stuck` hook is called with
one line. By default it prints that line and ends the process with exit
code 2 (``run``, ``sweep``); the live app's simulation process tells the app
and ends, and the app starts a fresh one with the paper's controller.

One watchdog thread per process watches every limited call; it sleeps while
none is running.
"""

from __future__ import annotations

import ctypes
import itertools
import os
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

#: Seconds a light program's call may take (``--program-time-limit``).
DEFAULT_LIMIT = 2.0
#: Seconds a call that overran has to take its exception before the process is ended.
GRACE = 0.5  # a pure-Python loop takes the exception within milliseconds


class ProgramTimeout(BaseException):
    """A limited call overran (raised inside it by the watchdog)."""


def exit_on_stuck(prefix: str = "phototaxis") -> Callable[[str], None]:
    """A :data:`on_stuck` hook for a command: print ``PREFIX: error: why`` and end with exit code 2
    (the process cannot unwind: one of its threads is stuck in the user's code)."""

    def stuck(why: str) -> None:
        sys.stderr.write(f"{prefix}: error: {why}\n")
        sys.stderr.flush()
        os._exit(2)

    return stuck


#: Called (on a thread of its own) with one line when a call overran and did not stop.
on_stuck: Callable[[str], None] = exit_on_stuck()


@dataclass
class _Call:
    thread_id: int
    deadline: float
    what: str
    source: str | None
    injected: bool = False
    where: str = ""


class _Watchdog:
    def __init__(self) -> None:
        self._calls: dict[int, _Call] = {}
        self._ids = itertools.count()
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._thread: threading.Thread | None = None

    def run(self, function: Callable, args: tuple, limit: float, what: str, source: str | None) -> Any:
        ident = next(self._ids)
        call = _Call(threading.get_ident(), time.monotonic() + limit, what, source)
        with self._lock:
            self._calls[ident] = call
            self._ensure_thread()
            self._wake.notify()
        try:
            try:
                return function(*args)
            finally:
                self._end(ident)
        except ProgramTimeout:
            self._end(ident)  # the exception may have landed inside the first _end: nothing is pending now
            raise ProgramTimeout(f"{what} took longer than {limit:g} s{call.where}") from None

    def _end(self, ident: int) -> None:
        with self._lock:
            call = self._calls.pop(ident, None)
            if call is not None and call.injected:
                _raise_in(call.thread_id, None)  # the call returned first: cancel the exception on its way

    def _ensure_thread(self) -> None:
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._watch, name="phototaxis-watchdog", daemon=True)
            self._thread.start()

    def _watch(self) -> None:
        with self._lock:
            while True:
                now = time.monotonic()
                for call in list(self._calls.values()):
                    if now < call.deadline:
                        continue
                    if not call.injected:
                        call.where = _where(call)
                        call.injected = True
                        call.deadline = now + GRACE
                        _raise_in(call.thread_id, ProgramTimeout)
                    else:
                        why = f"{call.what} took longer than its time limit and did not stop{call.where}"
                        call.deadline = float("inf")  # once
                        threading.Thread(target=on_stuck, args=(why,), daemon=True).start()
                deadlines = [c.deadline for c in self._calls.values() if c.deadline != float("inf")]
                self._wake.wait(None if not deadlines else max(0.0, min(deadlines) - time.monotonic()))


_WATCHDOG = _Watchdog()


def limited(function: Callable, *args: Any, limit: float = DEFAULT_LIMIT, what: str = "the light program",
            source: str | None = None) -> Any:
    """``function(*args)``, or ProgramTimeout after ``limit`` seconds; ``source``, the program's file,
    lets the message name the line it was at."""
    if limit is None or limit <= 0 or limit == float("inf"):
        return function(*args)
    return _WATCHDOG.run(function, args, float(limit), what, source)


def _raise_in(thread_id: int, exception: type | None) -> None:
    # None clears an exception not yet raised.
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread_id),
                                               None if exception is None else ctypes.py_object(exception))


def _where(call: _Call) -> str:
    """`` (at file.py line N, in f)``: the innermost frame in the program's file, else the innermost."""
    frame = sys._current_frames().get(call.thread_id)
    chosen = frame
    while frame is not None:
        if call.source and Path(frame.f_code.co_filename) == Path(call.source):
            chosen = frame
            break
        frame = frame.f_back
    if chosen is None:
        return ""
    return f" (at {Path(chosen.f_code.co_filename).name} line {chosen.f_lineno}, in {chosen.f_code.co_name})"
