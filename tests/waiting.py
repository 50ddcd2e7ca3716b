"""Waiting on a condition instead of sleeping: one helper for every test that waits."""
from __future__ import annotations

import time
from typing import Callable, TypeVar

T = TypeVar("T")


def wait_until(condition: Callable[[], T], timeout: float = 60.0, what: str = "condition",
               poll: float = 0.02) -> T:
    """The first truthy value of ``condition()``, polled every ``poll`` s; an AssertionError naming
    ``what`` after ``timeout`` s. Generous by default: a loaded machine (a sweep beside the tests)
    is slow, and a wait that succeeds returns as soon as it can."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(poll)


def wait_until_steady(read: Callable[[], T], quiet: float = 0.3, timeout: float = 20.0) -> T:
    """The value of ``read()`` once it has not changed for ``quiet`` seconds."""
    deadline = time.monotonic() + timeout
    value, since = read(), time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.02)
        now = read()
        if now != value:
            value, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet:
            return value
    raise AssertionError(f"still changing after {timeout:.0f} s")


def paused_step(runner) -> int:
    """The step the engine stopped at once told to pause.

    ``runner.playing`` flips at once in this process, while the engine may be in the middle of a
    frame's steps and, in its own process, a frame may still be on its way. Each frame says whether
    the engine was playing when it was taken: the first that says paused carries the last step, and
    every later one the same."""
    found = []

    def paused() -> bool:
        snap = runner.latest
        if not snap.playing:
            found.append(snap.step)
        return bool(found)

    wait_until(paused, what="the engine to pause")
    return found[0]


def frames_pass(runner, count: int = 5) -> None:
    """Wait until ``count`` more frames have arrived from the engine (it sends them while paused too)."""
    start = runner.latest.frame
    wait_until(lambda: runner.latest.frame >= start + count, what=f"{count} more frames")
