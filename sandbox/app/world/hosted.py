"""One world in a shared world host, behind the runner contract: :class:`HostedRunner`, a drop-in for
:class:`~sandbox.app.world.child.ProcessRunner` (class mode gives each student one). Called from the
app's event thread; its own receiving thread reads its world's messages and settles the futures, as a
process runner's does.

It *is* a process runner whose child is a slot in a host (sandbox.app.world.pool): every command,
answer, frame, crash and restart goes as a process runner's does, from the settings that stand
(sandbox.app.world.standing). What it adds:

- ``key``: the world's name in the pool. A runner stopped leaves its world paused in its host, and a
  runner made later with the same key finds it again (where it was, its goal, its series, and its
  controls: playing or paused, its speed) until the host frees it (``free_after``, 10 min by default);
- :meth:`HostedRunner.free`: stop, and free the world at once (nobody will come back for it);
- :meth:`HostedRunner.watch`: whether anyone watches (a world nobody watches pauses and sends no frames);
- :meth:`HostedRunner.on_queue`: a build's place in its host's queue (``3``: "3rd in the queue"), None
  when its turn has come.

A class's default pace is :data:`CLASS_FPS` frames a second of :data:`CLASS_STEPS_PER_FRAME` steps: 90
steps a second, three times real time at the paper's step of 1/30 s.
"""

from __future__ import annotations

import itertools
import threading
from typing import Any, Callable

from sandbox.app.world.child import ProcessRunner
from sandbox.app.world.contract import Deliver
from sandbox.app.world.host import Found, Queued, Watch
from sandbox.app.world.pool import HostPool, Slot
from sandbox.model import watchdog
from sandbox.model.config import Config

#: A class's worlds: 10 frames a second (a page draws 8 or more), 9 steps each: 3x real time.
CLASS_FPS = 10.0
CLASS_STEPS_PER_FRAME = 9

_runners = itertools.count(1)  # numbers the runners of this process (their commands' ids)
# the pool a runner made without one shares: made by the first such runner; shared by the threads that make
# runners (the main thread, the event thread, workers)
_default_lock = threading.Lock()
_default_pool: HostPool | None = None


def default_pool() -> HostPool:
    """The pool runners share when none is given: hosts up to the number of cores."""
    global _default_pool
    with _default_lock:
        if _default_pool is None or _default_pool.stopped:
            _default_pool = HostPool()
        return _default_pool


class HostedRunner(ProcessRunner):
    """A world in a host of ``pool`` (see the module docstring); ``key`` None: a new world's own."""

    def __init__(self, config: Config, *, pool: HostPool | None = None, key: str | None = None,
                 shape: Any = "from-config", seed: int | None = None, fps: float = CLASS_FPS,
                 steps_per_frame: int = CLASS_STEPS_PER_FRAME, playing: bool = True, chart_every: int = 100,
                 program_time_limit: float = watchdog.DEFAULT_LIMIT, wait: bool = True,
                 deliver: Deliver | None = None):
        self.pool = pool or default_pool()
        self.key = key or self.pool.new_key()
        self._queue_listeners: list[Callable[[int | None], None]] = []
        self._watched = True  # what watch() said last: a world restarted after a crash is told it again
        super().__init__(config, shape=shape, seed=seed, fps=fps, steps_per_frame=steps_per_frame, playing=playing,
                         chart_every=chart_every, program_time_limit=program_time_limit, wait=wait, deliver=deliver)
        # The ids of its commands are its own: the answer to an earlier runner's command on the same world
        # (a build that was under way when its page reloaded) settles nothing of this one's.
        self._ids = itertools.count(next(_runners) << 32)

    def _new_child(self, settings: dict) -> Slot:
        slot = self.pool.open(self.key, settings)
        if not self._watched:
            slot.send(Watch(False))
        return slot

    def _take(self, message: Any) -> None:
        if isinstance(message, Queued):
            for listener in list(self._queue_listeners):
                self._deliver(listener, message.place)
        elif isinstance(message, Found):  # (heard before its first frame: in the constructor, or ready())
            for setting in message.controls.settings():  # the world goes on as it was: paused, at its speed
                self.submit(setting)
        else:
            ProcessRunner._take(self, message)

    def on_queue(self, listener: Callable[[int | None], None]) -> None:
        """``listener(place)`` hears that a build waits in its host's queue, ``place``-th (the build
        under way is the first); ``listener(None)`` when its turn has come (its progress follows)."""
        self._queue_listeners.append(listener)

    def free(self) -> None:
        """Stop, and have the host free the world now rather than keep it for a reopen (a student who left
        the class)."""
        with self._child_lock:
            self._child.free = True
        self.stop()

    def watch(self, on: bool) -> None:
        """Someone watches the world (it steps, and sends frames), or nobody does (it pauses)."""
        with self._child_lock:
            self._watched = bool(on)
            self._child.send(Watch(self._watched))
