"""Build the goal by hand: a timed round scored against the paper's controller (issue 25, item 3).

A round starts a new world from :data:`ROUND_SEED` and gives the lights to
a person (:mod:`sandbox.model.lamp`) for :data:`ROUND_STEPS` world steps.
Its score is the share of boxes in the goal at its last sample; the
reference is the paper's controller's share in the same world (same
configuration and seed) after the same number of steps, computed here,
headless, so that the comparison is honest.
"""

from __future__ import annotations

import numpy as np

from sandbox.model.config import Config

#: A round's length in world steps: 11 minutes of simulated time, about a minute of play.
ROUND_STEPS = 20_000
#: The seed every round starts from (the paper's evaluations' first).
ROUND_SEED = 0


def paper_share(config: Config, seed: int, steps: int, shape: np.ndarray | None | str = "from-config") -> float:
    """The paper's controller's share of boxes in the goal after ``steps`` world steps of the world
    built from ``config``, ``seed`` and ``shape`` (the goal's vertices as given, None for the circle),
    as a live round runs it (open-ended)."""
    from sandbox.model.simulation import Simulation  # here: the web server imports this module, steps no world

    sim = Simulation(config, seed=seed, shape=shape, open_ended=True)
    sim.step(steps)
    return float(sim.measure().fraction_in_goal)
