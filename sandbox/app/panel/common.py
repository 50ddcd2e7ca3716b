"""What every folder of the panel shares: notifications. (Where a click meets the floor is the view's:
:func:`sandbox.app.view.floor.floor_point`.) Runs on the app's event thread."""

from __future__ import annotations

from typing import Any

PANEL_HZ = 6.0  # how often read-outs and charts refresh


def notify_error(client: Any, title: str, body: str) -> None:
    if client is not None:
        client.add_notification(title, body, color="red", auto_close_seconds=10.0)


def notify(client: Any, title: str, body: str, color: str = "blue") -> None:
    if client is not None:
        client.add_notification(title, body, color=color, auto_close_seconds=5.0)
