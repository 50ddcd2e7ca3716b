"""Refusals in the server's log, at most one line a second per page: :class:`RefusalLog`.
Runs on viser's event loop.

A page that sends thousands of refused messages a second must not write thousands of lines (a flood
of malformed cameras grew the log by 32 MB in 20 s, issue 54). The first refusal of a page is logged
as it comes; after it, at most one line a second says how many more were refused and the latest
reason; when the page leaves, one line says what was not said yet.

Runs on viser's event loop: each log belongs to one server's inbox or to one connection's budgets
(:mod:`sandbox.app.web.rates`), both read on that loop alone, so it takes no lock.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

#: Seconds between two lines about one page.
EVERY = 1.0


@dataclass
class _Page:
    logged_at: float
    unlogged: int = 0
    latest: str = ""


class RefusalLog:
    """One logger's refusals, per page (on the event loop of the server whose pages they are)."""

    def __init__(self, log: logging.Logger, every: float = EVERY):
        self.log, self.every = log, every
        self._pages: dict[int | None, _Page] = {}

    def refused(self, page: int | None, why: str, now: float | None = None) -> None:
        """A message from connection ``page`` was refused because ``why`` (one line: what to change)."""
        now = time.monotonic() if now is None else now
        state = self._pages.get(page)
        if state is None:
            self._pages[page] = _Page(logged_at=now)
            line = f"refused a message from connection {page}: {why}"
        elif now - state.logged_at >= self.every:
            line = (f"refused {_messages(state.unlogged + 1)} from connection {page} in the last "
                    f"{now - state.logged_at:.0f} s; the latest: {why}")
            state.logged_at, state.unlogged, state.latest = now, 0, ""
        else:
            state.unlogged, state.latest = state.unlogged + 1, why
            return
        self.log.warning(line)

    def forget(self, page: int | None) -> None:
        """The page left: say what was not said yet."""
        state = self._pages.pop(page, None)
        if state is not None and state.unlogged:
            self.log.warning("refused %s from connection %s before it left; the latest: %s",
                             _messages(state.unlogged, "more "), page, state.latest)


def _messages(count: int, more: str = "") -> str:
    return f"{count} {more}message" if count == 1 else f"{count} {more}messages"
