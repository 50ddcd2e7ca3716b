"""Be the light: a lamp that a person moves over the floor (issue 25).

The lamp is a light program like any other (:mod:`sandbox.model.programs`):
the lights within ``radius`` of its centre are on, all others off. Where
it is and how large come from outside, from clicks on the page, between
updates: the robots follow, charge and drain as always.
"""

from __future__ import annotations

import threading

import numpy as np

from sandbox.model.config import Config
from sandbox.model.programs import LightProgram, Observation

#: A lamp's radius when none is asked for (m), and the range a page offers.
DEFAULT_RADIUS, SMALLEST_RADIUS, LARGEST_RADIUS = 4.0, 1.0, 12.0


class Lamp(LightProgram):
    """A disc of lights, moved by :meth:`aim`; dark until it is first aimed."""

    #: World steps between two looks at where the lamp is: 0.33 s of simulated time.
    every = 10

    def __init__(self, radius: float = DEFAULT_RADIUS):
        self.centre: tuple[float, float] | None = None
        self.radius = float(radius)
        self._changed = True
        self._lock = threading.Lock()

    def aim(self, x: float, y: float, radius: float | None = None) -> None:
        """Move the lamp's centre to (x, y) (metres, the arena's frame), and resize it if asked."""
        with self._lock:
            self.centre = (float(x), float(y))
            if radius is not None:
                self.radius = float(np.clip(radius, SMALLEST_RADIUS, LARGEST_RADIUS))
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
            centre, radius = self.centre, self.radius
        if centre is None:
            return np.zeros(observation.lights_shape)
        distance = np.linalg.norm(observation.light_centres - np.asarray(centre), axis=-1)
        return (distance <= radius).astype(float)
