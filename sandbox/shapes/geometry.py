"""Pure polygon geometry: areas, angles, distances, inside tests, simplifying. Used by the shapes'
checks, the model (the goal, the outlines, the controller, the metrics) and the drawing panel, so it
sits below them all and imports none of them.

Polygons are float arrays of shape (n, 2), the last vertex joined back to the
first; either orientation is accepted everywhere.
"""

from __future__ import annotations

import math

import numpy as np
from shapely.geometry import Polygon

from sandbox.lazy_numba import compiled_at_first_use


def signed_area(vertices: np.ndarray) -> float:
    """Shoelace area: positive for counter-clockwise vertices."""
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def centroid(vertices: np.ndarray) -> np.ndarray:
    """Area centroid of a simple polygon."""
    x, y = vertices[:, 0], vertices[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = cross.sum() / 2.0
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * a)


def interior_angles(vertices: np.ndarray) -> np.ndarray:
    """Interior angle at each vertex in degrees (0, 360); > 180 is a reflex corner.

    Independent of the order the vertices are listed in: the polygon's own
    orientation (sign of its area) decides which side is inside.
    """
    v = np.asarray(vertices, dtype=float)
    to_prev = np.roll(v, 1, axis=0) - v
    to_next = np.roll(v, -1, axis=0) - v
    # Angle swept from the edge to the next vertex round to the edge to the
    # previous vertex, counter-clockwise: the interior angle of a CCW polygon.
    turn = np.degrees(np.arctan2(to_prev[:, 1], to_prev[:, 0]) - np.arctan2(to_next[:, 1], to_next[:, 0]))
    turn = np.mod(turn, 360.0)
    return turn if signed_area(v) > 0 else 360.0 - turn


def fit_to_area(vertices: np.ndarray, area: float, centre: np.ndarray) -> np.ndarray:
    """Translate so the centroid is at ``centre`` and scale to the given area."""
    v = np.asarray(vertices, dtype=float)
    rel = v - centroid(v)
    return centre + rel * math.sqrt(area / abs(signed_area(v)))


def regular_polygon(radius: float, n: int, centre=(0.0, 0.0)) -> np.ndarray:
    """A counter-clockwise regular polygon (used to draw and test circles)."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    return np.column_stack([centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)])


def flare(relative: np.ndarray, amount: float) -> tuple[np.ndarray, np.ndarray]:
    """The flare strategy (SPEC §5) on a polygon given relative to its centre.

    Inserts a vertex at the midpoint of every edge, then pushes each original
    corner away from the centre by ``max(1, 90 * amount / angle)``; reflex
    corners are left where they are. Returns the new vertices and a boolean
    mask of which of them are original corners.
    """
    v = np.asarray(relative, dtype=float)
    corners = v * flare_factors(v, amount)[:, None]
    mids = 0.5 * (v + np.roll(v, -1, axis=0))
    out = np.empty((2 * len(v), 2))
    out[0::2] = corners
    out[1::2] = mids
    is_corner = np.zeros(2 * len(v), dtype=bool)
    is_corner[0::2] = True
    return out, is_corner


def flare_factors(vertices: np.ndarray, amount: float) -> np.ndarray:
    """How far flare pushes each corner out (1 for reflex corners)."""
    angles = interior_angles(vertices)
    return np.where(angles < 180.0, np.maximum(1.0, 90.0 * amount / angles), 1.0)


def distances_to_edges(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Distance from each point (m, 2) to each edge vertices[i] -> vertices[i+1], shape (m, n)."""
    p = np.asarray(points, dtype=float)[:, None, :]
    a = np.asarray(vertices, dtype=float)[None, :, :]
    b = np.roll(a, -1, axis=1)
    ab = b - a
    length2 = np.maximum((ab**2).sum(-1), 1e-300)
    t = np.clip(((p - a) * ab).sum(-1) / length2, 0.0, 1.0)
    nearest = a + t[..., None] * ab
    return np.sqrt(((p - nearest) ** 2).sum(-1))


def nearest_on_outline(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """For each point (m, 2), the nearest point on the closed polygon's edges (the foot of
    :func:`distances_to_edges`' nearest edge)."""
    a = polygon[None, :, :]
    edge = np.roll(polygon, -1, axis=0)[None, :, :] - a
    p = points[:, None, :]
    along = np.clip(((p - a) * edge).sum(-1) / np.maximum((edge * edge).sum(-1), 1e-300), 0.0, 1.0)
    foot = a + along[..., None] * edge
    nearest = np.hypot(*(p - foot).transpose(2, 0, 1)).argmin(axis=1)
    return foot[np.arange(len(points)), nearest]


def distance_to_outline(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Distance from each point (m, 2) to the closed polyline through ``vertices``.

    The controller asks this for all 4,096 lights at every update; with numpy's
    (m, n, 2) temporaries that took 11 ms for a 49-edge outline, as long as 60
    world steps. The compiled loop does the same arithmetic, in the same order,
    as :func:`distances_to_edges`, so the answers are the same to the bit."""
    p = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
    v = np.ascontiguousarray(vertices, dtype=float).reshape(-1, 2)
    if len(v) == 0:
        return np.full(len(p), np.inf)
    return _compiled_min_distance(p, v)


def _min_distance_to_closed_polyline(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    m, n = points.shape[0], vertices.shape[0]
    out = np.empty(m)
    for i in range(m):
        px, py = points[i, 0], points[i, 1]
        best = np.inf
        for j in range(n):
            ax, ay = vertices[j, 0], vertices[j, 1]
            k = j + 1 if j + 1 < n else 0
            abx, aby = vertices[k, 0] - ax, vertices[k, 1] - ay
            length2 = max(abx * abx + aby * aby, 1e-300)
            t = min(max(((px - ax) * abx + (py - ay) * aby) / length2, 0.0), 1.0)
            dx, dy = px - (ax + t * abx), py - (ay + t * aby)
            d = math.sqrt(dx * dx + dy * dy)
            if d < best:
                best = d
        out[i] = best
    return out


#: The compiled loop, compiled at its first use: the server needs it only once a drawn goal is previewed
#: (its outlines).
_compiled_min_distance = compiled_at_first_use(_min_distance_to_closed_polyline)


#: points_in_polygon works on at most this many (point, edge) pairs at once: its temporaries stay
#: near 8 MB each however many points and edges (the offset outline asks 16,641 points of the spawn
#: square against a 500-vertex goal: 330 MB at once).
_PAIRS_AT_ONCE = 1 << 20


def points_in_polygon(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Even-odd test for each point (m, 2); vectorised over points and edges, a block of points at a
    time (each point's answer is the same, bit for bit, whatever the blocks)."""
    p = np.asarray(points, dtype=float)
    a = np.asarray(vertices, dtype=float)
    b = np.roll(a, -1, axis=0)
    rows = max(1, _PAIRS_AT_ONCE // max(len(a), 1))
    if len(p) <= rows:
        return _points_in_polygon(p, a, b)
    return np.concatenate([_points_in_polygon(p[i:i + rows], a, b) for i in range(0, len(p), rows)])


def _points_in_polygon(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    x, y = p[:, 0:1], p[:, 1:2]
    ax, ay, bx, by = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    straddles = (ay > y) != (by > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        cross_x = ax + (y - ay) * (bx - ax) / (by - ay)
    return ((straddles & (x < cross_x)).sum(axis=1) % 2) == 1


def simplify(vertices: np.ndarray, tolerance: float) -> np.ndarray:
    """The outline with vertices dropped wherever that moves it by less than
    ``tolerance`` (Douglas-Peucker, keeping it a simple polygon), in the
    original orientation."""
    vertices = np.asarray(vertices, dtype=float)
    simpler = Polygon(vertices).simplify(tolerance, preserve_topology=True)
    if simpler.is_empty or simpler.geom_type != "Polygon":
        return vertices
    coords = np.asarray(simpler.exterior.coords)[:-1]
    if (signed_area(coords) > 0) != (signed_area(vertices) > 0):
        coords = coords[::-1]
    return coords
