"""What every folder of the panel shares: notifications and clicks on the floor."""

from __future__ import annotations

from typing import Any

import numpy as np

PANEL_HZ = 6.0  # how often read-outs and charts refresh


def notify_error(client: Any, title: str, body: str) -> None:
    if client is not None:
        client.add_notification(title, body, color="red", auto_close_seconds=10.0)


def notify(client: Any, title: str, body: str, color: str = "blue") -> None:
    if client is not None:
        client.add_notification(title, body, color=color, auto_close_seconds=5.0)


def floor_point(origin: tuple, direction: tuple) -> tuple[float, float] | None:
    """Where a click ray meets the floor (z = 0), or None if it misses."""
    o, d = np.asarray(origin, float), np.asarray(direction, float)
    if abs(d[2]) < 1e-9:
        return None
    t = -o[2] / d[2]
    if t < 0:
        return None
    p = o + t * d
    return float(p[0]), float(p[1])
