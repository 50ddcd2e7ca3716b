"""Be the light: lights that a person sets, by clicks on the floor (issue 25).

The lamp is a light program like any other (:mod:`sandbox.model.programs`)
whose pattern comes from outside, between updates: the robots follow,
charge and drain as always. A click does one of three things (``mode``):

- ``lamp``: the lights within ``radius`` of the click are on, all others
  off (a lamp moved to where one clicked);
- ``paint``: the lights within ``radius`` of the click come on, the others
  stay as they were (a brush);
- ``erase``: the lights within ``radius`` of the click go off.
"""

from __future__ import annotations

import threading

import numpy as np

from sandbox.model.config import Config
from sandbox.model.programs import LightProgram, Observation

#: A lamp's radius when none is asked for (m), and the range a page offers.
DEFAULT_RADIUS, SMALLEST_RADIUS, LARGEST_RADIUS = 4.0, 1.0, 12.0
#: What a click does.
LAMP, PAINT, ERASE = "lamp", "paint", "erase"
MODES = (LAMP, PAINT, ERASE)


class Lamp(LightProgram):
    """Lights set by clicks (see the module docstring); dark until the first one."""

    #: World steps between two looks at the clicks: 0.33 s of simulated time.
    every = 10

    def __init__(self, radius: float = DEFAULT_RADIUS):
        self.radius = float(radius)
        self._clicks: list[tuple[str, tuple[float, float], float]] = []
        self._pattern: np.ndarray | None = None
        self._changed = True
        self._lock = threading.Lock()

    def aim(self, x: float, y: float, radius: float | None = None, mode: str = LAMP) -> None:
        """A click at (x, y) (metres, the arena's frame): the lamp moves there, or the brush paints or
        erases there (``mode``); ``radius`` resizes the disc, within what a page offers."""
        if mode not in MODES:
            raise ValueError(f"unknown mode {mode!r}: one of {', '.join(MODES)}")
        with self._lock:
            if radius is not None:
                self.radius = float(np.clip(radius, SMALLEST_RADIUS, LARGEST_RADIUS))
            self._clicks.append((mode, (float(x), float(y)), self.radius))
            self._changed = True

    def reset(self, config: Config, goal: object) -> np.ndarray | None:
        super().reset(config, goal)
        with self._lock:
            self._changed = True
        return None

    def update(self, observation: Observation) -> np.ndarray | None:
        with self._lock:
            if not self._changed:
                return None  # the pattern stays
            self._changed = False
            clicks, self._clicks = self._clicks, []
        pattern = self._pattern
        if pattern is None or pattern.shape != observation.lights_shape:
            pattern = np.zeros(observation.lights_shape)
        for mode, centre, radius in clicks:
            disc = np.linalg.norm(observation.light_centres - np.asarray(centre), axis=-1) <= radius
            if mode == LAMP:
                pattern = disc.astype(float)
            else:
                pattern = np.where(disc, 1.0 if mode == PAINT else 0.0, pattern)
        self._pattern = pattern
        return pattern.copy()
