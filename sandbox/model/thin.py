"""Where a notched goal's band holds farther out: beside its thin parts, tips and corners (issue 42).

The lights are 2 m up and their glow is wide (``B = I / d^2``, ``d`` the 3-D
distance). At the press the band is one robot diameter (0.5 m) from the goal
all round, so a part of the goal lit from both sides is bright inside: on
the axis of a strip 2 m wide the two sides' glow adds up to 0.93 of the
band's brightness, on a strip 1.5 m wide to 1.08. The robots ride the
brightest light, so at the press they drive onto such a part and push its
boxes out. The W's top middle apex, an acute tip, was bare after every press
(seed 0, step 29,000: 10 robots and 3 boxes in its top 2.9 m²).

So on a notched goal each light has a **least distance**: the band there
stops contracting where a strip as wide as the goal behind the light, lit on
both sides, is at most :data:`AXIS_RATIO` as bright on its axis as on the
band, and holds there while the rest of the band goes on. The **width**
behind a light is twice the depth of the goal's deepest point within
:data:`WIDTH_WITHIN` of the light's nearest edge point. Measured that close,
no part looks wider than 2 m, so the band stops at least 0.65 m from a
notched goal everywhere (0.5 m without notches); a right-angled corner looks
1.41 m wide (its deepest point within 1 m is 0.71 m deep) and holds the band
at 0.95 m, an acute tip farther still.

Measured (seeds 0-3, 100,000 steps; ``docs/design-notches.md``): the
W 0.750 against 0.720 without it, the comb 0.754 against 0.749, and no
notched shape of the set or the templates lower. Measuring the width within
1.2 m or 1.6 m, or holding at 0.65 m all round and nowhere farther, did less.

It belongs to the notched goal's regime (``notches = "lit"``), where the band
moves at 0.4 of its pace near the goal and each press lasts 2.5 times as
long. A goal without notches comes to one robot diameter all round, as before.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
import shapely

from sandbox.model.config import Config
from sandbox.model.lights import brightness_kernel
from sandbox.shapes import geometry

#: The band holds where a strip of the goal's width behind it, lit on both sides, is at most this bright on
#: its axis against the band (below 1: the band stays the brightest line, with a margin).
AXIS_RATIO = 0.85
#: A light's part of the goal is measured within this distance (m) of its nearest edge point.
WIDTH_WITHIN = 1.0
#: The table of least distances covers widths up to this (m); wider parts are never held out.
WIDEST = 3.0
#: The table of least distances is worked out every this many metres of width and of distance.
_WIDTH_STEP = 0.1
_DISTANCE_STEP = 0.05
#: The goal's depth is sampled on a grid this fine (m).
_DEPTH_SPACING = 0.1
#: Lights farther than this (m) from the goal are never near a press.
_NEAR_PRESS = 4.0
#: The line of lights a strip's side is lit by reaches this many pitches each way.
_LINE_LIGHTS = 20


class Glow(NamedTuple):
    """What the lights' glow depends on (``Config``'s light fields)."""

    pitch: float
    height: float
    falloff: float
    angle: str

    @classmethod
    def of(cls, config: Config) -> "Glow":
        return cls(config.light_pitch, config.light_height, config.light_falloff, config.light_angle)


def strip_brightness(glow: Glow, offset: float) -> float:
    """The brightness, at a horizontal distance ``offset`` from it, of a straight line of lights one pitch
    apart (as the band beside a straight edge is)."""
    along = np.arange(-_LINE_LIGHTS, _LINE_LIGHTS + 1) * glow.pitch
    return float(brightness_kernel(np.full_like(along, offset), along, glow.height, glow.falloff, glow.angle).sum())


def axis_over_band(glow: Glow, width: float, distance: float) -> float:
    """For a strip of the goal ``width`` wide with the band ``distance`` from it on both sides: how bright
    the strip's axis is against the band itself."""
    half = width / 2.0 + distance
    axis = 2.0 * strip_brightness(glow, half)
    band = strip_brightness(glow, 0.0) + strip_brightness(glow, 2.0 * half)
    return axis / band


@functools.lru_cache(maxsize=16)
def _table(glow: Glow, smallest: float) -> tuple[np.ndarray, np.ndarray]:
    widths = np.arange(0.0, WIDEST + _WIDTH_STEP / 2, _WIDTH_STEP)
    distances = np.arange(smallest, smallest + WIDEST + _DISTANCE_STEP / 2, _DISTANCE_STEP)
    least = np.array([next((d for d in distances if axis_over_band(glow, w, d) <= AXIS_RATIO), distances[-1])
                      for w in widths])
    return widths, least


def least_distance(glow: Glow, widths: np.ndarray, smallest: float) -> np.ndarray:
    """The least distance the band comes to a part of each width: the smallest at or above ``smallest`` at
    which the part's axis is at most :data:`AXIS_RATIO` as bright as the band."""
    table_widths, table_least = _table(glow, float(smallest))
    return np.interp(np.asarray(widths, dtype=float), table_widths, table_least)


def local_widths(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """For each point on the goal's edge: twice the depth of the goal's deepest point within
    :data:`WIDTH_WITHIN` of it."""
    goal = shapely.Polygon(vertices)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    xs, ys = np.meshgrid(np.arange(low[0], high[0], _DEPTH_SPACING), np.arange(low[1], high[1], _DEPTH_SPACING))
    inside = np.stack([xs.ravel(), ys.ravel()], axis=-1)
    inside = inside[shapely.contains_xy(goal, inside[:, 0], inside[:, 1])]
    depth = geometry.distance_to_outline(inside, vertices)
    widths = np.zeros(len(points))
    for i, point in enumerate(points):
        near = np.hypot(*(inside - point).T) <= WIDTH_WITHIN
        widths[i] = 2.0 * depth[near].max() if near.any() else 0.0
    return widths


def hold_distances(glow: Glow, centres: np.ndarray, distances: np.ndarray, vertices: np.ndarray,
                   smallest: float) -> np.ndarray:
    """Each light's least band distance (``centres`` flat, ``distances`` their signed distances to the
    goal): ``smallest`` where the goal behind it is wide, farther beside a thin part or a tip."""
    least = np.full(len(centres), smallest)
    near = np.flatnonzero((distances > 0.0) & (distances < _NEAR_PRESS))
    if not len(near):
        return least
    least[near] = least_distance(glow, local_widths(nearest_edge_points(centres[near], vertices), vertices), smallest)
    return least


def nearest_edge_points(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """The point of the goal's edge nearest each point (GEOS's choice where two are equally near)."""
    # GEOS divides by zero inside shortest_line on some inputs in some processes (seen once in CI, never
    # alone); the result is checked, and any point it did not give is projected here instead.
    with np.errstate(divide="ignore", invalid="ignore"):
        found = shapely.get_coordinates(
            shapely.shortest_line(shapely.Polygon(vertices).exterior, shapely.points(points)))[0::2]
    bad = ~np.all(np.isfinite(found), axis=1)
    if bad.any():
        found[bad] = geometry.nearest_on_outline(points[bad], vertices)
    return found

