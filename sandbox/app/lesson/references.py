"""The class challenge's reference runs, shared by the class: the paper's controller in a round's world
(settings, seed, goal) is run once for every student whose round ended in that world, in one process
pool for the class, not in a pool a student (ten students: ten processes of about 100 MB at once).
Runs on the app's event thread; a worker thread starts the pool (it blocks while the fork server loads
the model) and hands it over, as the Challenge folder's own reference run does.

A round ends at the first frame at or past its steps, so rounds in the same world end a few steps apart
(a late frame takes its steps in one): the asks for a world are gathered for :data:`GATHER_SECONDS`, then
one run answers each at its own step (:func:`~sandbox.model.challenge.paper_gains`). The pool starts
with the first run and is closed (its processes end) once no reference is waiting.
"""

from __future__ import annotations

import logging
import os
import pickle
import threading
from typing import Any, Callable

from sandbox.model.challenge import Gain, paper_gains
from sandbox.processes import simulation_context

log = logging.getLogger("sandbox.app.lesson")

#: Processes of the shared pool: distinct worlds (students on goals of their own) run side by side, one a core.
MOST_PROCESSES = max(1, min(2, os.cpu_count() or 1))
#: How long (s) the asks for one world are gathered before its run starts: a class challenge's rounds
#: start together at the class's pace and end within about a second of each other.
GATHER_SECONDS = 2.0

OnDone = Callable[[Gain], None]
OnError = Callable[[str], None]


class References:
    """The paper's score in a round's world, one run a world for a class (see the module docstring)."""

    def __init__(self, events: Any, processes: int = MOST_PROCESSES):
        self._events = events
        self.processes = int(processes)
        #: Each (world, step)'s score once known (a world: its pickled settings, seed and goal).
        self.known: dict[tuple[bytes, int], Gain] = {}
        #: Who waits for each (world, step)'s score: gathered, queued for the pool, or running.
        self._waiting: dict[tuple[bytes, int], list[tuple[OnDone, OnError]]] = {}
        self._gathering: dict[bytes, tuple[tuple, set[int]]] = {}  # world -> (config, seed, shape), steps
        self._queued: list[tuple[bytes, tuple]] = []  # runs waiting for the pool
        self._pool: Any = None
        self._starting = False
        self._stopped = False
        #: How many reference runs were started in all (the tests and the class benchmark count them).
        self.runs = 0

    def ask(self, spec: tuple, at_step: int, on_done: OnDone, on_error: OnError) -> None:
        """The paper's controller's :class:`Gain` in the world ``spec`` (settings, seed, goal: a runner's
        WorldSpec) over ``at_step`` steps, to ``on_done`` (or why not, to ``on_error``), on this thread."""
        config, seed, shape = spec
        world, step = pickle.dumps((config, seed, shape)), int(at_step)
        if (world, step) in self.known:
            on_done(self.known[(world, step)])
            return
        if self._stopped:
            on_error("the app stopped")
            return
        waiting = self._waiting.setdefault((world, step), [])
        waiting.append((on_done, on_error))
        if len(waiting) > 1:
            return  # gathered, or running, already: its answer is this one's too
        if world not in self._gathering:
            self._gathering[world] = ((config, seed, shape), set())
            self._events.after(GATHER_SECONDS, self._launch, world)
        self._gathering[world][1].add(step)

    def _launch(self, world: bytes) -> None:
        """The asks for ``world`` are gathered: one run for all their steps."""
        (config, seed, shape), steps = self._gathering.pop(world)
        if self._stopped:
            self._failed(world, sorted(steps), "the app stopped")
            return
        self._queued.append((world, (config, seed, sorted(steps), shape)))
        self._run_queued()

    def _run_queued(self) -> None:
        if self._pool is None:
            if not self._starting:
                self._starting = True
                threading.Thread(target=self._start_pool, name="class-references", daemon=True).start()
            return
        queued, self._queued = self._queued, []
        post = self._events.post  # the pool's callbacks run on its own thread: they only post
        for world, args in queued:
            self.runs += 1
            steps = args[2]
            self._pool.apply_async(paper_gains, args,
                                   callback=lambda gains, world=world: post(self._scored, world, gains),
                                   error_callback=lambda exc, world=world, steps=steps: post(
                                       self._failed, world, steps, str(exc)))

    def _start_pool(self) -> None:
        """In a worker: start the pool and hand it to the event thread (or end it, the app stopping)."""
        try:
            pool = simulation_context().Pool(self.processes)
        except Exception as exc:  # noqa: BLE001 - no process to run them in: each round counts, without a reference
            self._events.post(self._no_pool, str(exc))
            return
        if self._events.submit(self._adopt, pool).exception() is not None:
            pool.terminate()  # the queue stopped before it ran: nobody else will end it

    def _adopt(self, pool: Any) -> None:
        self._starting = False
        if self._stopped:
            pool.terminate()
            return
        self._pool = pool
        self._run_queued()

    def _no_pool(self, why: str) -> None:
        self._starting = False
        queued, self._queued = self._queued, []
        for world, args in queued:
            self._failed(world, args[2], why)

    def _scored(self, world: bytes, gains: dict[int, Gain]) -> None:
        for step, gain in gains.items():
            self.known[(world, step)] = gain
            for on_done, _ in self._waiting.pop((world, step), []):
                on_done(gain)
        self._close_if_idle()

    def _failed(self, world: bytes, steps: list[int], why: str) -> None:
        for step in steps:
            for _, on_error in self._waiting.pop((world, step), []):
                on_error(why)
        self._close_if_idle()

    def _close_if_idle(self) -> None:
        """No reference waits: the pool's processes end (a later challenge starts a new pool)."""
        if not self._waiting and self._pool is not None:
            self._pool.close()  # its tasks are done: its processes end by themselves, nothing waits here
            self._pool = None

    def stop(self) -> None:
        """The app is stopping (after its event queue stopped): the runs still going end now."""
        self._stopped = True
        if self._pool is not None:
            self._pool.terminate()
            self._pool = None
