"""The compact observation: a fixed-size vector of fractions an agent can learn from.

The world's full state (hundreds of positions) changes size with the
populations and means little to a small policy. What the paper's question
needs is where the boxes are relative to the goal, where the robots are (the
light steers them, it does not push boxes), how charged they are and how
much time is left. Every entry is in [0, 1]:

* ``boxes inside``, ``boxes 0-0.5 m``, ... ``boxes > 16 m``: the fraction of
  boxes in the goal and at each distance band outside it (they sum to 1);
  the first is the fraction in the goal the reward counts;
* ``robots inside`` ... ``robots > 16 m``: the same for the robots;
* ``mean charge``: the robots' mean charge over their capacity;
* ``time``: the fraction of the episode's world steps done;
* with the outline action, the knobs of the last action (zeros before the first).

:func:`feature_names` gives the names in order, so a policy can be read.
"""

from __future__ import annotations

import numpy as np

from sandbox.model.goal import Goal

#: Upper edges (m) of the distance bands outside the goal; beyond the last is one more band.
DISTANCE_EDGES = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)


def _band_labels() -> list[str]:
    lows = (0.0,) + DISTANCE_EDGES[:-1]
    return ["inside"] + [f"{lo:g}-{hi:g} m" for lo, hi in zip(lows, DISTANCE_EDGES)] + [f"> {DISTANCE_EDGES[-1]:g} m"]


def feature_names(knobs: tuple[str, ...] = ()) -> list[str]:
    """The observation's entries, in order (``knobs``: the action's, when it is reported back)."""
    bands = _band_labels()
    return ([f"boxes {b}" for b in bands] + [f"robots {b}" for b in bands] + ["mean charge", "time"]
            + [f"last {k}" for k in knobs])


def distance_histogram(points: np.ndarray, goal: Goal) -> np.ndarray:
    """The fraction of ``points`` inside the goal and in each distance band outside it (zeros if none)."""
    counts = np.zeros(len(DISTANCE_EDGES) + 2)
    if not len(points):
        return counts
    inside = goal.contains(points)
    outside = goal.distance(points[~inside])
    counts[0] = inside.sum()
    # Band i + 1 holds distances in (edge[i - 1], edge[i]]; a box touching the goal's edge from outside counts
    # in the first band.
    counts[1:] = np.bincount(np.searchsorted(DISTANCE_EDGES, outside, side="left"), minlength=len(DISTANCE_EDGES) + 1)
    return counts / len(points)


def observe(sim, time_fraction: float, knobs: np.ndarray | None = None) -> np.ndarray:
    """The observation vector of a simulation (see the module docstring), float32."""
    capacity = sim.config.capacity
    charges = sim.robot_charges
    mean_charge = float(np.mean(charges)) / capacity if capacity > 0 and len(charges) else 0.0
    parts = [distance_histogram(sim.box_positions, sim.goal), distance_histogram(sim.robot_positions, sim.goal),
             [mean_charge, time_fraction]]
    if knobs is not None:
        parts.append(knobs)
    return np.clip(np.concatenate(parts), 0.0, 1.0).astype(np.float32)
