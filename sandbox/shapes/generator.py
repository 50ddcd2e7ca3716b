"""Goal shapes nobody chose: random simple polygons a person could draw, in families, each made again from
its family and seed alone and named after them (``gen-rectilinear-0042``).

The families (:data:`FAMILIES`):

- ``convex``: the hull of a few points on a stretched circle, no corner sharper than 45 degrees;
- ``star``: star-shaped blobs, a radius around the centre with random harmonics (``blob``), or a star of
  3 to 8 jittered points (``points``);
- ``rectilinear``: unions of the cells of an uneven grid: letters, combs, forks, keys, stairs, a head on
  a stem, a body with a handle, a block with a channel cut into it (:data:`RECTILINEAR_KINDS`), turned
  and mirrored;
- ``branching``: a random tree of segments, buffered: a thick trunk forking into thin arms (``tree``), or a
  round body with arms, some forked into prongs (``hub``);
- ``curved``: a crescent, a ring segment, a spiral arm (:data:`CURVED_KINDS`).

Every shape is drawn at the default goal's size, in metres: the area of the default 500 boxes
(:data:`GOAL_AREA`), its centroid at the origin, as the model places a goal (it fits a goal to the
boxes' area anyway, so only the shape matters to a run). It spans at most :data:`MAX_EXTENT` each way,
so it fits the construction area with room to spare (the model moves a goal that reaches past the
area's wall inside when the band follows its edge); it is a valid simple polygon without holes
or a point where it touches itself, with at most :data:`MAX_VERTICES` vertices (what the outlines
afford: the model leaves a goal with fewer as it is); no part of it is narrower than
:data:`MIN_WIDTH` and no gap narrower than :data:`MIN_GAP` (docs/shapes.md says why those two). The
widths are kept by opening and closing the outline: by a disc, which rounds the convex corners of
stars, trees and curves to half the width; by a square for rectilinear shapes, whose corners stay
square. A convex shape is too wide for either and keeps its corners, none sharper than
:data:`MIN_CORNER_ANGLE`.

Each draw keeps its parameters (:attr:`GeneratedShape.params`): :func:`from_params` makes the same
vertices from them without the random numbers. A draw that breaks a rule above is drawn again from the
same random stream, so a seed always gives the same shape. Headless: numpy and shapely only.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import shapely
import shapely.affinity
from shapely.geometry import LineString, MultiPoint, Point, Polygon, box
from shapely.ops import unary_union

from sandbox.shapes import geometry
from sandbox.shapes.errors import ShapeError
from sandbox.shapes.validation import validate_polygon

FAMILIES = ("convex", "star", "rectilinear", "branching", "curved")
RECTILINEAR_KINDS = ("letter", "comb", "fork", "key", "stairs", "stem", "handle", "channel")
CURVED_KINDS = ("crescent", "ring", "spiral")
#: Each family's kinds, taken in turn by seed (a convex shape has none).
KINDS = {"convex": (), "star": ("blob", "points"), "rectilinear": RECTILINEAR_KINDS, "branching": ("tree", "hub"),
         "curved": CURVED_KINDS}
#: Each family's part of the random seed: fixed numbers, so that adding a family never changes another's shapes.
_FAMILY_KEYS = {"convex": 1, "star": 2, "rectilinear": 3, "branching": 4, "curved": 5}

#: The default goal's area (m²): 500 hexagonal boxes of circumradius 0.25 m (tests check it against Config).
GOAL_AREA = 500 * 1.5 * math.sqrt(3) * 0.25 ** 2
#: The side of the default construction area (m), which boxes never leave (tests check it against Config).
CONSTRUCTION_SIZE = 16.0
#: A generated shape spans at most this much each way (m): the construction area less a box's size all round.
MAX_EXTENT = CONSTRUCTION_SIZE - 1.0
#: The narrowest part (m): the thin hold's table (sandbox.model.thin) brings the band to its least distance
#: on a notched goal, 0.65 m, only beside parts at least this wide; beside narrower ones it holds farther out
#: (1.15 m beside a 1 m part), where a robot's push no longer reaches into the goal.
MIN_WIDTH = 2.0
#: The narrowest gap between two parts (m): a strip this wide always holds a line of lights (one pitch, 1 m)
#: and a robot (0.5 m) beside it, so the notch it makes can be lit and cleared.
MIN_GAP = 1.5
#: The most vertices (the outlines' bound, sandbox.model.budget.MAX_GOAL_VERTICES; tests check it).
MAX_VERTICES = 300
#: A convex shape's sharpest corner (degrees).
MIN_CORNER_ANGLE = 45.0
#: Outlines are simplified within this (m), far below a light's pitch, and rounded to this step (m).
SIMPLIFY_WITHIN = 0.02
COORDINATE_STEP = 0.001
#: Draws tried for one seed before giving up (over seeds 0-199 and 1000-1099 of each family: at most 60, a
#: rectilinear key; 3 on average).
ATTEMPTS = 200
#: The widths are made this much larger than the least, so that rescaling and simplifying keep them.
MARGIN = 1.05
#: Curves are buffered with this many segments a quarter circle.
QUAD_SEGS = 6
#: The seeds of one draw: generator seed S gives the shapes S * SEEDS_PER_DRAW, S * SEEDS_PER_DRAW + 1, ...
#: of every family, so two generator seeds never share a shape.
SEEDS_PER_DRAW = 1000

_NAME = re.compile(r"^gen-([a-z]+)-(\d{1,9})$")


@dataclass(frozen=True)
class GeneratedShape:
    """A generated goal: its family, seed and parameters, and its vertices (m, counter-clockwise)."""

    family: str
    seed: int
    params: dict = field(compare=False)
    vertices: np.ndarray = field(compare=False, repr=False)

    @property
    def name(self) -> str:
        return shape_name(self.family, self.seed)

    @property
    def kind(self) -> str:
        """The family's kind (a rectilinear ``comb``, a curved ``spiral``, a star ``blob``); '' for convex."""
        return str(self.params.get("kind", ""))

    def record(self) -> dict:
        """What a sweep keeps of it: name, family, seed, parameters (plain JSON)."""
        return {"name": self.name, "family": self.family, "seed": self.seed, "kind": self.kind,
                "params": self.params}


def shape_name(family: str, seed: int) -> str:
    return f"gen-{family}-{int(seed):04d}"


def parse_name(name: str) -> tuple[str, int] | None:
    """(family, seed) of a generated shape's name, None for any other name."""
    match = _NAME.match(str(name).strip().lower())
    if match is None or match.group(1) not in FAMILIES:
        return None
    return match.group(1), int(match.group(2))


def families_from_text(text: str) -> tuple[str, ...]:
    """``all`` or names separated by commas, as the command line gives them; a ShapeError naming the
    families for an unknown one."""
    if text.strip() == "all":
        return FAMILIES
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    unknown = [n for n in names if n not in FAMILIES]
    if unknown or not names:
        raise ShapeError(f"unknown shape family {unknown[0] if unknown else text!r}; the families are: all, "
                         f"{', '.join(FAMILIES)}")
    return names


def draw(count: int, families: tuple[str, ...] = FAMILIES, generator_seed: int = 0) -> list[GeneratedShape]:
    """``count`` shapes, the families in turn (any first k shapes are as even across them as k allows);
    the i-th of a family has seed ``generator_seed * SEEDS_PER_DRAW + i``."""
    if count < 0 or count > SEEDS_PER_DRAW * len(families):
        raise ShapeError(f"a draw holds 0 to {SEEDS_PER_DRAW * len(families):,} shapes of {len(families)} "
                         f"families (asked for {count:,})")
    if generator_seed < 0:
        raise ShapeError(f"the generator seed must be 0 or more (got {generator_seed})")
    first = generator_seed * SEEDS_PER_DRAW
    return [generate(families[i % len(families)], first + i // len(families)) for i in range(count)]


def generate(family: str, seed: int) -> GeneratedShape:
    """The shape of ``family`` and ``seed``: the same vertices on every call."""
    if family not in FAMILIES:
        raise ShapeError(f"unknown shape family {family!r}; the families are: {', '.join(FAMILIES)}")
    if int(seed) < 0:
        raise ShapeError(f"a shape's seed must be 0 or more (got {seed})")
    return _generate(family, int(seed))


@functools.lru_cache(maxsize=512)
def _generate(family: str, seed: int) -> GeneratedShape:
    rng = np.random.default_rng([_FAMILY_KEYS[family], seed])
    kind = kind_of(family, seed)
    for attempt in range(ATTEMPTS):
        params = _DRAWS[family](rng, kind)
        vertices = _finished(family, _OUTLINES[family](params))
        if vertices is not None and not problems(vertices, family):
            return _frozen(GeneratedShape(family, seed, {**params, "attempt": attempt}, vertices))
    raise ShapeError(f"{shape_name(family, seed)}: no shape within the rules after {ATTEMPTS} draws")


def kind_of(family: str, seed: int) -> str:
    """The kind a seed draws, in turn: any run of seeds holds every kind of its family about as often."""
    kinds = KINDS[family]
    return kinds[seed % len(kinds)] if kinds else ""


def from_params(family: str, params: dict) -> np.ndarray:
    """The vertices a draw's parameters make (as :func:`generate` made them); a ShapeError if they break a rule."""
    vertices = _finished(family, _OUTLINES[family](params))
    found = ["the outline falls apart"] if vertices is None else problems(vertices, family)
    if found:
        raise ShapeError(f"{family} parameters: {found[0]}")
    return vertices


def generated_vertices(name: str) -> np.ndarray | None:
    """The vertices of a generated shape's name (``gen-star-0007``), None for any other name."""
    parsed = parse_name(name)
    return None if parsed is None else generate(*parsed).vertices.copy()


def _frozen(shape: GeneratedShape) -> GeneratedShape:
    shape.vertices.setflags(write=False)  # cached: a caller must not move the cache's copy
    return shape


# ------------------------------------------------------------------ the rules


def problems(vertices: np.ndarray, family: str) -> list[str]:
    """What keeps these vertices from being a generated shape of ``family`` (none: they are one)."""
    try:
        validate_polygon(vertices, "generated shape")
    except ShapeError as exc:
        return [str(exc)]
    polygon = Polygon(vertices)
    found = []
    if not (polygon.is_valid and polygon.exterior.is_simple) or len(polygon.interiors):
        found.append(f"not a simple polygon ({shapely.is_valid_reason(polygon)})")
    if len(vertices) > MAX_VERTICES:
        found.append(f"{len(vertices)} vertices, more than {MAX_VERTICES}")
    if abs(polygon.area / GOAL_AREA - 1.0) > 0.01:
        found.append(f"area {polygon.area:.1f} m², not {GOAL_AREA:.1f}")
    extent = np.ptp(vertices, axis=0)
    if (extent > MAX_EXTENT + 1e-9).any():
        found.append(f"{extent[0]:.1f} x {extent[1]:.1f} m, more than {MAX_EXTENT:g} m")
    if family == "convex":
        found += _convex_problems(vertices)
    else:
        found += _width_problems(polygon, square=family == "rectilinear")
    return found


def narrowest_part(polygon: Polygon, width: float, *, square: bool = False) -> float:
    """The share of ``polygon``'s area that parts narrower than ``width`` hold: what an opening (every disc,
    or axis-aligned square, of that size that fits inside, united) leaves out of its largest piece."""
    opened = _largest(_opening(polygon, width, square))
    return 1.0 - (0.0 if opened is None else opened.area) / polygon.area


def narrowest_gap(polygon: Polygon, width: float, *, square: bool = False) -> float:
    """The area (as a share of ``polygon``'s) that closing it by discs (squares) of ``width`` adds: the gaps
    narrower than that."""
    return _closing(polygon, width, square).area / polygon.area - 1.0


#: Share of the area a part narrower than the least may hold, or a gap narrower than the least may add: the
#: slivers that rounding the coordinates and simplifying leave.
WIDTH_TOLERANCE = 0.003
#: The rules' widths are checked this much below the least (their arcs are polygons).
CHECK_BELOW = 0.98


def _width_problems(polygon: Polygon, square: bool) -> list[str]:
    found = []
    thin = narrowest_part(polygon, MIN_WIDTH * CHECK_BELOW, square=square)
    if thin > WIDTH_TOLERANCE:
        found.append(f"{thin:.1%} of it lies in parts narrower than {MIN_WIDTH:g} m")
    gaps = narrowest_gap(polygon, MIN_GAP * CHECK_BELOW, square=square)
    if gaps > WIDTH_TOLERANCE:
        found.append(f"gaps narrower than {MIN_GAP:g} m ({gaps:.1%} of its area)")
    return found


def _convex_problems(vertices: np.ndarray) -> list[str]:
    found = []
    angles = geometry.interior_angles(vertices)
    if (angles >= 180.0 - 1e-6).any():
        found.append("not convex")
    elif angles.min() < MIN_CORNER_ANGLE:
        found.append(f"a corner of {angles.min():.0f} degrees, sharper than {MIN_CORNER_ANGLE:g}")
    if convex_width(vertices) < MIN_WIDTH:
        found.append(f"narrower than {MIN_WIDTH:g} m")
    return found


def convex_width(vertices: np.ndarray) -> float:
    """A convex polygon's width: the least distance between two parallel lines that hold it (an edge's line
    and the vertex farthest from it)."""
    v = np.asarray(vertices, dtype=float)
    edges = np.roll(v, -1, axis=0) - v
    normals = np.column_stack([-edges[:, 1], edges[:, 0]]) / np.hypot(*edges.T)[:, None]
    spans = np.abs(np.einsum("ijk,ik->ij", v[None, :, :] - v[:, None, :], normals))  # vertex j from edge i's line
    return float(spans.max(axis=1).min())


# ------------------------------------------------------------------ from an outline to a shape


def _opening(polygon, width: float, square: bool):
    join = {"join_style": "mitre", "mitre_limit": 10.0} if square else {"quad_segs": QUAD_SEGS}
    return polygon.buffer(-width / 2.0, **join).buffer(width / 2.0, **join)


def _closing(polygon, width: float, square: bool):
    join = {"join_style": "mitre", "mitre_limit": 10.0} if square else {"quad_segs": QUAD_SEGS}
    return polygon.buffer(width / 2.0, **join).buffer(-width / 2.0, **join)


def _largest(shape) -> Polygon | None:
    pieces = [g for g in getattr(shape, "geoms", [shape]) if isinstance(g, Polygon) and not g.is_empty]
    return max(pieces, key=lambda g: g.area) if pieces else None


def _fitted(polygon: Polygon) -> Polygon:
    """Scaled to :data:`GOAL_AREA`, its centroid at the origin."""
    centre = polygon.centroid
    factor = math.sqrt(GOAL_AREA / polygon.area)
    return shapely.affinity.scale(shapely.affinity.translate(polygon, -centre.x, -centre.y), factor, factor,
                                  origin=(0.0, 0.0))


#: How much the cleaning may change a shape's area, by whether it is rectilinear.
CLEANING_CHANGES = {False: 0.1, True: 0.001}


def _finished(family: str, outline) -> np.ndarray | None:
    """The outline as a generated shape's vertices: fitted, its gaps closed and thin parts opened away (none
    for a convex one), simplified, fitted again, rounded; None when that leaves no polygon or changes its
    area by more than :data:`CLEANING_CHANGES` (a grid's cells are drawn wide enough, so a rectilinear
    shape the cleaning changes at all is drawn again: it would no longer be the comb its parameters say)."""
    polygon = _largest(outline)
    if polygon is None or polygon.area <= 0.0:
        return None
    polygon = _fitted(Polygon(polygon.exterior))
    if family != "convex":
        square = family == "rectilinear"
        before = polygon.area
        cleaned = _largest(_opening(_closing(polygon, MIN_GAP * MARGIN, square), MIN_WIDTH * MARGIN, square))
        if cleaned is None or abs(cleaned.area / before - 1.0) > CLEANING_CHANGES[square]:
            return None
        polygon = _fitted(Polygon(cleaned.exterior))
    simpler = polygon.simplify(SIMPLIFY_WITHIN, preserve_topology=True)
    if simpler.geom_type != "Polygon" or simpler.is_empty:
        return None
    vertices = np.asarray(_fitted(Polygon(simpler.exterior)).exterior.coords)[:-1]
    if geometry.signed_area(vertices) < 0:
        vertices = vertices[::-1]
    vertices = np.round(vertices / COORDINATE_STEP) * COORDINATE_STEP
    keep = np.any(vertices != np.roll(vertices, 1, axis=0), axis=1)
    return vertices[keep] + 0.0  # + 0.0: no negative zeros


# ------------------------------------------------------------------ drawing parameters


def _r(value: float, digits: int = 3) -> float:
    return round(float(value), digits)


def _uniform(rng: np.random.Generator, low: float, high: float, digits: int = 3) -> float:
    return _r(rng.uniform(low, high), digits)


def _rotated(shape, degrees: float):
    return shapely.affinity.rotate(shape, degrees, origin=(0.0, 0.0))


# convex


def _draw_convex(rng: np.random.Generator, kind: str) -> dict:
    n = int(rng.integers(3, 11))
    angles = np.sort(rng.uniform(0.0, 360.0, n))
    return {"points": n, "angles": [_r(a, 2) for a in angles],
            "radii": [_uniform(rng, 0.75, 1.0) for _ in range(n)],
            "aspect": _uniform(rng, 1.0, 1.9), "rotation": _uniform(rng, 0.0, 180.0, 1)}


def _convex_outline(p: dict):
    t = np.radians(p["angles"])
    r = np.asarray(p["radii"])
    points = np.column_stack([r * np.cos(t) * p["aspect"], r * np.sin(t)])
    return _rotated(MultiPoint(points).convex_hull, p["rotation"])


# star-shaped


def _draw_star(rng: np.random.Generator, kind: str) -> dict:
    stretch, rotation = _uniform(rng, 1.0, 1.5), _uniform(rng, 0.0, 180.0, 1)
    if kind == "blob":
        count = int(rng.integers(2, 6))
        orders = sorted(rng.choice(np.arange(2, 8), size=count, replace=False).tolist())
        amplitudes = rng.uniform(0.05, 0.35, count)
        amplitudes *= min(1.0, 0.7 / amplitudes.sum())  # the radius stays at least 0.3 of its mean
        return {"kind": "blob", "harmonics": [[int(k), _r(a), _uniform(rng, 0.0, 360.0, 1)]
                                              for k, a in zip(orders, amplitudes)],
                "stretch": stretch, "rotation": rotation}
    points = int(rng.integers(3, 9))
    return {"kind": "points", "points": points, "inner": _uniform(rng, 0.45, 0.75),
            "jitter": [_uniform(rng, 0.85, 1.0) for _ in range(2 * points)], "stretch": stretch,
            "rotation": rotation}


#: Samples around a blob's centre.
BLOB_SAMPLES = 120


def _star_outline(p: dict):
    if p["kind"] == "blob":
        t = np.linspace(0.0, 2.0 * math.pi, BLOB_SAMPLES, endpoint=False)
        r = np.ones_like(t)
        for order, amplitude, phase in p["harmonics"]:
            r += amplitude * np.cos(order * t + math.radians(phase))
    else:
        t = np.arange(2 * p["points"]) * math.pi / p["points"]
        r = np.where(np.arange(2 * p["points"]) % 2 == 0, 1.0, p["inner"]) * np.asarray(p["jitter"])
    return _rotated(Polygon(np.column_stack([r * np.cos(t) * p["stretch"], r * np.sin(t)])), p["rotation"])


# rectilinear: cells of an uneven grid


#: Letters of three by five cells, top row first: only those without a hole or two cells that meet at a corner.
LETTERS = {
    "C": ("###", "#..", "#..", "#..", "###"), "E": ("###", "#..", "###", "#..", "###"),
    "F": ("###", "#..", "##.", "#..", "#.."), "G": ("###", "#..", "#.#", "#.#", "###"),
    "H": ("#.#", "#.#", "###", "#.#", "#.#"), "I": ("###", ".#.", ".#.", ".#.", "###"),
    "J": ("..#", "..#", "..#", "#.#", "###"), "L": ("#..", "#..", "#..", "#..", "###"),
    "S": ("###", "#..", "###", "..#", "###"), "T": ("###", ".#.", ".#.", ".#.", ".#."),
    "U": ("#.#", "#.#", "#.#", "#.#", "###"), "Y": ("#.#", "#.#", "###", ".#.", ".#."),
    "h": ("#..", "#..", "###", "#.#", "#.#"), "4": ("#.#", "#.#", "###", "..#", "..#"),
    "7": ("###", "..#", "..#", "..#", "..#"),
}


def _cells_of_rows(rows: tuple[str, ...]) -> list[list[int]]:
    height = len(rows)
    return [[x, height - 1 - y] for y, row in enumerate(rows) for x, c in enumerate(row) if c == "#"]


def _letter(rng) -> tuple[dict, list]:
    letter = str(rng.choice(sorted(LETTERS)))
    return {"letter": letter}, _cells_of_rows(LETTERS[letter])


def _comb(rng) -> tuple[dict, list]:
    teeth, length = int(rng.integers(2, 5)), int(rng.integers(1, 4))
    cells = [[x, 0] for x in range(2 * teeth - 1)]
    cells += [[2 * i, y] for i in range(teeth) for y in range(1, length + 1)]
    return {"teeth": teeth, "length": length}, cells


def _fork(rng) -> tuple[dict, list]:
    """Prongs on a crossbar on a stem: the stem under any column of the bar."""
    prongs, prong, stem = int(rng.integers(2, 4)), int(rng.integers(1, 4)), int(rng.integers(1, 4))
    at = int(rng.integers(0, 2 * prongs - 1))
    cells = [[at, y] for y in range(stem)] + [[x, stem] for x in range(2 * prongs - 1)]
    cells += [[2 * i, stem + y] for i in range(prongs) for y in range(1, prong + 1)]
    return {"prongs": prongs, "prong_length": prong, "stem_length": stem, "stem_at": at}, cells


def _key(rng) -> tuple[dict, list]:
    """A square bow, a shaft from its middle, bits hanging below the shaft's far half."""
    bow, shaft = int(rng.integers(2, 4)), int(rng.integers(3, 6))
    row = bow // 2 if bow == 3 else 1
    cells = [[x, y] for x in range(bow) for y in range(bow)]
    cells += [[bow + x, row] for x in range(shaft)]
    places = list(range(bow + 1, bow + shaft, 2))
    bits = sorted(rng.choice(places, size=int(rng.integers(1, len(places) + 1)), replace=False).tolist())
    cells += [[x, row - 1] for x in bits]
    return {"bow": bow, "shaft": shaft, "bits": [int(b) for b in bits]}, cells


def _stairs(rng) -> tuple[dict, list]:
    steps, solid = int(rng.integers(3, 6)), bool(rng.random() < 0.5)
    if solid:
        cells = [[x, y] for x in range(steps) for y in range(x + 1)]
    else:
        cells = [[x, x] for x in range(steps)] + [[x + 1, x] for x in range(steps - 1)]
    return {"steps": steps, "solid": solid}, cells


_HEADS = {"block": ("###", "###"), "U": ("#.#", "###"), "T": ("###",), "cup": ("#.#", "#.#", "###")}


def _stem(rng) -> tuple[dict, list]:
    """A head on a stem, the stem under any column of the head, with or without a foot."""
    head = str(rng.choice(sorted(_HEADS)))
    length, at, foot = int(rng.integers(2, 5)), int(rng.integers(0, 3)), bool(rng.random() < 0.4)
    base = 1 if foot else 0
    cells = [[x, base + length + y] for x, y in _cells_of_rows(_HEADS[head])]
    cells += [[at, base + y] for y in range(length)]
    if foot:
        cells += [[x, 0] for x in range(3)]
    return {"head": head, "stem_length": length, "stem_at": at, "foot": foot}, cells


def _handle(rng) -> tuple[dict, list]:
    """A body with a handle from the middle of one side, straight or hooked at its end."""
    width, height = int(rng.integers(2, 4)), int(rng.integers(2, 4))
    length, hook = int(rng.integers(2, 5)), int(rng.integers(0, 3))
    row = height // 2
    cells = [[x, y] for x in range(width) for y in range(height)]
    cells += [[width + x, row] for x in range(length)]
    cells += [[width + length - 1, row + 1 + y] for y in range(hook)]
    return {"body": [width, height], "handle_length": length, "hook": hook}, cells


def _channel(rng) -> tuple[dict, list]:
    """A block with a channel one cell wide cut in from its top, straight or turning at its end."""
    width, height = int(rng.integers(3, 5)), int(rng.integers(3, 5))
    at, depth = int(rng.integers(1, width - 1)), int(rng.integers(1, height - 1))
    turn = int(rng.choice([-1, 0, 1])) if depth >= 1 else 0
    cut = {(at, height - 1 - y) for y in range(depth)}
    bottom = height - depth
    if turn and 1 <= at + turn <= width - 2:
        cut.add((at + turn, bottom))
    else:
        turn = 0
    cells = [[x, y] for x in range(width) for y in range(height) if (x, y) not in cut]
    return {"block": [width, height], "channel_at": at, "depth": depth, "turn": turn}, cells


_KINDS: dict[str, Callable] = {"letter": _letter, "comb": _comb, "fork": _fork, "key": _key, "stairs": _stairs,
                               "stem": _stem, "handle": _handle, "channel": _channel}


#: The grid's columns and rows are drawn between these sizes (relative: the shape is scaled to the goal's area).
CELL_SIZES = (0.7, 1.8)


def _draw_rectilinear(rng: np.random.Generator, kind: str) -> dict:
    details, cells = _KINDS[kind](rng)
    columns = max(x for x, _ in cells) + 1
    rows = max(y for _, y in cells) + 1
    return {"kind": kind, **details, "cells": sorted(cells),
            "columns": [_uniform(rng, *CELL_SIZES, 2) for _ in range(columns)],
            "rows": [_uniform(rng, *CELL_SIZES, 2) for _ in range(rows)],
            "turns": int(rng.integers(0, 4)), "mirror": bool(rng.random() < 0.5)}


def _rectilinear_outline(p: dict):
    xs = np.concatenate([[0.0], np.cumsum(p["columns"])])
    ys = np.concatenate([[0.0], np.cumsum(p["rows"])])
    shape = unary_union([box(xs[x], ys[y], xs[x + 1], ys[y + 1]) for x, y in p["cells"]])
    if p["mirror"]:
        shape = shapely.affinity.scale(shape, -1.0, 1.0, origin=(0.0, 0.0))
    return _rotated(shape, 90.0 * p["turns"])


# branching: a buffered tree


#: The half-widths (m) of a tree's trunk and of a hub's arms (ranges), of its thinnest arm, its most segments.
TRUNK, HUB_ARM, ARM, MOST_SEGMENTS = (1.5, 2.6), (1.05, 1.5), 1.05, 9


def _draw_branching(rng: np.random.Generator, kind: str) -> dict:
    """A ``tree``: a trunk that forks into thinner arms, up to three times; a ``hub``: a round body with two to
    five arms, some forked at their ends into prongs. The tree's lengths (the hub's arms) are scaled so that
    it covers the goal's area at its widths."""
    if kind == "tree":
        heading, half = rng.uniform(0.0, 2.0 * math.pi), rng.uniform(*TRUNK)
        trunks = [(0.0, 0.0, heading, rng.uniform(2.0, 4.0), half, 0)]
        if rng.random() < 0.5:  # the trunk forks at both ends
            trunks.append((0.0, 0.0, heading + math.pi, rng.uniform(1.0, 3.0), half, 0))
        segments = _branches(rng, trunks, int(rng.integers(1, 3)))
        params = {"kind": kind, "hub": 0.0, "segments": segments, "scale": 1.0}
    else:
        arms = int(rng.integers(2, 6))
        headings = np.sort(rng.uniform(0.0, 2.0 * math.pi, arms))
        starts = [(0.0, 0.0, h, rng.uniform(2.5, 5.0), rng.uniform(*HUB_ARM), 1 - int(rng.random() < 0.4))
                  for h in headings]
        params = {"kind": kind, "hub": _uniform(rng, 1.8, 3.0, 2), "segments": _branches(rng, starts, 1),
                  "scale": 1.0}
    params["scale"] = _r(_solve(lambda k: _tree({**params, "scale": k}).area, GOAL_AREA, 0.2, 5.0), 4)
    return params


def _branches(rng: np.random.Generator, queue: list, depth: int) -> list[list[float]]:
    """Segments [x0, y0, x1, y1, half-width] grown from ``queue`` (x, y, heading, length, half-width, level):
    each ends in one to three children (a bend, a fork, prongs) until ``depth``."""
    segments: list[list[float]] = []
    while queue and len(segments) < MOST_SEGMENTS:
        x, y, heading, length, half, level = queue.pop(0)
        end = (x + length * math.cos(heading), y + length * math.sin(heading))
        segments.append([_r(x), _r(y), _r(end[0]), _r(end[1]), _r(half)])
        if level >= depth:
            continue
        children = int(rng.choice([1, 2, 2, 3]))
        spread = math.radians(rng.uniform(40.0, 85.0))
        for i in range(children):
            turn = spread * (i - (children - 1) / 2.0) + math.radians(rng.normal(0.0, 10.0))
            queue.append((end[0], end[1], heading + turn, length * rng.uniform(0.6, 1.0),
                          max(ARM, half * rng.uniform(0.6, 0.9)), level + 1))
    return segments


def _tree(p: dict):
    """The segments' lengths times ``scale`` (not their widths), buffered, with the hub's disc."""
    k = p["scale"]
    parts = [LineString([(k * x0, k * y0), (k * x1, k * y1)]).buffer(half, quad_segs=QUAD_SEGS)
             for x0, y0, x1, y1, half in p["segments"]]
    if p["hub"] > 0:
        parts.append(Point(0.0, 0.0).buffer(p["hub"], quad_segs=QUAD_SEGS))
    return unary_union(parts)


def _branching_outline(p: dict):
    return _tree(p)


# curved


def _draw_curved(rng: np.random.Generator, kind: str) -> dict:
    rotation = _uniform(rng, 0.0, 360.0, 1)
    if kind == "crescent":
        inner = _uniform(rng, 0.55, 0.9)
        return {"kind": kind, "inner": inner, "offset": _uniform(rng, max(1.05 - inner, 0.3), 0.8),
                "rotation": rotation}
    if kind == "ring":
        sweep, thickness = _uniform(rng, 180.0, 320.0, 1), _uniform(rng, 2.5, 4.5, 2)
        ends = str(rng.choice(["round", "flat"]))
        params = {"kind": kind, "sweep": sweep, "thickness": thickness, "ends": ends, "rotation": rotation}
        params["radius"] = _r(_solve(lambda r: _ring({**params, "radius": r}).area, GOAL_AREA, thickness, 40.0))
        return params
    half = _uniform(rng, 1.05, 1.5)
    params = {"kind": kind, "half_width": half, "start": _uniform(rng, 1.0, 2.5),
              "spacing": _uniform(rng, MIN_GAP * 1.1, 3.0, 2), "turn": 1.0, "rotation": rotation,
              "clockwise": bool(rng.random() < 0.5)}
    params["turn"] = _r(_solve(lambda t: _spiral({**params, "turn": t}).area, GOAL_AREA, 0.5, 6.0), 4)
    return params


def _ring(p: dict):
    t = np.radians(np.linspace(0.0, p["sweep"], 64))
    arc = LineString(np.column_stack([p["radius"] * np.cos(t), p["radius"] * np.sin(t)]))
    return arc.buffer(p["thickness"] / 2.0, quad_segs=QUAD_SEGS, cap_style="round" if p["ends"] == "round" else "flat")


def _spiral(p: dict):
    """An Archimedean arm: its radius grows by the arm's width and the spacing each turn; ``turn`` turns long."""
    pitch = (2.0 * p["half_width"] + p["spacing"]) / (2.0 * math.pi)
    t = np.linspace(0.0, 2.0 * math.pi * p["turn"], max(16, int(48 * p["turn"])))
    r = p["start"] + pitch * t
    line = LineString(np.column_stack([r * np.cos(t), r * np.sin(t) * (-1.0 if p["clockwise"] else 1.0)]))
    return line.buffer(p["half_width"], quad_segs=QUAD_SEGS)


def _curved_outline(p: dict):
    if p["kind"] == "crescent":
        shape = Point(0.0, 0.0).buffer(1.0, quad_segs=24).difference(
            Point(p["offset"], 0.0).buffer(p["inner"], quad_segs=24))
    elif p["kind"] == "ring":
        shape = _ring(p)
    else:
        shape = _spiral(p)
    return _rotated(shape, p["rotation"])


def _solve(area: Callable[[float], float], target: float, low: float, high: float) -> float:
    """The value between ``low`` and ``high`` at which ``area`` (growing with it, nearly in a straight line)
    reaches ``target``: false position, each end kept after it moved twice halved in weight (Illinois), to a
    ten-thousandth of the area."""
    f_low, f_high = area(low) - target, area(high) - target
    if f_low >= 0.0 or f_high <= 0.0:
        return low if f_low >= 0.0 else high
    side = 0
    for _ in range(40):
        middle = (low * f_high - high * f_low) / (f_high - f_low)
        f_middle = area(middle) - target
        if abs(f_middle) <= 1e-4 * target:
            return middle
        if f_middle < 0.0:
            low, f_low = middle, f_middle
            f_high *= 0.5 if side == -1 else 1.0
            side = -1
        else:
            high, f_high = middle, f_middle
            f_low *= 0.5 if side == 1 else 1.0
            side = 1
    return middle


_DRAWS: dict[str, Callable[[np.random.Generator, str], dict]] = {
    "convex": _draw_convex, "star": _draw_star, "rectilinear": _draw_rectilinear, "branching": _draw_branching,
    "curved": _draw_curved}
_OUTLINES: dict[str, Callable[[dict], Any]] = {
    "convex": _convex_outline, "star": _star_outline, "rectilinear": _rectilinear_outline,
    "branching": _branching_outline, "curved": _curved_outline}
