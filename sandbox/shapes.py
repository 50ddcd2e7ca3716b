"""Goal-shape polygons: loading, format detection and validation (SPEC §8).

Every loader returns a float64 ``(n, 2)`` array of outline vertices in file
order, without a repeated closing vertex. Position, size and orientation are
left alone: normalising them is the engine's job (SPEC §5). Every problem is
reported as a :class:`ShapeError` whose message is one line naming the source
and, where it helps, the line number (plain text) or 1-based vertex number.
"""
from __future__ import annotations

import json
import math
import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import shapely.wkt
from shapely.errors import ShapelyError
from shapely.geometry import MultiPoint, MultiPolygon, Polygon
from shapely.validation import explain_validity

from .geometry import distances_to_edges

MAX_BYTES = 1_000_000          # "1 MB": no sane polygon file is larger
MAX_VERTICES = 10_000
MIN_RELATIVE_AREA = 1e-9       # area / (bounding-box size)^2 below this is "zero"
FORMATS = ("txt", "geojson", "wkt", "json", "svg")
_EXTENSIONS = {".txt": "txt", ".csv": "txt", ".poly": "txt", ".dat": "txt",
               ".geojson": "geojson", ".json": "json", ".wkt": "wkt", ".svg": "svg"}
# ``builtin_shapes`` is a link to the repository's shapes/ folder, copied
# into wheels, so built-in names work in editable and regular installs.
SHAPES_DIR = Path(os.environ.get("PHOTOTAXIS_SHAPES_DIR")
                  or (Path(__file__).parent / "builtin_shapes").resolve())


class ShapeError(ValueError):
    """A polygon could not be used; the message is one line a user can act on."""


def _fail(source: str, what: str, where: str | None = None) -> ShapeError:
    prefix = f"{source}, {where}" if where else source
    return ShapeError(" ".join(f"{prefix}: {what}".split()))


def _to_float(token, source: str, where: str) -> float:
    if isinstance(token, bool) or not isinstance(token, (int, float, str)):
        raise _fail(source, f"{json.dumps(token)[:40]} is not a number", where)
    try:
        value = float(token)
    except OverflowError:
        value = math.inf
    except ValueError:
        raise _fail(source, f"{str(token)[:40]!r} is not a number", where) from None
    if not math.isfinite(value):
        raise _fail(source, f"{str(token)[:40]!r} is not a finite number", where)
    return value


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
            raise _fail(source, f"expected 2 numbers (x y), found {len(tokens)}",
                        f"line {number}")
        points.append([_to_float(t, source, f"line {number}") for t in tokens])
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
        raise _fail(source, f"not valid JSON ({error.msg})", f"line {error.lineno}") from None
    if isinstance(data, list):
        return _ring_from_positions(data, source), None
    if isinstance(data, dict):
        return _ring_from_positions(_geojson_ring(data, source), source), None
    raise _fail(source, "JSON must be a list of [x, y] pairs or a GeoJSON object")


def _geojson_polygons(obj, source: str) -> list:
    """All polygons (each a list of rings) found in a GeoJSON object."""
    if not isinstance(obj, dict):
        raise _fail(source, "GeoJSON geometry or feature must be an object")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        return [p for f in obj.get("features") or [] for p in _geojson_polygons(f, source)]
    if kind == "Feature":
        if obj.get("geometry") is None:
            raise _fail(source, "the GeoJSON Feature has no geometry")
        return _geojson_polygons(obj["geometry"], source)
    if kind == "GeometryCollection":
        return [p for g in obj.get("geometries") or [] for p in _geojson_polygons(g, source)]
    coordinates = obj.get("coordinates")
    if kind == "Polygon" and isinstance(coordinates, list):
        return [coordinates]
    if kind == "MultiPolygon" and isinstance(coordinates, list):
        return list(coordinates)
    raise _fail(source, f"GeoJSON type {kind!r} is not a Polygon, Feature or FeatureCollection")


def _geojson_ring(obj: dict, source: str) -> list:
    polygons = _geojson_polygons(obj, source)
    if len(polygons) != 1:
        raise _fail(source, f"the GeoJSON holds {len(polygons)} polygons; exactly one is needed")
    rings = polygons[0]
    if not isinstance(rings, list) or not rings:
        raise _fail(source, "the GeoJSON polygon has no coordinates")
    if len(rings) > 1:
        raise _fail(source, "the polygon has holes; holes are not supported")
    return rings[0]


def _ring_from_positions(positions, source: str) -> list:
    if not isinstance(positions, list):
        raise _fail(source, "expected a list of [x, y] positions")
    points = []
    for index, position in enumerate(positions, start=1):
        where = f"vertex {index}"
        if not isinstance(position, list) or len(position) not in (2, 3):
            raise _fail(source, f"expected [x, y], found {json.dumps(position)[:40]}", where)
        points.append([_to_float(value, source, where) for value in position[:2]])
    return points


# ------------------------------------------------------------------------ WKT

def _parse_wkt(text: str, source: str):
    try:
        geometry = shapely.wkt.loads(text.strip())
    except (ShapelyError, ValueError) as error:
        raise _fail(source, f"not valid WKT ({str(error)[:80]})") from None
    if isinstance(geometry, MultiPolygon):
        if len(geometry.geoms) != 1:
            raise _fail(source, f"the MULTIPOLYGON has {len(geometry.geoms)} parts; exactly one is needed")
        geometry = geometry.geoms[0]
    if not isinstance(geometry, Polygon):
        raise _fail(source, f"WKT {geometry.geom_type.upper()} is not a POLYGON")
    if geometry.is_empty:
        raise _fail(source, "the WKT polygon is empty")
    if geometry.interiors:
        raise _fail(source, "the polygon has holes; holes are not supported")
    return [list(c[:2]) for c in geometry.exterior.coords], None


# ------------------------------------------------------------------------ SVG

_SVG_SKIP = {"defs", "clipPath", "mask", "symbol", "pattern", "marker", "metadata"}
_SVG_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_PATH_TOKEN = re.compile(rf"\s*,?\s*(?:([A-Za-z])|({_SVG_NUMBER}))")


def _parse_svg(text: str, source: str):
    if re.search(r"<!(DOCTYPE|ENTITY)", text, re.IGNORECASE):
        raise _fail(source, "SVG files with <!DOCTYPE> or <!ENTITY> declarations are refused "
                    "(remove them; they can hide entity-expansion attacks)")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise _fail(source, f"not valid SVG/XML ({error})") from None
    found = list(_svg_shapes(root, np.eye(3)))
    if len(found) != 1:
        raise _fail(source, f"the SVG has {len(found)} <polygon>/<polyline>/<path> elements; "
                    "exactly one is needed")
    element, matrix = found[0]
    if _local(element.tag) == "path":
        points = _svg_path_points(element.get("d", ""), source)
    else:
        text_points = element.get("points", "")
        if not re.fullmatch(rf"(?:[\s,]*{_SVG_NUMBER})*[\s,]*", text_points):
            raise _fail(source, f"the <{_local(element.tag)}> points attribute is not a list of numbers")
        numbers = [float(n) for n in re.findall(_SVG_NUMBER, text_points)]
        if len(numbers) % 2:
            raise _fail(source, "the <polygon> points attribute has an odd number of values")
        points = list(zip(numbers[0::2], numbers[1::2]))
    if not points:
        raise _fail(source, "the SVG shape has no points")
    homogeneous = np.column_stack([np.asarray(points, float), np.ones(len(points))])
    xy = (homogeneous @ matrix.T)[:, :2]
    xy[:, 1] *= -1.0                       # SVG's y axis points down
    return xy.tolist(), None


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _svg_shapes(element, matrix):
    """Yield (shape element, accumulated transform) in document order."""
    if _local(element.tag) in _SVG_SKIP:
        return
    matrix = matrix @ _svg_transform(element.get("transform", ""))
    if _local(element.tag) in ("polygon", "polyline", "path"):
        yield element, matrix
    for child in element:
        yield from _svg_shapes(child, matrix)


def _svg_transform(text: str) -> np.ndarray:
    result = np.eye(3)
    for name, args in re.findall(r"(\w+)\s*\(([^)]*)\)", text):
        given = [float(n) for n in re.findall(_SVG_NUMBER, args)]
        v = given + [0.0] * 6
        if name == "matrix":
            m = [[v[0], v[2], v[4]], [v[1], v[3], v[5]], [0, 0, 1]]
        elif name == "translate":
            m = [[1, 0, v[0]], [0, 1, v[1]], [0, 0, 1]]
        elif name == "scale":
            sy = given[1] if len(given) > 1 else v[0]
            m = [[v[0], 0, 0], [0, sy, 0], [0, 0, 1]]
        elif name == "rotate":
            c, s = math.cos(math.radians(v[0])), math.sin(math.radians(v[0]))
            cx, cy = v[1], v[2]
            m = [[c, -s, cx - c * cx + s * cy], [s, c, cy - s * cx - c * cy], [0, 0, 1]]
        elif name == "skewX":
            m = [[1, math.tan(math.radians(v[0])), 0], [0, 1, 0], [0, 0, 1]]
        elif name == "skewY":
            m = [[1, 0, 0], [math.tan(math.radians(v[0])), 1, 0], [0, 0, 1]]
        else:
            continue
        result = result @ np.asarray(m, float)
    return result


def _path_tokens(d: str, source: str):
    position, d = 0, d.rstrip(" \t\r\n,")
    while position < len(d):
        match = _PATH_TOKEN.match(d, position)
        if not match:
            raise _fail(source, f"the <path> d attribute has unreadable text {d[position:position + 20]!r}")
        position = match.end()
        yield match.group(1) or float(match.group(2))


def _svg_path_points(d: str, source: str) -> list:
    """Vertices of a path made only of straight segments (M L H V Z)."""
    points, command, args, closed = [], None, [], False
    for token in list(_path_tokens(d, source)) + ["<end>"]:
        if isinstance(token, float):
            args.append(token)
            continue
        if command is not None:
            closed = _apply_path_command(command, args, points, closed, source)
        if token == "<end>":
            break
        if token.upper() in "CSQTA":
            raise _fail(source, f"the <path> uses the curve command {token!r}; curves are not "
                        "supported, only straight segments (M, L, H, V, Z)")
        if token.upper() not in "MLHVZ":
            raise _fail(source, f"the <path> has an unknown command {token!r}")
        command, args = token, []
    return points


def _apply_path_command(command: str, args: list, points: list, closed: bool, source: str) -> bool:
    upper, relative = command.upper(), command.islower()
    if upper == "Z":
        if args:
            raise _fail(source, "the <path> has numbers after a Z command")
        return True
    if closed or (upper == "M" and len(points) > 1):
        raise _fail(source, "the <path> has more than one subpath; holes and separate "
                    "pieces are not supported")
    arity = 2 if upper in "ML" else 1
    if not args or len(args) % arity:
        count = f"{len(args)} number{'' if len(args) == 1 else 's'}"
        raise _fail(source, f"the <path> command {command!r} has {count}; "
                    f"it needs {'pairs of numbers' if arity == 2 else 'at least one number'}")
    if upper == "M" and points:        # a lone moveto followed by another: restart
        points.clear()
    for i in range(0, len(args), arity):
        x, y = points[-1] if points else (0.0, 0.0)
        if upper in "ML":
            dx, dy = args[i], args[i + 1]
            points.append((x + dx, y + dy) if relative else (dx, dy))
        elif upper == "H":
            points.append((x + args[i] if relative else args[i], y))
        else:
            points.append((x, y + args[i] if relative else args[i]))
    return False


# ----------------------------------------------------------------- dispatch

_PARSERS = {"txt": _parse_txt, "geojson": _parse_json, "json": _parse_json,
            "wkt": _parse_wkt, "svg": _parse_svg}


def _detect_format(text: str, source: str) -> str:
    by_extension = _EXTENSIONS.get(Path(source).suffix.lower())
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
        raise _fail(source, f"is larger than {MAX_BYTES // 1_000_000} MB; that is too large "
                    "to be a polygon file")
    text = text.lstrip("\ufeff")
    if not text.strip():
        raise _fail(source, "is empty; expected polygon vertices")
    fmt = (fmt or _detect_format(text, source)).lower()
    if fmt not in _PARSERS:
        raise _fail(source, f"unknown format {fmt!r}; use one of {', '.join(FORMATS)}")
    points, line_numbers = _PARSERS[fmt](text, source)
    if not points:
        raise _fail(source, "contains no vertices")
    return validate_polygon(points, source, line_numbers=line_numbers)


def load_polygon(path) -> np.ndarray:
    """Read a polygon file (at most 1 MB of UTF-8 text) and parse it."""
    path = Path(path).expanduser()
    name = path.name
    if not path.is_file():
        raise _fail(name, f"no such file ({path})")
    if path.stat().st_size > MAX_BYTES:
        raise _fail(name, f"is {path.stat().st_size / 1e6:.1f} MB; polygon files must be "
                    f"under {MAX_BYTES // 1_000_000} MB")
    with path.open("rb") as handle:
        data = handle.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise _fail(name, f"is larger than {MAX_BYTES // 1_000_000} MB; that is too large "
                    "to be a polygon file")
    if b"\x00" in data:
        raise _fail(name, "looks like a binary file, not a text polygon file")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise _fail(name, f"is not UTF-8 text (bad byte at offset {error.start})") from None
    return parse_polygon(text, source=name)


# ---------------------------------------------------------------- validation

def validate_polygon(vertices, source: str, line_numbers=None) -> np.ndarray:
    """Check an outline and return it as float64 (n, 2), consecutive repeats dropped.

    ``line_numbers`` (one per vertex, optional) makes messages name file lines;
    otherwise they name 1-based vertex numbers.
    """
    try:
        array = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise _fail(source, "vertices must be numbers") from None
    if array.ndim != 2 or array.shape[1] != 2:
        raise _fail(source, "vertices must be (x, y) pairs")
    labels = list(line_numbers) if line_numbers is not None else list(range(1, len(array) + 1))
    kind = "line" if line_numbers is not None else "vertex"
    if len(array) > MAX_VERTICES:
        raise _fail(source, f"has {len(array):,} vertices; at most {MAX_VERTICES:,} are "
                    "supported (simplify the outline)")
    bad = np.flatnonzero(~np.isfinite(array).all(axis=1))
    if bad.size:
        raise _fail(source, f"{array[bad[0]].tolist()} is not a pair of finite numbers",
                    f"{kind} {labels[bad[0]]}")
    keep = np.ones(len(array), dtype=bool)
    keep[1:] = np.any(array[1:] != array[:-1], axis=1)
    last = np.flatnonzero(keep)[-1] if len(array) else 0
    if last > 0 and np.array_equal(array[last], array[0]):
        keep[last] = False                 # the closing repeat of the first vertex
    array, labels = array[keep], [label for label, k in zip(labels, keep) if k]
    distinct = len(np.unique(array, axis=0))
    if distinct < 3:
        raise _fail(source, f"has only {distinct} distinct vertices; a polygon needs at least 3")
    _check_area(array, source, MultiPoint(array).convex_hull.area, "all vertices lie on one line")
    _check_repeats(array, source, labels, kind)
    _check_simple(array, source, labels, kind)
    _check_area(array, source, Polygon(array).area, "the outline encloses almost nothing")
    return array


def _check_area(array: np.ndarray, source: str, area: float, why: str) -> None:
    size = float(np.ptp(array, axis=0).max())
    if size == 0.0 or area / size ** 2 < MIN_RELATIVE_AREA:
        raise _fail(source, f"the polygon has zero area ({why})")


def _check_repeats(array: np.ndarray, source: str, labels: list, kind: str) -> None:
    """A vertex visited twice makes the outline touch itself there."""
    _, first, inverse = np.unique(array, axis=0, return_index=True, return_inverse=True)
    repeats = np.flatnonzero(first[inverse.ravel()] != np.arange(len(array)))
    if repeats.size:
        i, j = int(repeats[0]), int(first[inverse.ravel()[repeats[0]]])
        x, y = array[i]
        raise _fail(source, f"repeats {kind} {labels[j]} at ({x:.6g}, {y:.6g}); the outline "
                    "must not touch itself", f"{kind} {labels[i]}")


def _check_simple(array: np.ndarray, source: str, labels: list, kind: str) -> None:
    polygon = Polygon(array)
    if polygon.is_valid:
        return
    reason = explain_validity(polygon)
    match = re.match(r"(.*?)\[(\S+) (\S+)\]", reason)
    if not match:
        raise _fail(source, f"the outline is not a simple polygon ({reason})")
    what, x, y = match.group(1).strip(), float(match.group(2)), float(match.group(3))
    verb = {"Self-intersection": "crosses itself near",
            "Ring Self-intersection": "touches itself at"}.get(what, f"is invalid ({what}) near")
    edges = _edges_near(array, (x, y))
    plural = "lines" if kind == "line" else "vertices"
    names = [f"{labels[i]}-{labels[(i + 1) % len(labels)]}" for i in edges]
    names = ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else "".join(names)
    detail = f" (edges at {plural} {names})" if edges else ""
    raise _fail(source, f"the outline {verb} ({x:.6g}, {y:.6g}){detail}")


def _edges_near(array: np.ndarray, point, limit: int = 4) -> list[int]:
    """Indices i of edges array[i] -> array[i+1] passing within a hair of point."""
    distance = distances_to_edges(np.asarray(point, dtype=float)[None, :], array)[0]
    tolerance = 1e-7 * max(float(np.ptp(array, axis=0).max()), 1e-300)
    return sorted(np.flatnonzero(distance <= tolerance).tolist())[:limit]


# ----------------------------------------------------------- built-in shapes

def _shapes_dir() -> Path:
    override = os.environ.get("PHOTOTAXIS_SHAPES_DIR")
    return Path(override) if override else SHAPES_DIR


def _builtin_files() -> dict[str, Path]:
    folder = _shapes_dir()
    if not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.iterdir())
            if p.is_file() and p.suffix.lower() in _EXTENSIONS and not p.name.startswith(".")}


def builtin_shape_names() -> list[str]:
    """"circle" first, then the stems of the files in the shapes folder, sorted."""
    return ["circle"] + sorted(_builtin_files())


def shape_vertices(spec: str) -> np.ndarray | None:
    """Vertices for a built-in shape name or a file path; None for "circle"."""
    spec = str(spec).strip()
    if spec.lower() == "circle":
        return None
    builtins = {name.lower(): path for name, path in _builtin_files().items()}
    if spec.lower() in builtins:
        return load_polygon(builtins[spec.lower()])
    if spec and Path(spec).expanduser().is_file():
        return load_polygon(spec)
    raise ShapeError(f"{spec or '<empty>'}: not a built-in shape or an existing file; "
                     f"built-in shapes are: {', '.join(builtin_shape_names())}")
