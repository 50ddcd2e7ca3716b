"""viser's message buffers, woken safely from the threads that draw.

viser 1.1.1's ``AsyncMessageBuffer.push`` runs in whatever thread changes
the scene (ours: the frame thread) and calls ``message_event.set()`` there,
then again through ``call_soon_threadsafe``. The first call is not thread
safe: ``asyncio.Event.set`` walks the event's waiters while the event loop
may be adding or removing one. Under two test suites at once it raised
"deque mutated during iteration" inside a frame's update, which was then
drawn only in part.

The buffers here get an event whose ``set`` from another thread only raises
the flag (what viser's own comment says the call is for: "so we can read
the value immediately in synchronous logic"). Waking the waiters is left to
the event loop, where viser's ``call_soon_threadsafe(set)`` (right after
the push, or at the end of an atomic block) does it; there ``set`` wakes
them even if another thread raised the flag first, so no wake-up is lost.
"""

from __future__ import annotations

import asyncio

from sandbox.app.web import viser_seam


class LoopSafeEvent(asyncio.Event):
    """An asyncio.Event that other threads may ``set``: the flag at once, the waiters on ``loop``."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__()
        self._owner = loop

    def set(self) -> None:
        if _running_loop() is self._owner:
            viser_seam.set_event_flag(self, False)  # so that set() wakes the waiters even if a thread raised it
            super().set()
        else:
            viser_seam.set_event_flag(self, True)


def _running_loop() -> asyncio.AbstractEventLoop | None:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def install() -> None:
    """Every message buffer viser builds from now on wakes its sender as above (once)."""
    viser_seam.give_message_buffers(LoopSafeEvent)
