"""viser's message buffers are woken safely from the frame thread (sandbox/app/web/wakeups.py)."""

from __future__ import annotations

import asyncio
import threading

import pytest

from sandbox.app.web import wakeups
from viser.infra._async_message_buffer import AsyncMessageBuffer


@pytest.fixture
def loop():
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    yield loop
    loop.call_soon_threadsafe(loop.stop)
    thread.join(5)
    loop.close()


def on_loop(loop, coroutine):
    return asyncio.run_coroutine_threadsafe(coroutine, loop).result(5)


def test_another_thread_raises_the_flag_and_only_the_loop_wakes_the_waiters(loop):
    event = wakeups.LoopSafeEvent(loop)
    waiting = asyncio.run_coroutine_threadsafe(event.wait(), loop)
    on_loop(loop, asyncio.sleep(0))  # the waiter is parked
    event.set()                       # from this thread: never touches the waiters
    assert event.is_set()
    on_loop(loop, asyncio.sleep(0))
    assert not waiting.done()         # the loop has not been asked to wake it yet
    loop.call_soon_threadsafe(event.set)  # as viser's push does next
    assert waiting.result(5) is True  # woken, although the flag was already up


def test_a_buffer_built_after_install_has_the_loop_safe_event(loop):
    wakeups.install()
    wakeups.install()  # once is enough; twice changes nothing
    buffer = AsyncMessageBuffer(loop, persistent_messages=False)
    assert isinstance(buffer.message_event, wakeups.LoopSafeEvent)
    assert buffer.message_event._owner is loop
