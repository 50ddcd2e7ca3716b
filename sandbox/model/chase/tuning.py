"""Chase's numbers: how it shapes the band near the goal and how long it holds.

They were chosen by trying a few values on seeds 0, 1 and 100-103, never on
the evaluation's seeds' results as a target (the trials are in
``docs/design-chase.md``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Sculpting:
    """How the closed loop shapes the band near the goal and holds it (lengths in metres)."""

    #: Sculpt only while the outline is at most this far from the goal.
    start: float = 1.5
    #: Radius of the neighbourhood of a goal edge point in which boxes are counted.
    near: float = 1.0
    #: How far the band moves toward the goal where boxes spill out...
    press: float = 0.45
    #: ...but never nearer the goal edge than this (a robot's centre; its radius is 0.25).
    closest: float = 0.2
    #: Boxes outside the goal within ``near`` of an edge point that make it spill.
    spill: int = 2
    #: Boxes fewer than a full pile's within ``near`` of an edge point that make it lack...
    lack: int = 2
    #: ...or this share of a full pile missing: at a sharp tip a full pile holds only two or three.
    lack_share: float = 0.5
    #: Area fraction of a full pile: piles pressed into a circle reach 0.85-0.87.
    packing: float = 0.85
    #: Lights within this distance of a lacking band point are off.
    dark: float = 0.8
    #: Spacing of the band's points while sculpting.
    spacing: float = 0.5
    #: World steps between two looks at the pile while holding.
    check: int = 500
    #: Boxes that must arrive in the goal per check to keep holding for progress.
    gain: int = 2
    #: Keep holding while fewer boxes than this are out of the robots' reach...
    stay: int = 5
    #: ...and extend no hold past this many steps.
    longest: int = 20000


SCULPTING = Sculpting()
