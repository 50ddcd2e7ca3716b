"""Send each viewer what it draws (issue 24, item 2).
Its reports are read on viser's event loop; the app's event thread asks each page's rate.

The frame thread changes the shared scene 30 times a second, and viser
sends every change to every page. A page that draws in software (a
classroom laptop, a headless test browser) draws 7-12 of them: the rest
cost bytes and the page's time to apply, and are never seen.

viser's client reports nothing per drawn frame, but it runs the Javascript
the server sends (``RunJavascriptMessage``, viser's own way to load
plotly). At connect, each page gets :func:`report_js` (``page/report.js``)
with a token of its own. The script marks the page's WebGL draw calls. While
the page is busy (an animation frame came more than :data:`BUSY_GAP_MS` after
the last), it asks ``/__drawn/<token>`` at the first animation frame after a
draw (one request at a time): "I drew". After a second with no such gap it says
``/__drawn/<token>?calm`` once, and reports no more until it is busy again:
a page that keeps up (a laptop with a graphics card) costs the server one
request, its calm after its first second (a report cost it 0.6 ms of CPU,
measured under load). The gate answers that address (:meth:`Pacer.drawn`).

The worlds themselves take a snapshot only as often as the fastest drawing
page needs (:func:`frames_per_snapshot`, applied by the app twice a second):
every frame while any page keeps up or is paced without a rate yet.

The shared scene leaves the server in windows, one connection at a time
(viser's window generator over the broadcast buffer, reached through
:func:`sandbox.app.web.viser_seam.pace_windows`). A page that has
reported once is paced: after each window it gets, the next waits until it
reports a drawn frame again, or :data:`MOST_WAIT` passes (a hidden tab
stops drawing). Meanwhile the buffer keeps only the newest of each node's
updates (viser culls the older), so the next window carries the current
frame, never a backlog. A page that never reports (viser's embed, a
websocket client of our own), or says it is calm, is not paced.

:data:`CLIENT` is what the script relies on in viser's client, checked against the installed viser's
bundle (:mod:`sandbox.app.web.client_seam`).

:class:`Pacer` runs on viser's event loop (the gate's answer to a report, a page arriving and leaving,
its windows), but for :meth:`Pacer.drawing_rates`, which the app's event thread calls.
"""

from __future__ import annotations

import asyncio
import math
import secrets
import threading
import time
from collections import Counter, deque
from typing import AsyncGenerator, Iterable

from sandbox.app.web.client_seam import Relies, script

#: Where a page reports a drawn frame.
PATH = "/__drawn/"
#: Longest a page waits for the scene's next window when it reports no drawing (s).
MOST_WAIT = 1.0
#: A page is busy while its animation frames come further apart than this (ms): it draws under 20 a second.
BUSY_GAP_MS = 50
#: What a page adds to its address when it keeps up again.
CALM = "?calm"
#: A page's drawing rate is read over its reports of this many last seconds (at least 3 of them).
RATE_WINDOW = 2.0
#: Snapshots are taken at least this many times the fastest page's drawing rate, and at least
#: :data:`FEWEST_SHOWN` a second: a page is never left waiting for a frame to draw. (A page drawing 20
#: frames a second or more keeps up, and is sent every frame.)
HEADROOM = 1.5
FEWEST_SHOWN = 10.0


def frames_per_snapshot(fps: float, rates: Iterable[float | None], most: float | None = None) -> int:
    """Every how many frames (of ``fps`` a second) the worlds need a snapshot, given each page's drawing
    rate (frames a second; None: a page that keeps up, or has not said). A snapshot nobody draws still
    costs its world's process, the app and the pages' decoding: in compare mode, with one page drawing
    6-7 frames a second in software, taking 15 instead of 30 a second ran both worlds about 6 % faster
    (60-s runs, alternating: 21.5 and 20.6x against 20.2 and 19.4x).
    Every frame while any page keeps up (or there is none, or one has not said); ``most``: at most that
    many snapshots a second all the same (a class's teacher's world, :mod:`sandbox.app.lesson.classroom`)."""
    rates = list(rates)
    if not rates or any(rate is None for rate in rates):
        every = 1
    else:
        every = max(1, int(fps // max(HEADROOM * max(rates), FEWEST_SHOWN)))
    return every if most is None else max(every, math.ceil(fps / most - 1e-9))

def report_js(address: str) -> str:
    """The reporting script (``page/report.js``) for a page that reports at ``address``."""
    return script("report.js", address=address, busy_gap_ms=BUSY_GAP_MS, calm=CALM)


#: What report.js relies on in viser's client (sandbox.app.web.client_seam).
CLIENT = (
    Relies("WebGL2RenderingContext.prototype", "viser's scene (three.js) draws with WebGL 2: the script marks "
           "its draw calls on the context's prototype", found=(r"getContext\(`webgl2`",)),
    Relies("drawArrays", "one of the calls with which three.js draws", found=(r"\.drawArrays\(",)),
    Relies("drawElements", "one of the calls with which three.js draws", found=(r"\.drawElements\(",)),
    Relies("drawArraysInstanced", "one of the calls with which three.js draws", found=(r"\.drawArraysInstanced\(",)),
    Relies("drawElementsInstanced", "one of the calls with which three.js draws",
           found=(r"\.drawElementsInstanced\(",)),
)


def drawing_rate(times: Iterable[float], now: float) -> float | None:
    """Frames a second from the times of a page's reports (one per drawn frame while it is busy): over
    those of the last :data:`RATE_WINDOW` s, None if fewer than 3 (it keeps up, or stopped drawing).
    ``(n - 1) / span``: n reports span n - 1 frame intervals."""
    recent = [t for t in times if now - t <= RATE_WINDOW]
    if len(recent) < 3 or recent[-1] <= recent[0]:
        return None
    return (len(recent) - 1) / (recent[-1] - recent[0])


class Pacer:
    """Which page reports under which token, and the windows of the shared scene held for each."""

    def __init__(self) -> None:
        self._client_of: dict[str, int] = {}
        self._token_of: dict[int, str] = {}
        self._drawn: dict[int, asyncio.Event] = {}
        self.paced: set[int] = set()  # pages that reported a drawn frame and have not said calm since
        #: per page that said how it draws (busy or calm; a websocket client never does): when it reported
        #: its last drawn frames, emptied by its calm
        self._report_times: dict[int, deque] = {}
        # Shared by viser's event loop (a page's report, a page leaving) and the app's event thread, which
        # reads the rates twice a second (drawing_rates): the one state here another thread reads.
        self._rates_lock = threading.Lock()
        #: per page: reports heard, and windows of the shared scene sent
        self.reports: Counter = Counter()
        self.windows: Counter = Counter()

    # ------------------------------------------------------------ pages
    def script_for(self, client_id: int) -> str:
        """The reporting script for a page that just connected (on the event loop)."""
        token = secrets.token_urlsafe(16)
        self._client_of[token], self._token_of[client_id] = client_id, token
        self._drawn[client_id] = asyncio.Event()
        return report_js(PATH + token)

    def drawn(self, report: str, now: float | None = None) -> bool:
        """A page reports (on the event loop; ``now``: its time.monotonic(), for tests): ``<token>`` a drawn
        frame, ``<token>?calm`` that it keeps up again (it is then sent everything). True if the token is
        a page's."""
        calm = report.endswith(CALM)
        client_id = self._client_of.get(report[:-len(CALM)] if calm else report)
        if client_id is None:
            return False
        if calm:
            self.paced.discard(client_id)
        else:
            self.reports[client_id] += 1
            self.paced.add(client_id)
        with self._rates_lock:
            times = self._report_times.setdefault(client_id, deque(maxlen=64))
            if calm:
                times.clear()
            else:
                times.append(time.monotonic() if now is None else now)
        self._drawn[client_id].set()  # a window held for the page goes
        return True

    def forget(self, client_id: int) -> None:
        token = self._token_of.pop(client_id, None)
        self._client_of.pop(token, None)
        with self._rates_lock:
            self._report_times.pop(client_id, None)
        self.paced.discard(client_id)
        self.reports.pop(client_id, None)
        self.windows.pop(client_id, None)
        event = self._drawn.pop(client_id, None)
        if event is not None:
            event.set()  # a window held for the page goes (and its connection ends)

    def drawing_rates(self, now: float | None = None, pages: Iterable[int] | None = None) -> list[float | None]:
        """Each drawing page's rate (frames a second) over the last :data:`RATE_WINDOW` s, or None for a
        page that keeps up or has not reported enough lately (any thread). A client that never said how
        it draws draws nothing (a websocket client of our own, a page that has not drawn for a second
        yet): it is not counted. ``pages``: only these pages' (client ids; None: every page's): a class's
        students draw worlds of their own, not the one whose snapshots these rates pace."""
        now = time.monotonic() if now is None else now
        wanted = None if pages is None else set(pages)
        with self._rates_lock:
            return [drawing_rate(times, now) for client_id, times in self._report_times.items()
                    if wanted is None or client_id in wanted]

    # ---------------------------------------------------------- windows
    async def hold_windows(self, windows: AsyncGenerator, client_id: int, full: int) -> AsyncGenerator:
        """``windows`` (one page's windows of the shared scene, :func:`sandbox.app.web.viser_seam.pace_windows`),
        each after the page's report of drawing the last. A ``full`` window (viser cuts
        them at that many messages) may end inside a frame: the rest follows at once."""
        try:
            while True:
                try:
                    window = await windows.__anext__()
                except StopAsyncIteration:
                    return
                drawn = self._drawn.get(client_id)
                if drawn is not None:  # (None: the page has left)
                    drawn.clear()  # the next report is of a frame drawn after this window came
                    self.windows[client_id] += 1
                yield window
                if drawn is not None and client_id in self.paced and len(window) < full:
                    try:
                        await asyncio.wait_for(drawn.wait(), MOST_WAIT)
                    except asyncio.TimeoutError:
                        pass
        finally:
            await windows.aclose()
