"""Chase's outline near the goal: the goal grown, pressed in where boxes spill
out and dark where the goal lacks them (see :mod:`sandbox.model.chase`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from sandbox.model.chase.tuning import SCULPTING, Sculpting
from sandbox.shapes.geometry import nearest_on_outline

#: Segments per quarter circle of an offset's round corners.
ROUND_SEGMENTS = 4


def offset_outline(polygon: np.ndarray, distance: float) -> np.ndarray:
    """The polygon grown by ``distance`` with round corners (vertices, not closed)."""
    grown = Polygon(polygon).buffer(max(distance, 0.0), quad_segs=ROUND_SEGMENTS, join_style="round")
    if grown.geom_type != "Polygon":  # cannot happen for a simple polygon grown outward; be safe
        grown = grown.convex_hull
    return np.asarray(grown.exterior.coords)[:-1]


def corner_points(polygon: np.ndarray, corners: np.ndarray, distance: float) -> np.ndarray:
    """Where the grown outline passes the polygon's convex ``corners`` (a boolean mask):
    each corner moved ``distance`` out along its outward bisector."""
    to_prev = _unit(polygon - np.roll(polygon, 1, axis=0))
    to_next = _unit(polygon - np.roll(polygon, -1, axis=0))
    return (polygon + distance * _unit(to_prev + to_next))[corners]


def densify(vertices: np.ndarray, spacing: float) -> np.ndarray:
    """The closed polygon with extra vertices so no edge is longer than ``spacing``."""
    ends = np.roll(vertices, -1, axis=0)
    pieces = np.maximum(1, np.ceil(np.hypot(*(ends - vertices).T) / spacing).astype(int))
    starts = np.repeat(vertices, pieces, axis=0)
    steps = np.repeat(ends - vertices, pieces, axis=0)
    fraction = np.concatenate([np.arange(k) / k for k in pieces])
    return starts + fraction[:, None] * steps


def full_counts(goal: np.ndarray, points: np.ndarray, radius: float, box_area: float, packing: float) -> np.ndarray:
    """Boxes a full pile holds within ``radius`` of each point, inside the goal."""
    discs = shapely.buffer(shapely.points(points), radius, quad_segs=16)
    return shapely.area(shapely.intersection(Polygon(goal), discs)) * packing / box_area


@dataclass(frozen=True)
class Sculpted:
    """The band's outline and the points whose lights stay dark."""

    outline: np.ndarray
    dark: np.ndarray  # (m, 2), possibly empty


def sculpt(goal: np.ndarray, distance: float, boxes: np.ndarray, in_goal: np.ndarray, box_area: float,
           tuning: Sculpting = SCULPTING) -> Sculpted:
    """The goal grown by ``distance``, moved in where boxes spill out, dark where the goal lacks boxes.

    ``goal`` is the goal polygon, ``boxes`` the box centres and ``in_goal``
    which of them lie in it. Beyond ``tuning.start`` the plain offset."""
    if distance > tuning.start or not len(boxes):
        return Sculpted(offset_outline(goal, distance), np.empty((0, 2)))
    band, edge, gap, outward, full = _band_near_goal(goal, distance, box_area, tuning)
    near = np.hypot(*(boxes[None, :, :] - edge[:, None, :]).transpose(2, 0, 1)) < tuning.near
    spilled = (near & ~in_goal[None, :]).sum(axis=1)
    held = (near & in_goal[None, :]).sum(axis=1)
    missing = full - held
    lacking = (spilled == 0) & ((missing >= tuning.lack) | (missing >= tuning.lack_share * full))
    gap = np.where(spilled >= tuning.spill, np.maximum(gap - tuning.press, tuning.closest), gap)
    return Sculpted(edge + gap[:, None] * outward, band[lacking])


def _band_near_goal(goal: np.ndarray, distance: float, box_area: float, tuning: Sculpting) -> tuple:
    """The geometry of the band at ``distance`` from the goal that the boxes do not change: its points,
    their nearest points on the goal's edge, the gap and outward direction between them, and the boxes
    a full pile holds there. A hold redraws the same band every update: it is computed once."""
    goal = np.ascontiguousarray(goal, dtype=float)
    return _band_of(goal.tobytes(), len(goal), distance, box_area, tuning)


@functools.lru_cache(maxsize=8)  # the last few bands: a hold's, and the contraction's last sizes
def _band_of(goal_bytes: bytes, vertices: int, distance: float, box_area: float, tuning: Sculpting) -> tuple:
    goal = np.frombuffer(goal_bytes, dtype=float).reshape(vertices, 2)
    band = densify(offset_outline(goal, distance), tuning.spacing)
    edge = nearest_on_outline(band, goal)
    away = band - edge
    gap = np.hypot(*away.T)
    outward = away / np.maximum(gap, 1e-12)[:, None]
    full = full_counts(goal, edge, tuning.near, box_area, tuning.packing)
    for array in (band, edge, gap, outward, full):
        array.flags.writeable = False  # shared by later calls
    return band, edge, gap, outward, full


def darken_near(on: np.ndarray, centres: np.ndarray, points: np.ndarray, radius: float) -> np.ndarray:
    """``on`` with the lights within ``radius`` of any of ``points`` switched off."""
    lit = np.flatnonzero(on)
    if not len(points) or not len(lit):
        return on
    # Only the lit lights can change: a band lights a few hundred of the grid's thousands.
    d = np.hypot(*(centres[lit, None, :] - points[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    out = np.array(on, dtype=bool)
    out[lit] = d >= radius
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.hypot(*v.T), 1e-12)[:, None]
