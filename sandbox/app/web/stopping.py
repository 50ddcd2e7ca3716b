"""How ``phototaxis serve`` is stopped: a SIGTERM (a service manager, ``kill``) is a Ctrl+C, and
either stops it cleanly at any moment, start-up included (issue 39, hole 4).
Runs on the main thread (its signal handler and its wait).

From the dispatcher's first line on (:func:`term_stops`), the first SIGTERM or Ctrl+C is a request to
stop, acted on within 2 s whatever the program is doing (issue 54, E):

- until the program starts something a stop must end (:func:`starting`: its simulation process, its
  web server), there is nothing to tidy: it says "stopped" and exits with 0 at once, in the middle of
  an import if need be (raising there instead would leave half-imported modules that no ``finally``
  can tidy; Python 3.11 even turns it into a RuntimeError inside a class's ``__set_name__``);
- from then on, where the program waits (for its simulation's first world, however long that takes
  to build, then serving: :func:`interruptible`), it raises KeyboardInterrupt at once, and ``serve``
  stops what it has started; elsewhere (building the app's panel: a fraction of a second) it is
  noted and raised at the next wait.

Later signals are ignored: a service manager's impatience, or a second Ctrl+C, does not cut the
clean stop short. Before this, a SIGTERM while the app was being built ended the process at once,
leaving its fork server and simulation process running and the semaphores of its queues leaked
(issue 39); then a SIGTERM while the first world was being built waited for it (53 s for a slow
goal, and exit 1 with a traceback when the build ran out of memory; issue 54).

No viser here: the dispatcher imports this module before any of the web server's.
"""

from __future__ import annotations

import contextlib
import os
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
    started = False  # the program has started something a stop must end (see starting)


def term_stops() -> contextlib.AbstractContextManager:
    """Within: the first SIGTERM or Ctrl+C asks the program to stop (see the module docstring). On
    the way out, the handlers found are put back, unless a stop was asked for (the program ends).
    Only the main thread may set signal handlers: elsewhere, nothing changes."""
    return _handling() if _in_main_thread() and not _Requests.handling else contextlib.nullcontext()


def starting() -> None:
    """From here on the program starts what a stop must end (processes, a server): a stop asked for is
    acted on where it waits (:func:`interruptible`), no longer by exiting at once."""
    _Requests.started = True


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """Within: a stop asked for raises KeyboardInterrupt in the main thread at once (on entering,
    if it was asked for earlier). Nested, the outer one goes on; in another thread, nothing changes."""
    if not _in_main_thread():
        yield
        return
    outer = _Requests.interruptible
    _Requests.interruptible = True
    try:
        if _Requests.asked:
            raise KeyboardInterrupt
        yield
    finally:
        _Requests.interruptible = outer


@contextlib.contextmanager
def _handling() -> Iterator[None]:
    found = {number: signal.signal(number, _ask_to_stop) for number in STOPPING}
    _Requests.asked, _Requests.interruptible, _Requests.handling, _Requests.started = False, False, True, False
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
    if not _Requests.started:  # nothing to tidy (os.write: the handler may have come in the middle of a print)
        os.write(1, b"stopped\n")
        os._exit(0)
    if _Requests.interruptible:
        raise KeyboardInterrupt


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()
