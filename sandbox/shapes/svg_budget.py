"""How much work an SVG asks for, counted in its XML before svgelements reads it.

svgelements parses and flattens in pure Python: a 780 KB path of 30,000 arcs
took 9.5 s and 209 MB at its peak before the vertex limit could refuse the
480,000 points, and seven levels of ``<use>`` ten times each (2 KB) ask it for ten
million copies. Counting is cheap (regular expressions over the attributes,
one pass over the tree), so a file that could never be a usable goal is
refused before that work starts.

A path or a polygon counts the points svgelements would make of it, on the
low side where a file is ambiguous, so nothing usable is refused: a curve or
an arc counts the points it is flattened into, a ``<use>`` what it copies.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

from sandbox.shapes.errors import fail
from sandbox.shapes.validation import MAX_VERTICES

#: Elements an SVG may hold, each ``<use>`` counted as the elements it copies: a polygon file
#: needs one shape and a few dozen elements around it (Inkscape's metadata, groups, defs).
MAX_ELEMENTS = 10_000
#: Elements and points together: one shape at the vertex limit and room around it.
WORK_LIMIT = MAX_ELEMENTS + MAX_VERTICES
#: A number in SVG's path and points syntax ("1.5.5" is 1.5 and .5).
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_COMMANDS = "MmZzLlHhVvCcSsQqTtAa"
#: One path command and the arguments that follow it (an exponent's e is not a command).
_COMMAND_RUN = re.compile(rf"([{_COMMANDS}])([^{_COMMANDS}]*)")
#: Numbers per segment of each command; a run of n numbers repeats the command n / that times.
_ARGUMENTS = {"m": 2, "z": 0, "l": 2, "h": 1, "v": 1, "c": 6, "s": 4, "q": 4, "t": 2, "a": 7}
_STRAIGHT = frozenset("mlhv")
#: A rect with rounded corners, a circle or an ellipse: four arcs and four lines at most.
_ROUND_ARCS, _ROUND_LINES = 4, 5


def check_svg_budget(root: ET.Element, source: str, curve_points: int) -> None:
    """Refuse an SVG whose shapes or ``<use>`` copies ask for more than a goal can use."""
    elements = list(root.iter())
    if len(elements) > MAX_ELEMENTS:
        raise fail(source, f"the SVG has {len(elements):,} elements; at most {MAX_ELEMENTS:,} are read "
                   "(a goal needs one shape)")
    points = {}
    for element in elements:
        points[id(element)] = count = element_points(element, curve_points)
        if count > MAX_VERTICES:
            made = " once its curves are flattened" if _tag(element) == "path" else ""
            raise fail(source, f"the <{_tag(element)}> has more than {MAX_VERTICES:,} points{made}; at most "
                       f"{MAX_VERTICES:,} are supported (simplify the outline)")
    copies = any(_tag(element) == "use" for element in elements)
    work = expanded_work(root, points) if copies else len(elements) + sum(points.values())
    if work > WORK_LIMIT:
        raise fail(source, f"the SVG has more than {WORK_LIMIT:,} elements and points"
                   f"{' once its <use> copies are made' if copies else ''}; a goal needs one shape "
                   f"of at most {MAX_VERTICES:,} points")


def element_points(element: ET.Element, curve_points: int) -> int:
    """The points svgelements would make of this element alone (0 for anything not a shape), counted
    up to just past the vertex limit."""
    tag = _tag(element)
    if tag == "path":
        return path_points(element.get("d", ""), curve_points)
    if tag in ("polygon", "polyline"):
        return len(NUMBER.findall(element.get("points", ""))) // 2
    if tag in ("rect", "circle", "ellipse"):
        return _ROUND_ARCS * curve_points + _ROUND_LINES
    if tag == "line":
        return 2
    return 0


def path_points(d: str, curve_points: int) -> int:
    """The points a path's ``d`` is flattened into, one per straight segment and ``curve_points``
    per curve or arc, counted up to just past the vertex limit (a file of 30,000 arcs is not read
    to its end)."""
    points = 0
    for run in _COMMAND_RUN.finditer(d):
        kind = run.group(1).lower()
        if kind == "z":
            continue
        # An arc's flags may be written together ("0150" is 0, 1 and 50), which this counts as fewer
        # numbers: an estimate on the low side.
        segments = math.ceil(len(NUMBER.findall(run.group(2))) / _ARGUMENTS[kind])
        points += segments * (1 if kind in _STRAIGHT else curve_points)
        if points > MAX_VERTICES:
            break
    return points


def expanded_work(root: ET.Element, points: dict[int, int]) -> int:
    """Elements plus ``points`` (by element id) in the tree, each ``<use>`` counted as what it copies,
    up to just past :data:`WORK_LIMIT`. Iterative: a tree may be nested deeper than Python's
    recursion limit."""
    by_id = {element.get("id"): element for element in root.iter() if element.get("id")}
    work: dict[int, int] = {}
    entered: set[int] = set()
    stack: list[tuple[ET.Element, bool]] = [(root, False)]
    while stack:
        element, finished = stack.pop()
        key = id(element)
        if key in work:
            continue
        parts = list(element) + _used(element, by_id)
        if finished:
            total = 1 + points[key] + sum(work[id(part)] for part in parts)
            work[key] = min(total, WORK_LIMIT + 1)
            continue
        if key in entered:  # reached again before it was finished: it copies itself
            return WORK_LIMIT + 1
        entered.add(key)
        stack.append((element, True))
        stack.extend((part, False) for part in parts if id(part) not in work)
    return work[id(root)]


def _used(element: ET.Element, by_id: dict) -> list[ET.Element]:
    """The element a ``<use>`` copies (by ``href`` or ``xlink:href``), if it is in this file."""
    if _tag(element) != "use":
        return []
    for name, value in element.attrib.items():
        if name.rsplit("}", 1)[-1] == "href" and value.startswith("#") and value[1:] in by_id:
            return [by_id[value[1:]]]
    return []


def _tag(element: ET.Element) -> str:
    return str(element.tag).rsplit("}", 1)[-1]
