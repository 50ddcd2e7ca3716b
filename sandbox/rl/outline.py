"""The low-dimensional action: the paper's controller's own knobs, turned into a light pattern.

The paper's controller (:mod:`sandbox.model.controller`) lights every light
within ``band`` of an outline: the goal (or a circle) scaled about the
assembly centre, reshaped by its strategies. It changes the scale on a fixed
schedule. Here an agent turns the same knobs itself at every update:

==============  =====================================================================
``size``        0 = the smallest outline (one robot diameter around the goal), 1 = the
                largest; linear in scale, as the controller's ``progress``
``flare``       0..1 = flare amount 0 .. :data:`FLARE_HIGH` (twice the amount the
                strategy takes when switched on)
``circle``      at least 0.5: light a circle of the goal's area times the scale instead
                of the polygon (the paper text's reading of *switch to circle*)
``no_corners``  0..1 = fraction 0 .. 0.95 of the band's lights nearest convex corners
                that stay dark
==============  =====================================================================

Every knob is in [0, 1], the range RL libraries expect. On a circle goal only
``size`` changes anything: there are no corners to flare or darken.

This module builds on the public functions the controller is built from
(:mod:`~sandbox.model.outlines` for the sizes, :mod:`~sandbox.model.band` for
which lights a band lights and which no corners darkens) and never drives a
controller, so it needs no hook in it. A test pins its pattern to the
controller's own at the controller's first size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.model import band, outlines
from sandbox.model.config import STRATEGIES, STRATEGY_DEFAULTS, Config
from sandbox.model.goal import Goal
from sandbox.model.lights import light_centres

KNOBS = ("size", "flare", "circle", "no_corners")
#: The flare amount at flare knob 1: twice the strategy's amount when switched on (1.75).
FLARE_HIGH = 2.0 * STRATEGY_DEFAULTS["flare"]
#: The largest no-corners fraction (at 1 the whole band would be dark).
NO_CORNERS_HIGH = next(s.high for s in STRATEGIES if s.name == "no_corners")
#: Flare amounts are rounded to the panel slider's step, so the outlines of
#: the amounts an agent tries can be kept (a few dozen at most).
FLARE_STEP = next(s.step for s in STRATEGIES if s.name == "flare")


@dataclass(frozen=True)
class Knobs:
    """One setting of the outline, in the strategies' own units."""

    size: float = 1.0
    flare: float = 0.0
    circle: bool = False
    no_corners: float = 0.0

    @classmethod
    def from_action(cls, action: np.ndarray) -> "Knobs":
        """The knobs for an action of four values in [0, 1] (clipped there), in :data:`KNOBS` order."""
        size, flare, circle, no_corners = np.clip(np.asarray(action, dtype=float).reshape(len(KNOBS)), 0.0, 1.0)
        return cls(float(size), float(flare) * FLARE_HIGH, bool(circle >= 0.5), float(no_corners) * NO_CORNERS_HIGH)


class OutlinePainter:
    """Turns :class:`Knobs` into the light pattern for one configuration and goal."""

    def __init__(self, config: Config, goal: Goal):
        self.config, self.goal = config, goal
        self.centres = light_centres(config).reshape(-1, 2)
        self._sizes: dict[float, outlines.Sizing] = {}

    def sizes(self, flare: float) -> outlines.Sizing:
        """The goal's outline family (the controller's) for a flare amount (rounded to
        :data:`FLARE_STEP`), computed once."""
        key = round(round(flare / FLARE_STEP) * FLARE_STEP, 6)
        if key not in self._sizes:
            self._sizes[key] = outlines.sizing_for(self.config, self.goal, key)
        return self._sizes[key]

    def pattern(self, knobs: Knobs) -> np.ndarray:
        """The intensities, (n, n) indexed [ix, iy]: ``light_intensity`` on the band, 0 elsewhere."""
        cfg, goal = self.config, self.goal
        sizes = self.sizes(knobs.flare)
        size = sizes.smallest + knobs.size * (sizes.largest - sizes.smallest)
        if goal.is_circle or (knobs.circle and sizes.switchable):
            on = band.around(self.centres, goal.centre, sizes.circle_radius(size), cfg.band)
        else:
            on = sizes.lit(self.centres, size, cfg.band)
            corners = sizes.corners(size)
            if knobs.no_corners > 0 and len(corners):
                on = band.darken_corners(on, self.centres, corners, knobs.no_corners, cfg)
        n = cfg.lights_per_side
        return (on * cfg.light_intensity).reshape(n, n)
