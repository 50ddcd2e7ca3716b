"""Which lights a band along an outline turns on (flat arrays, one boolean per
light centre), and the ones the no-corners strategy turns off again."""

from __future__ import annotations

import numpy as np

from sandbox.model.config import Config
from sandbox.shapes import geometry

#: Lights exactly ``band`` from the outline are in it, whatever the rounding.
_EDGE = 1e-9


def along(centres: np.ndarray, outline: np.ndarray, band: float) -> np.ndarray:
    """The lights within ``band`` of the closed polygon ``outline``."""
    return geometry.distance_to_outline(centres, outline) <= band + _EDGE


def around(centres: np.ndarray, centre: np.ndarray, radius: float, band: float) -> np.ndarray:
    """The lights within ``band`` of the circle (measured on the circle itself, not a polygon)."""
    return np.abs(np.hypot(*(centres - centre).T) - radius) <= band + _EDGE


def darken_corners(on: np.ndarray, centres: np.ndarray, corners: np.ndarray, fraction: float,
                   config: Config) -> np.ndarray:
    """The no-corners strategy: ``on`` with the lit lights nearest ``corners`` switched off."""
    lit = np.flatnonzero(on)
    off = no_corners_count(fraction, len(lit), config.no_corners_count)
    if off == 0:
        return on
    if config.no_corners_count == "at-least":
        # The program breaks ties by its light index, x + y * n (lit lists ix * n + iy).
        n = config.lights_per_side
        lit = lit[np.argsort((lit % n) * n + lit // n, kind="stable")]
    d = np.hypot(*(centres[lit, None, :] - corners[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    on = on.copy()
    # Rounded so that equally near lights tie exactly, whatever order the
    # file lists its vertices in; ties then go by light index.
    on[lit[np.argsort(np.round(d, 9), kind="stable")[:off]]] = False
    return on


def no_corners_count(fraction: float, lit: int, rule: str) -> int:
    """How many of ``lit`` lights the no-corners strategy turns off."""
    if rule == "round":
        return int(round(fraction * lit))
    # The program turns lights off while (turned off) / lit < fraction.
    off = 0
    while off < lit and off / lit < fraction:
        off += 1
    return off
