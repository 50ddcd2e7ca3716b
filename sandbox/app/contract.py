"""What the app asks of a simulation runner, and what both runners share.

The app (server, scene, panel, recorder) drives a simulation only through
:class:`SimulationRunner`. Two classes follow it:
:class:`~sandbox.app.runner.Runner` (the simulation in a thread of this
process: tests, headless recording) and
:class:`~sandbox.app.process.ProcessRunner` (in a process of its own: the
live app). Both publish frames through :class:`FramePublisher`, which owns
the listeners, counts the frames and keeps one broken listener from
silencing the others.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from typing import Any, Callable, Iterable, Protocol, runtime_checkable

from sandbox.app.snapshot import Snapshot
from sandbox.model.metrics import Sample

log = logging.getLogger("sandbox.app")

Callback = Callable[[Any], None] | None


class FramePublisher:
    """Listeners of frames, guarded callbacks, and the frame rate they were handed at."""

    def __init__(self) -> None:
        self._listeners: list[Callable[[Snapshot], None]] = []
        #: What went wrong in a listener or a callback (logged too); the simulation went on.
        self.errors: list[BaseException] = []
        self.frames_published = 0
        self.publish_times: deque = deque(maxlen=120)

    def subscribe(self, listener: Callable[[Snapshot], None]) -> None:
        self._listeners.append(listener)

    def _publish(self, snap: Snapshot) -> None:
        """Hand a frame to every listener (a broken one must not stop the others) and count it."""
        for listener in list(self._listeners):
            self._deliver(listener, snap)
        self.frames_published += 1
        self.publish_times.append(time.perf_counter())

    def _deliver(self, callback: Callable[[Any], None], value: Any) -> None:
        """Call one listener or callback; one that raises is logged and kept in :attr:`errors`."""
        try:
            callback(value)
        except Exception as exc:  # noqa: BLE001 - the simulation and the other listeners go on
            self.errors.append(exc)
            log.exception("a listener of the simulation failed")

    def frames_per_second(self) -> float:
        if len(self.publish_times) < 2:
            return 0.0
        span = self.publish_times[-1] - self.publish_times[0]
        return (len(self.publish_times) - 1) / span if span > 0 else 0.0


@runtime_checkable
class SimulationRunner(Protocol):
    """The simulation as the app drives it. Commands run between steps; what they return
    (or raise) reaches ``on_done`` (or ``on_error``) on the runner's thread."""

    playing: bool
    steps_per_frame: int
    #: The robots the viewers follow: the snapshots carry their photocells (``Snapshot.followed``).
    followed: tuple[int, ...]
    want_field: bool
    hold_at: int | None
    errors: list

    def start(self) -> Any: ...

    def stop(self, timeout: float = 5.0) -> None: ...

    def post(self, command: Callable, *, on_done: Callable[[Any], None] | None = None,
             on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def call(self, command: Callable, timeout: float = 10.0) -> Any: ...

    def update_config(self, changes: dict[str, Any], *, on_done: Callable[[Any], None] | None = None,
                      on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def reset(self, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def set_shape(self, vertices: Any, name: str, *, on_done: Callable[[Any], None] | None = None,
                  on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def set_program(self, spec: str | None, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def set_outline(self, outline: str, *, on_done: Callable[[Any], None] | None = None,
                    on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def world_spec(self, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def set_lamp(self, centre: tuple[float, float] | None, radius: float | None = None, mode: str = "lamp", *,
                 on_done: Callable[[Any], None] | None = None,
                 on_error: Callable[[BaseException], None] | None = None) -> None: ...

    def set_playing(self, playing: bool) -> None: ...

    def set_speed(self, steps_per_frame: int) -> None: ...

    def follow(self, indices: Iterable[int]) -> None: ...

    def step_once(self, n: int = 1) -> None: ...

    def hold(self, step: int | None) -> None:
        """Playing, step no further than ``step`` (None: no limit)."""
        ...

    def run_to(self, step: int) -> None:
        """Step until the world is at ``step`` (nothing if it is there or past)."""
        ...

    def cancel_build(self) -> None: ...

    def subscribe(self, listener: Callable[[Snapshot], None]) -> None: ...

    def on_progress(self, listener: Callable[[float | None], None]) -> None: ...

    @property
    def latest(self) -> Snapshot: ...

    def series(self) -> list[Sample]:
        """The metric samples of the running world only (a reset starts a new list)."""
        ...

    def steps_per_second(self) -> float: ...

    def frames_per_second(self) -> float: ...
