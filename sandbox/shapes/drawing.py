"""The pure parts of drawing a goal by hand: snapping a point to a grid,
reading typed or pasted coordinates, finding the edges of an outline that
cross or touch each other (to mark them while it is drawn), and which point
or edge a click on the floor is on.

Vertices are numbered from 1 and edge ``i`` runs from vertex ``i + 1`` to
the next, the closing edge from the last vertex back to the first: the
numbers the floor shows and :func:`sandbox.shapes.validate_polygon`'s
messages use.
"""

from __future__ import annotations

import json
import re

import numpy as np
import shapely

from sandbox.shapes.errors import fail, to_float
from sandbox.shapes.validation import MAX_VERTICES

SOURCE = "coordinates"
#: What the coordinates field takes, for hints and errors.
FORMATS_HINT = "x y per line, or x,y; x,y, or a JSON list [[x, y], ...]"

Point = tuple[float, float]


def snap(point, step: float) -> Point:
    """``point`` on the nearest node of a square grid of ``step`` metres (unchanged when step <= 0).
    Rounded to a nanometre so a 0.1 m grid gives 0.3, not 0.30000000000000004."""
    x, y = float(point[0]), float(point[1])
    if step <= 0:
        return x, y
    return (round(round(x / step) * step, 9) + 0.0, round(round(y / step) * step, 9) + 0.0)  # + 0.0: no -0.0


def without_repeats(points) -> list[Point]:
    """The outline without a point repeated right after itself, nor a last point that closes
    back onto the first: validation drops them too, and the floor should number what it keeps."""
    kept: list[Point] = []
    for x, y in points:
        if not kept or kept[-1] != (x, y):
            kept.append((float(x), float(y)))
    while len(kept) > 1 and kept[-1] == kept[0]:
        kept.pop()
    return kept


# ---------------------------------------------------------------- picking
def vertex_at(points, p, reach: float) -> int | None:
    """The index of the point of ``points`` nearest ``p``, if it is within ``reach`` metres."""
    v = np.asarray(points, dtype=float).reshape(-1, 2)
    if not len(v):
        return None
    distances = np.hypot(*(v - np.asarray(p, float)).T)
    k = int(np.argmin(distances))
    return k if distances[k] <= reach else None


def edge_at(points, p, reach: float) -> int | None:
    """The edge of the outline through ``points`` nearest ``p``, if it passes within ``reach`` metres:
    edge ``i`` runs from point ``i`` to the next, and from 3 points on the last edge closes back to
    the first (as the floor shows it). A point inserted on edge ``i`` goes at index ``i + 1``."""
    v = np.asarray(points, dtype=float).reshape(-1, 2)
    n = len(v)
    if n < 2:
        return None
    a = v if n >= 3 else v[:1]
    b = np.roll(v, -1, axis=0) if n >= 3 else v[1:]
    ab, ap = b - a, np.asarray(p, float) - a
    lengths2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    t = np.clip(np.einsum("ij,ij->i", ap, ab) / lengths2, 0.0, 1.0)
    distances = np.hypot(*(ap - t[:, None] * ab).T)
    k = int(np.argmin(distances))
    return k if distances[k] <= reach else None


# ---------------------------------------------------------------- typing
def parse_coordinates(text: str) -> list[Point]:
    """Points from typed or pasted text: ``x y`` (or ``x, y``) one pair per line,
    pairs separated by ``;``, or a JSON list of pairs. ``#`` starts a comment
    line; brackets around a pair are allowed. Raises ShapeError with one line
    that says where and what is wrong. Repeats are kept (see without_repeats)."""
    text = text.strip()
    if not text:
        raise fail(SOURCE, f"nothing to read; type {FORMATS_HINT}")
    points = _parse_json(text) if text.startswith("[") else _parse_pairs(text)
    if len(points) > MAX_VERTICES:
        raise fail(SOURCE, f"{len(points):,} points; at most {MAX_VERTICES:,}")
    return points


def _parse_json(text: str) -> list[Point]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise fail(SOURCE, f"not a JSON list: {exc.msg} (line {exc.lineno}, column {exc.colno})") from None
    if not isinstance(data, list):
        raise fail(SOURCE, "a JSON list of [x, y] pairs was expected")
    points = []
    for k, pair in enumerate(data, 1):
        where = f"pair {k}"
        if not isinstance(pair, list) or len(pair) != 2:
            raise fail(SOURCE, f"{json.dumps(pair)[:40]} is not an [x, y] pair", where)
        points.append((to_float(pair[0], SOURCE, where), to_float(pair[1], SOURCE, where)))
    return points


def _parse_pairs(text: str) -> list[Point]:
    points = []
    chunks = [c.strip() for line in text.splitlines() if not line.lstrip().startswith("#")
              for c in line.split(";")]
    for k, chunk in enumerate([c for c in chunks if c], 1):
        where = f"pair {k}"
        tokens = re.sub(r"[(),\[\]]", " ", chunk).split()
        if len(tokens) != 2:
            raise fail(SOURCE, f"{chunk[:40]!r} is not two numbers x y (expected {FORMATS_HINT})", where)
        points.append((to_float(tokens[0], SOURCE, where), to_float(tokens[1], SOURCE, where)))
    return points


def format_coordinates(points) -> str:
    """The points as the coordinates field shows them: ``x y`` one pair per line."""
    return "\n".join(f"{x:.6g} {y:.6g}" for x, y in points)


# -------------------------------------------------------------- crossings
def crossing_edges(points) -> list[tuple[int, int]]:
    """Pairs (i, j), i < j, of edges of the closed outline through ``points`` that
    cross or touch where they should not: any contact between edges that are not
    neighbours, and an overlap (not just the shared corner) between neighbours.
    The same rule as validate_polygon's; empty for fewer than 3 points."""
    v = np.asarray(points, dtype=float).reshape(-1, 2)
    n = len(v)
    if n < 3:
        return []
    ends = np.stack([v, np.roll(v, -1, axis=0)], axis=1)
    real = np.flatnonzero(np.any(ends[:, 0] != ends[:, 1], axis=1))  # a zero-length edge touches nothing new
    edges = shapely.linestrings(ends[real])
    a, b = shapely.STRtree(edges).query(edges, predicate="intersects")
    pairs = set()
    for p, q in zip(a.tolist(), b.tolist()):
        i, j = int(real[p]), int(real[q])
        if j <= i:
            continue
        if (j - i) % n in (1, n - 1) and shapely.intersection(edges[p], edges[q]).geom_type == "Point":
            continue  # neighbours meeting at their shared corner
        pairs.add((i, j))
    return sorted(pairs)


def edge_name(i: int, n: int) -> str:
    """Edge ``i`` of an n-vertex outline by its vertex numbers: ``"3-4"``, the closing one ``"6-1"``."""
    return f"{i + 1}-{(i + 1) % n + 1}"
