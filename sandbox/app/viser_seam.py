"""(Placeholder until the seam module lands: route_callbacks only.)"""

from __future__ import annotations

from concurrent.futures import Future
from typing import Any, Callable


class _Submitter:
    """Stands where viser keeps its callback thread pool: each callback goes to ``submit``."""

    def __init__(self, submit: Callable[..., Future]):
        self.submit = submit

    def shutdown(self, wait: bool = True, **_: Any) -> None:
        """viser shuts its pool down on stop; the app's queue is stopped by the app."""


def route_callbacks(server: Any, submit: Callable[..., Future]) -> None:
    executor = _Submitter(submit)
    server._thread_executor = executor
    server.gui._thread_executor = executor
    server.scene._thread_executor = executor
