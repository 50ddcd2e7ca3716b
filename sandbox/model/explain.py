"""Why a run ended where it did: where the boxes outside the goal lie, in words.

A designer who sees "78 % in the goal" wants to know where the other 22 %
are. Each box outside the goal is put in one place, the first that fits:

1. **near the goal**: within :data:`NEAR_BOX_WIDTHS` box widths of its edge
   (the band brought it most of the way);
2. **heaped in a corner** of the construction area: in one of its four
   corner squares (a quarter of its side each way), when that corner holds
   at least :data:`HEAP_SHARE` of the strays and :data:`HEAP_LEAST` boxes;
3. **against the wall** of the construction area: within
   :data:`WALL_BOX_WIDTHS` box widths of it;
4. **elsewhere** in the construction area.

And one line on what 100 % would mean: the goal is made exactly as large as
the boxes' total area, so every box in it is perfect packing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.shapes.geometry import distance_to_outline

NEAR_BOX_WIDTHS = 3.0
WALL_BOX_WIDTHS = 1.5
HEAP_SHARE = 0.25
HEAP_LEAST = 5
#: The corners as (sign of x, sign of y) from the centre, and their names seen from above.
CORNERS = {(-1, -1): "lower-left", (1, -1): "lower-right", (-1, 1): "upper-left", (1, 1): "upper-right"}

PERFECT_PACKING = ("The goal is exactly as large as the boxes' total area, so 100 % would mean perfect packing: "
                   "a real swarm stops short of it.")


@dataclass(frozen=True)
class Strays:
    """The boxes outside the goal and where they lie (each counted once)."""

    indices: np.ndarray  # of the boxes outside the goal
    near_goal: int
    heaps: tuple[tuple[str, int], ...]  # (corner, boxes), the fullest first
    against_wall: int
    elsewhere: int

    @property
    def count(self) -> int:
        return len(self.indices)


def place_strays(box_positions: np.ndarray, in_goal: np.ndarray, goal_outline: np.ndarray, centre: float,
                 construction_size: float, box_width: float) -> Strays:
    """Where the boxes outside the goal lie (see the module's docstring)."""
    positions = np.asarray(box_positions, float).reshape(-1, 2)
    outside = np.flatnonzero(~np.asarray(in_goal, bool))
    if len(outside) == 0:
        return Strays(outside, 0, (), 0, 0)
    p = positions[outside]
    near = distance_to_outline(p, goal_outline) <= NEAR_BOX_WIDTHS * box_width
    rel = p - centre
    half = construction_size / 2.0
    in_corner = np.all(np.abs(rel) >= half / 2.0, axis=1) & ~near
    heaps, heaped = [], np.zeros(len(p), bool)
    for (sx, sy), name in CORNERS.items():
        here = in_corner & (np.sign(rel[:, 0]) == sx) & (np.sign(rel[:, 1]) == sy)
        n = int(here.sum())
        if n >= HEAP_LEAST and n >= HEAP_SHARE * len(p):
            heaps.append((name, n))
            heaped |= here
    wall = (half - np.abs(rel).max(axis=1) <= WALL_BOX_WIDTHS * box_width) & ~near & ~heaped
    return Strays(outside, int(near.sum()), tuple(sorted(heaps, key=lambda h: -h[1])), int(wall.sum()),
                  int(len(p) - near.sum() - heaped.sum() - wall.sum()))


def strays_in_words(strays: Strays, box_width: float) -> str:
    """One sentence: where the boxes outside the goal lie."""
    if strays.count == 0:
        return "Every box is in the goal."
    parts = []
    if strays.near_goal:
        parts.append(f"{strays.near_goal} near the goal (within {NEAR_BOX_WIDTHS * box_width:.1f} m of its edge)")
    parts += [f"{n} heaped in the {corner} corner of the construction area" for corner, n in strays.heaps]
    if strays.against_wall:
        parts.append(f"{strays.against_wall} against the construction area's wall")
    if strays.elsewhere:
        parts.append(f"{strays.elsewhere} scattered elsewhere in the construction area")
    return f"Of the {strays.count} {'box' if strays.count == 1 else 'boxes'} outside the goal: " + ", ".join(parts) + "."
