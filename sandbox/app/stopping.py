"""How ``phototaxis serve`` is stopped: a SIGTERM (a service manager, ``kill``) is a Ctrl+C, and
either stops it cleanly at any moment, start-up included (issue 39, hole 4).

From the dispatcher's first line on (:func:`term_stops`), the first SIGTERM or Ctrl+C is a request to
stop. While the program loads its modules and builds the app it is only noted: an exception raised
in the middle of an import or of a half-built object leaves things no ``finally`` can tidy (Python
3.11 even turns it into a RuntimeError inside a class's ``__set_name__``), and that phase takes a few
seconds at most. Where the program waits (for its simulation's first frame, then serving:
:func:`interruptible`), it raises KeyboardInterrupt at once, and ``serve`` stops what it has started.
Later signals are ignored: a service manager's impatience, or a second Ctrl+C, does not cut the
clean stop short. Before this, a SIGTERM while the app was being built ended the process at once,
leaving its fork server and simulation process running and the semaphores of its queues leaked.

No viser here: the dispatcher imports this module before any of the web server's.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Any, Iterator

#: The signals that stop the program.
STOPPING = (signal.SIGTERM, signal.SIGINT)


class _Requests:
    """Whether a stop was asked for, and whether the main thread may be interrupted now."""

    asked = False
    interruptible = False
    handling = False  # term_stops is in force (nested, it leaves the outer one be)


def term_stops() -> contextlib.AbstractContextManager:
    """Within: the first SIGTERM or Ctrl+C asks the program to stop (see the module docstring). On
    the way out, the handlers found are put back, unless a stop was asked for (the program ends).
    Only the main thread may set signal handlers: elsewhere, nothing changes."""
    return _handling() if _in_main_thread() and not _Requests.handling else contextlib.nullcontext()


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """Within: a stop asked for raises KeyboardInterrupt in the main thread at once (on entering,
    if it was asked for earlier)."""
    _Requests.interruptible = True
    try:
        if _Requests.asked:
            raise KeyboardInterrupt
        yield
    finally:
        _Requests.interruptible = False


@contextlib.contextmanager
def _handling() -> Iterator[None]:
    found = {number: signal.signal(number, _ask_to_stop) for number in STOPPING}
    _Requests.asked, _Requests.interruptible, _Requests.handling = False, False, True
    try:
        yield
    finally:
        _Requests.handling = False
        if not _Requests.asked:
            for number, handler in found.items():
                signal.signal(number, handler)


def _ask_to_stop(signum: int, frame: Any) -> None:
    for number in STOPPING:  # once: the stop it starts is not cut short
        signal.signal(number, signal.SIG_IGN)
    _Requests.asked = True
    if _Requests.interruptible:
        raise KeyboardInterrupt


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()
