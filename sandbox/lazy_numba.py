"""Compiled loops that load numba only when first called.

The web server imports modules that hold such loops (the light field, the
outline's distance) but runs them rarely or never; importing numba took a
quarter of its start. :func:`compiled_at_first_use` leaves the function as it
is and returns a callable that compiles it (or loads it from numba's cache) on
its first call.
"""

from __future__ import annotations

import functools
import threading
from typing import Any, Callable

_lock = threading.Lock()


def compiled_at_first_use(function: Callable[..., Any]) -> Callable[..., Any]:
    """``function`` compiled by numba (``njit(cache=True)``) when the returned callable is first called."""
    compiled: Callable[..., Any] | None = None

    @functools.wraps(function)
    def call(*args: Any) -> Any:
        nonlocal compiled
        if compiled is None:
            with _lock:  # two threads' first calls compile once
                if compiled is None:
                    from numba import njit

                    compiled = njit(cache=True)(function)
        return compiled(*args)

    return call
