"""Where a click on the page meets the floor: the one piece of camera geometry the panel and the
shape being drawn share. Pure function; any thread."""

from __future__ import annotations

import numpy as np


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
