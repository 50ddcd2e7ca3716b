"""SVG goal shapes: one ``<polygon>``, ``<polyline>``, ``<rect>`` or ``<path>``.

Parsing, units, nested transforms and curves are `svgelements`' job (it
reads SVG as a browser does); this module picks the one shape and turns it
into an outline: straight segments give their end points, curves and arcs
are flattened into short straight pieces.
"""

from __future__ import annotations

import io
import re
import xml.etree.ElementTree as ET

import numpy as np
import svgelements as svg

from sandbox.shapes.errors import fail
from sandbox.shapes.svg_budget import NUMBER, check_svg_budget

#: Points a curve or arc is flattened into (per segment).
CURVE_POINTS = 16
#: What may stand between the numbers of a points attribute (svgelements skips anything else silently).
_SEPARATORS = re.compile(r"[\s,]*")
_SHAPES = (svg.Polygon, svg.Polyline, svg.Rect, svg.Path, svg.Ellipse, svg.Circle)


def parse_svg(text: str, source: str) -> tuple[list, None]:
    if re.search(r"<!(DOCTYPE|ENTITY)", text, re.IGNORECASE):
        raise fail(source, "SVG files with <!DOCTYPE> or <!ENTITY> declarations are refused "
                   "(remove them; they can hide entity-expansion attacks)")
    try:
        root = ET.fromstring(text)  # svgelements is lenient about broken XML: be strict first
    except ET.ParseError as error:
        raise fail(source, f"not valid SVG/XML ({error})") from None
    # The outline in the file's own user units: no fitting of the view box into a viewport.
    for attribute in ("viewBox", "width", "height"):
        root.attrib.pop(attribute, None)
    check_svg_budget(root, source, CURVE_POINTS)  # before svgelements spends seconds on a flood of curves
    for element in root.iter():
        tag = str(element.tag).rsplit("}", 1)[-1]
        if tag in ("polygon", "polyline") and not _is_number_list(element.get("points", "")):
            raise fail(source, f"the <{tag}> points attribute is not a list of numbers")
    try:
        document = svg.SVG.parse(io.StringIO(ET.tostring(root, encoding="unicode")), reify=True)
    except (ValueError, IndexError, TypeError) as error:
        raise fail(source, f"not a readable SVG ({str(error)[:80] or type(error).__name__})") from None
    shapes = [e for e in document.elements() if isinstance(e, _SHAPES)]
    if len(shapes) != 1:
        raise fail(source, f"the SVG has {len(shapes)} shape elements (<polygon>, <polyline>, <rect>, <path>...); "
                   "exactly one is needed")
    points = _outline(svg.Path(shapes[0]), source)
    if not points:
        raise fail(source, "the SVG shape has no points")
    xy = np.asarray(points, dtype=float)
    xy[:, 1] *= -1.0  # SVG's y axis points down
    return xy.tolist(), None


def _is_number_list(points: str) -> bool:
    """Numbers separated by whitespace and commas. Checked by taking the numbers out, in one pass: a
    single pattern for the whole list (separators optional, so "1111" is 1, 11 and 1 too) tried
    every split of a long run of digits before a stray letter, 10 s for sixteen digits."""
    return _SEPARATORS.fullmatch(NUMBER.sub(" ", points)) is not None


def _outline(path: svg.Path, source: str) -> list:
    """The points of a single closed or open subpath, curves flattened."""
    path.reify()
    points: list = []
    subpaths = 0
    for segment in path:
        if isinstance(segment, svg.Move):
            subpaths += 1
            if subpaths > 1 and len(points) > 1:
                raise fail(source, "the SVG path has more than one subpath; holes and separate pieces "
                           "are not supported")
            points = [(segment.end.x, segment.end.y)]
        elif isinstance(segment, svg.Close):
            subpaths += 1  # anything after a close is a second piece
        elif isinstance(segment, svg.Line):
            points.append((segment.end.x, segment.end.y))
        else:  # a curve or an arc
            t = np.linspace(0.0, 1.0, CURVE_POINTS + 1)[1:]
            points.extend((float(x), float(y)) for x, y in np.asarray(segment.npoint(t)))
    return points
