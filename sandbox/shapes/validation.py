"""Is an outline usable as a goal? A simple polygon: at least three distinct
vertices, finite coordinates, a non-zero area, no edge crossing or touching
another, and not absurdly many vertices."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import MultiPoint, Polygon

from sandbox.shapes.errors import fail
from sandbox.shapes.geometry import distances_to_edges

MAX_VERTICES = 10_000
MIN_RELATIVE_AREA = 1e-9       # area / (bounding-box size)^2 below this is "zero"
#: Coordinates beyond this are refused: only the shape matters, and squares of
#: larger numbers overflow double precision.
MAX_COORDINATE = 1e12
#: Edges whose crossings are listed at once when looking for the first: at most this many times
#: MAX_VERTICES pairs in memory.
QUERY_EDGES = 32


def validate_polygon(vertices, source: str, line_numbers=None) -> np.ndarray:
    """Check an outline and return it as float64 (n, 2), consecutive repeats dropped.

    ``line_numbers`` (one per vertex, optional) makes messages name file lines;
    otherwise they name 1-based vertex numbers.
    """
    try:
        array = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise fail(source, "vertices must be numbers") from None
    if array.ndim != 2 or array.shape[1] != 2:
        raise fail(source, "vertices must be (x, y) pairs")
    labels = list(line_numbers) if line_numbers is not None else list(range(1, len(array) + 1))
    kind = "line" if line_numbers is not None else "vertex"
    if len(array) > MAX_VERTICES:
        raise fail(source, f"has {len(array):,} vertices; at most {MAX_VERTICES:,} are "
                    "supported (simplify the outline)")
    bad = np.flatnonzero(~np.isfinite(array).all(axis=1))
    if bad.size:
        raise fail(source, f"{array[bad[0]].tolist()} is not a pair of finite numbers",
                    f"{kind} {labels[bad[0]]}")
    huge = np.flatnonzero((np.abs(array) > MAX_COORDINATE).any(axis=1))
    if huge.size:
        raise fail(source, f"{array[huge[0]].tolist()} is too large: coordinates must be within "
                   f"+-{MAX_COORDINATE:g} (only the outline's shape matters; scale it down)",
                   f"{kind} {labels[huge[0]]}")
    keep = np.ones(len(array), dtype=bool)
    keep[1:] = np.any(array[1:] != array[:-1], axis=1)
    last = np.flatnonzero(keep)[-1] if len(array) else 0
    if last > 0 and np.array_equal(array[last], array[0]):
        keep[last] = False                 # the closing repeat of the first vertex
    array, labels = array[keep], [label for label, k in zip(labels, keep) if k]
    distinct = len(np.unique(array, axis=0))
    if distinct < 3:
        raise fail(source, f"has only {distinct} distinct vertices; a polygon needs at least 3")
    _check_area(array, source, MultiPoint(array).convex_hull.area, "all vertices lie on one line")
    _check_repeats(array, source, labels, kind)
    _check_simple(array, source, labels, kind)
    _check_area(array, source, Polygon(array).area, "the outline encloses almost nothing")
    return array


def _check_area(array: np.ndarray, source: str, area: float, why: str) -> None:
    size = float(np.ptp(array, axis=0).max())
    if size == 0.0 or area / size ** 2 < MIN_RELATIVE_AREA:
        raise fail(source, f"the polygon has zero area ({why})")


def _check_repeats(array: np.ndarray, source: str, labels: list, kind: str) -> None:
    """A vertex visited twice makes the outline touch itself there."""
    _, first, inverse = np.unique(array, axis=0, return_index=True, return_inverse=True)
    repeats = np.flatnonzero(first[inverse.ravel()] != np.arange(len(array)))
    if repeats.size:
        i, j = int(repeats[0]), int(first[inverse.ravel()[repeats[0]]])
        x, y = array[i]
        raise fail(source, f"repeats {kind} {labels[j]} at ({x:.6g}, {y:.6g}); the outline "
                    "must not touch itself", f"{kind} {labels[i]}")


def _check_simple(array: np.ndarray, source: str, labels: list, kind: str) -> None:
    """The outline must not cross or touch itself. Where it does is found from
    the edges themselves (shapely's is_valid_reason says it only in prose)."""
    if Polygon(array).is_valid:
        return
    crossing = _first_self_contact(array)
    if crossing is None:
        raise fail(source, f"the outline is not a simple polygon ({shapely.is_valid_reason(Polygon(array))})")
    i, j, point, proper = crossing
    x, y = point
    verb = "crosses itself near" if proper else "touches itself at"
    edges = sorted({i, j} | set(_edges_near(array, point)))[:4]
    plural = "lines" if kind == "line" else "vertices"
    names = [f"{labels[e]}-{labels[(e + 1) % len(labels)]}" for e in edges]
    names = ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else "".join(names)
    raise fail(source, f"the outline {verb} ({x:.6g}, {y:.6g}) (edges at {plural} {names})")


def _first_self_contact(array: np.ndarray) -> tuple[int, int, tuple[float, float], bool] | None:
    """Two edges that meet though they should not: (edge i, edge j, a point where
    they meet, whether they properly cross), the pair with the lowest indices."""
    n = len(array)
    ends = np.stack([array, np.roll(array, -1, axis=0)], axis=1)
    edges = shapely.linestrings(ends)
    tree = shapely.STRtree(edges)
    # Edges are asked about a few at a time: a star of 10,000 points has 50 million crossing pairs,
    # which asked all at once took minutes and gigabytes to list. The first few alone, then up to
    # QUERY_EDGES at a time.
    start, count = 0, 1
    while start < n:
        a, b = tree.query(edges[start:start + count], predicate="intersects")
        a = a + start
        later = b > a
        a, b = a[later], b[later]
        for k in np.lexsort((b, a)).tolist():
            i, j = int(a[k]), int(b[k])
            meeting = shapely.intersection(edges[i], edges[j])
            if (j - i) % n in (1, n - 1):  # neighbours share a corner; only an overlap counts
                if meeting.geom_type == "Point":
                    continue
            point = meeting.representative_point()
            proper = bool(shapely.crosses(edges[i], edges[j]))
            return i, j, (point.x, point.y), proper
        start, count = start + count, min(count * 2, QUERY_EDGES)
    return None


def _edges_near(array: np.ndarray, point, limit: int = 4) -> list[int]:
    """Indices i of edges array[i] -> array[i+1] passing within a hair of point."""
    distance = distances_to_edges(np.asarray(point, dtype=float)[None, :], array)[0]
    tolerance = 1e-7 * max(float(np.ptp(array, axis=0).max()), 1e-300)
    return sorted(np.flatnonzero(distance <= tolerance).tolist())[:limit]


