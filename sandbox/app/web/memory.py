"""Memory that pages leave behind goes back to the system (issue 39, hole 8).
Runs on the app's event thread (a timer after pages leave).

20 pages connecting and dropping, 5 rounds, against ``serve``: the server grew 5-8 MB a round, 25 MB
after the first round. Nothing a page leaves stays reachable (tracemalloc from the third round to the
sixth: under 0.1 MB more of Python objects, none of them a page's), but two things kept memory:

- **Cycles.** The coroutines viser and websockets run for a connection (its message producer and
  consumer, the window loop, :mod:`sandbox.app.web.pacing`'s pacing, keepalive) end cancelled, and each
  cancelled task's exception holds its traceback, whose frames hold the task: reference cycles, with
  the last window of messages each had encoded. Only Python's full collection frees them, and it
  came every few rounds: 2-4 MB per 20 pages, held meanwhile.
- **malloc.** glibc keeps freed memory for reuse, in one arena per thread (viser's pool grows to
  the most pages served at once, up to 32 threads), and hands it back only from the top of a heap.

So once pages have left, and none has for :data:`QUIET_SECONDS` (a class closing its laptops leaves
in a burst), a full collection frees the cycles and glibc's ``malloc_trim`` hands the free pages of
every arena back: 80 ms of CPU once per burst (150,000 objects, after the drawing preview loaded
numba), on the app's event thread. Measured the same way: 1-4 MB after the first round, flat from the
second (collection alone: 9 MB; trimming alone: 24 MB, until a full collection came). Elsewhere than
glibc (macOS, musl, Windows) there is no trimming; the collection is done all the same.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import logging
from typing import Any, Callable

log = logging.getLogger("sandbox.app.web.memory")

#: Seconds without a page leaving before freed memory is handed back.
QUIET_SECONDS = 1.0


def _glibc_trim() -> Callable[[], Any] | None:
    """glibc's ``malloc_trim(0)``, or None where the C library has none."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        trim = libc.malloc_trim
    except (OSError, AttributeError):
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return lambda: trim(0)


class FreedMemoryReturn:
    """:data:`QUIET_SECONDS` after the last of a burst of departures (:meth:`page_left`), free what
    the departed pages left in cycles and hand freed memory back to the system: a timer on the app's
    event queue (``after(seconds, fn)``), restarted by each departure."""

    def __init__(self, after: Callable[..., Any], quiet: float = QUIET_SECONDS,
                 trim: Callable[[], Any] | None = None):
        self.quiet = float(quiet)
        self._after = after
        self._trim = trim if trim is not None else _glibc_trim()
        self._timer: Any = None
        #: How many times freed memory was handed back (for tests).
        self.returns = 0

    def page_left(self, *_: Any) -> None:
        """A page left (viser's disconnect callback, on the event queue; its client is not kept)."""
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self._after(self.quiet, self._give_back)

    def _give_back(self) -> None:
        self._timer = None
        gc.collect()  # the departed connections' coroutines, in cycles (module docstring)
        if self._trim is not None:
            self._trim()
        self.returns += 1


def return_memory_after_pages_leave(server: Any, after: Callable[..., Any]) -> FreedMemoryReturn:
    """Once pages have left ``server`` (a viser server), hand the memory they used back (see above);
    ``after(seconds, fn)``: the app's event queue's timer."""
    returner = FreedMemoryReturn(after)
    server.on_client_disconnect(returner.page_left)
    return returner
