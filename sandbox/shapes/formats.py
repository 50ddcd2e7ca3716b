"""Goal-shape polygon files: plain text, JSON / GeoJSON, WKT and SVG, read
into outlines.

Every loader returns a float64 ``(n, 2)`` array of outline vertices in file
order, without a repeated closing vertex. Position, size and orientation are
left alone: normalising them is the model's job. Every problem is reported
as a :class:`~sandbox.shapes.errors.ShapeError` whose message is one line
naming the source and, where it helps, the line number (plain text) or
1-based vertex number: also malformed files that make a parser give up
(nesting too deep, numbers too large).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import shapely.wkt
from shapely.errors import ShapelyError
from shapely.geometry import MultiPolygon, Polygon

from sandbox.shapes.errors import ShapeError, fail, to_float
from sandbox.shapes.svg import parse_svg
from sandbox.shapes.validation import validate_polygon

MAX_BYTES = 1_000_000          # "1 MB": no sane polygon file is larger
FORMATS = ("txt", "geojson", "wkt", "json", "svg")
EXTENSIONS = {".txt": "txt", ".csv": "txt", ".poly": "txt", ".dat": "txt",
              ".geojson": "geojson", ".json": "json", ".wkt": "wkt", ".svg": "svg"}


# ---------------------------------------------------------------- plain text

def _parse_txt(text: str, source: str):
    points, line_numbers = [], []
    for number, raw in enumerate(text.splitlines(), start=1):
        tokens = [t for t in re.split(r"[\s,;]+", raw.split("#", 1)[0]) if t]
        if not tokens:
            continue
        if not points and _is_csv_header(tokens):
            continue
        if len(tokens) != 2:
            raise fail(source, f"expected 2 numbers (x y), found {len(tokens)}",
                        f"line {number}")
        points.append([to_float(t, source, f"line {number}") for t in tokens])
        line_numbers.append(number)
    return points, line_numbers


_HEADER_WORD = re.compile(r"[xy](_\w*)?|lon|lng|long|longitude|lat|latitude|east(ing)?|north(ing)?")


def _is_csv_header(tokens) -> bool:
    """A first data line such as ``x,y`` in a CSV export is a header, not data."""
    return len(tokens) == 2 and all(_HEADER_WORD.fullmatch(t.lower()) for t in tokens)


def polygon_to_text(vertices, comment: str | None = None) -> str:
    """Plain text format: optional ``#`` comment lines, then one ``x y`` per line."""
    array = np.asarray(vertices, dtype=float).reshape(-1, 2)
    head = [f"# {line}".rstrip() for line in (comment or "").splitlines()]
    body = [f"{float(x)!r} {float(y)!r}" for x, y in array]
    return "\n".join(head + body) + "\n"


# ---------------------------------------------------------- JSON and GeoJSON

def _parse_json(text: str, source: str):
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise fail(source, f"not valid JSON ({error.msg})", f"line {error.lineno}") from None
    if isinstance(data, list):
        return _ring_from_positions(data, source), None
    if isinstance(data, dict):
        return _ring_from_positions(_geojson_ring(data, source), source), None
    raise fail(source, "JSON must be a list of [x, y] pairs or a GeoJSON object")


def _geojson_polygons(obj, source: str) -> list:
    """All polygons (each a list of rings) found in a GeoJSON object."""
    if not isinstance(obj, dict):
        raise fail(source, "GeoJSON geometry or feature must be an object")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        return [p for f in obj.get("features") or [] for p in _geojson_polygons(f, source)]
    if kind == "Feature":
        if obj.get("geometry") is None:
            raise fail(source, "the GeoJSON Feature has no geometry")
        return _geojson_polygons(obj["geometry"], source)
    if kind == "GeometryCollection":
        return [p for g in obj.get("geometries") or [] for p in _geojson_polygons(g, source)]
    coordinates = obj.get("coordinates")
    if kind == "Polygon" and isinstance(coordinates, list):
        return [coordinates]
    if kind == "MultiPolygon" and isinstance(coordinates, list):
        return list(coordinates)
    raise fail(source, f"GeoJSON type {kind!r} is not a Polygon, Feature or FeatureCollection")


def _geojson_ring(obj: dict, source: str) -> list:
    polygons = _geojson_polygons(obj, source)
    if len(polygons) != 1:
        raise fail(source, f"the GeoJSON holds {len(polygons)} polygons; exactly one is needed")
    rings = polygons[0]
    if not isinstance(rings, list) or not rings:
        raise fail(source, "the GeoJSON polygon has no coordinates")
    if len(rings) > 1:
        raise fail(source, "the polygon has holes; holes are not supported")
    return rings[0]


def _ring_from_positions(positions, source: str) -> list:
    if not isinstance(positions, list):
        raise fail(source, "expected a list of [x, y] positions")
    points = []
    for index, position in enumerate(positions, start=1):
        where = f"vertex {index}"
        if not isinstance(position, list) or len(position) not in (2, 3):
            raise fail(source, f"expected [x, y], found {json.dumps(position)[:40]}", where)
        points.append([to_float(value, source, where) for value in position[:2]])
    return points


# ------------------------------------------------------------------------ WKT

def _parse_wkt(text: str, source: str):
    try:
        geometry = shapely.wkt.loads(text.strip())
    except (ShapelyError, ValueError) as error:
        raise fail(source, f"not valid WKT ({str(error)[:80]})") from None
    if isinstance(geometry, MultiPolygon):
        if len(geometry.geoms) != 1:
            raise fail(source, f"the MULTIPOLYGON has {len(geometry.geoms)} parts; exactly one is needed")
        geometry = geometry.geoms[0]
    if not isinstance(geometry, Polygon):
        raise fail(source, f"WKT {geometry.geom_type.upper()} is not a POLYGON")
    if geometry.is_empty:
        raise fail(source, "the WKT polygon is empty")
    if geometry.interiors:
        raise fail(source, "the polygon has holes; holes are not supported")
    return [list(c[:2]) for c in geometry.exterior.coords], None


# ----------------------------------------------------------------- dispatch

_PARSERS = {"txt": _parse_txt, "geojson": _parse_json, "json": _parse_json,
            "wkt": _parse_wkt, "svg": parse_svg}


def _detect_format(text: str, source: str) -> str:
    by_extension = EXTENSIONS.get(Path(source).suffix.lower())
    if by_extension:
        return by_extension
    start = text.lstrip()[:20]
    if start.startswith("<"):
        return "svg"
    if start.startswith("{"):
        return "geojson"
    if start.startswith("["):
        return "json"
    if re.match(r"(MULTI)?POLYGON\b", start, re.IGNORECASE):
        return "wkt"
    return "txt"


def parse_polygon(text: str, source: str = "<input>", fmt: str | None = None) -> np.ndarray:
    """Parse polygon text in any supported format and validate it."""
    if len(text) > MAX_BYTES or len(text.encode("utf-8")) > MAX_BYTES:
        raise fail(source, f"is larger than {MAX_BYTES // 1_000_000} MB; that is too large "
                    "to be a polygon file")
    text = text.lstrip("\ufeff")
    if not text.strip():
        raise fail(source, "is empty; expected polygon vertices")
    fmt = (fmt or _detect_format(text, source)).lower()
    if fmt not in _PARSERS:
        raise fail(source, f"unknown format {fmt!r}; use one of {', '.join(FORMATS)}")
    try:
        points, line_numbers = _PARSERS[fmt](text, source)
        if not points:
            raise fail(source, "contains no vertices")
        return validate_polygon(points, source, line_numbers=line_numbers)
    except ShapeError:
        raise
    except MemoryError:
        # A file of at most 1 MB runs out of memory only under a limit: the page's reader, whose child says
        # how much it was allowed (sandbox/shapes/isolated.py); read here it came out as a parse error.
        raise
    except (RecursionError, ArithmeticError, ValueError, TypeError) as error:
        # Whatever a parser or a check gives up with (JSON nested 100,000 deep, ...) is the file's fault.
        raise fail(source, f"could not be read as {fmt.upper()} ({type(error).__name__}: "
                   f"{str(error)[:60] or 'no details'})") from None


def load_polygon(path) -> np.ndarray:
    """Read a polygon file (at most 1 MB of UTF-8 text) and parse it."""
    path = Path(path).expanduser()
    name = path.name
    if not path.is_file():
        raise fail(name, f"no such file ({path})")
    if path.stat().st_size > MAX_BYTES:
        raise fail(name, f"is {path.stat().st_size / 1e6:.1f} MB; polygon files must be "
                    f"under {MAX_BYTES // 1_000_000} MB")
    with path.open("rb") as handle:
        data = handle.read(MAX_BYTES + 1)
    return read_polygon_bytes(data, name)


def read_polygon_bytes(data: bytes, name: str) -> np.ndarray:
    """A polygon file's bytes (an upload, or a file read by :func:`load_polygon`) parsed; ``name``
    gives the format by its extension and names the file in messages."""
    if len(data) > MAX_BYTES:
        raise fail(name, f"is larger than {MAX_BYTES // 1_000_000} MB; that is too large "
                    "to be a polygon file")
    if b"\x00" in data:
        raise fail(name, "looks like a binary file, not a text polygon file")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise fail(name, f"is not UTF-8 text (bad byte at offset {error.start})") from None
    return parse_polygon(text, source=name)
