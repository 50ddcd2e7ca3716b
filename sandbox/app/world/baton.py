"""Two threads of a world host that take turns, never run together: the host's scheduler thread (which
steps the worlds' frames) and a builder thread (which runs one long build, a reset or a run to the end).
Held by the scheduler thread; handed to the builder thread for a slice of time at a time.

A long build cannot be cut into pieces from outside: a world's reset is one call into the model. So it
runs on a thread of its own, and it gives the host back at its *turning points* (each chunk of steps of
a run to the end, each progress report of a world being built) once its slice is over: between two
slices the scheduler steps the other worlds' frames. Only one of the two runs at any moment, so the
world being built is touched by one thread at a time and needs no lock; the hand-over (a condition)
orders what each wrote before the other reads it.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

SCHEDULER, BUILDER = "scheduler", "builder"


class Baton:
    """Who runs: the scheduler, or the builder until :attr:`until` (perf_counter seconds)."""

    def __init__(self) -> None:
        # shared by the scheduler thread and the builder thread, which hand the turn to each other
        self._turn = threading.Condition()
        self._holder = SCHEDULER
        self._builder: threading.Thread | None = None
        self._over = True
        #: When the builder's slice ends (it gives the turn back at its next turning point after it).
        self.until = 0.0
        #: Seconds the builds have run, slices counted (what the scheduler gave away).
        self.given = 0.0

    @property
    def building(self) -> bool:
        """Whether a build is under way (it runs only in the slices it is given)."""
        return not self._over

    def begin(self, build: Callable[[], Any]) -> None:
        """Scheduler: start ``build`` on a builder thread; it waits for its first slice."""
        assert self._over, "one build at a time"
        self._over = False

        def body() -> None:
            with self._turn:
                self._turn.wait_for(lambda: self._holder == BUILDER)
            try:
                build()
            finally:
                with self._turn:
                    self._over = True
                    self._holder = SCHEDULER
                    self._turn.notify_all()

        self._builder = threading.Thread(target=body, name="phototaxis-build", daemon=True)
        self._builder.start()

    def give(self, until: float) -> bool:
        """Scheduler: let the build run until ``until`` (or its end); True once it is over."""
        if self._over:
            return True
        started = time.perf_counter()
        with self._turn:
            self.until = until
            self._holder = BUILDER
            self._turn.notify_all()
            self._turn.wait_for(lambda: self._holder == SCHEDULER)
        self.given += time.perf_counter() - started
        if self._over and self._builder is not None:
            self._builder.join()
            self._builder = None
        return self._over

    def on_builder(self) -> bool:
        return self._builder is not None and threading.current_thread() is self._builder

    def turning_point(self) -> None:
        """Builder: give the turn back if the slice is over, and wait for the next (nothing on any
        other thread: the scheduler's own frames pass here too)."""
        if not self.on_builder() or time.perf_counter() < self.until:
            return
        with self._turn:
            self._holder = SCHEDULER
            self._turn.notify_all()
            self._turn.wait_for(lambda: self._holder == BUILDER)
