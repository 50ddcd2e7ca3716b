"""What every folder of the panel shares: notifications. (Where a click meets the floor is the view's:
:func:`sandbox.app.view.floor.floor_point`.) Runs on the app's event thread."""

from __future__ import annotations

from typing import Any

PANEL_HZ = 6.0  # how often read-outs and charts refresh


#: A notice stays at least this long (s), longer when it has more to read: one second for every
#: READING_WORDS words (about 200 words a minute), at most LONGEST (a pointer over it holds it open).
SHORTEST, READING_WORDS, LONGEST = 5.0, 3.5, 30.0


def reading_seconds(title: str, body: str, least: float = SHORTEST) -> float:
    """How long a notice stays: time to read it, e.g. 5 s for one line and 25 s for the 89 words a drawn
    F's *Goal changed* says (issue 56, item 1)."""
    return min(LONGEST, max(least, len(f"{title} {body}".split()) / READING_WORDS))


def notify_error(client: Any, title: str, body: str) -> None:
    if client is not None:
        client.add_notification(title, body, color="red", auto_close_seconds=reading_seconds(title, body, 10.0))


def notify(client: Any, title: str, body: str, color: str = "blue") -> None:
    if client is not None:
        client.add_notification(title, body, color=color, auto_close_seconds=reading_seconds(title, body))
