"""Outlines a designer starts a drawing from: letters and simple figures,
as vertices in metres, counter-clockwise, the bounding box's lower-left
corner at the origin.

They are drawn on round numbers so that they sit on the drawing grid
(0.5 m by default) and stay easy to edit point by point: the figures on
2 m strokes inside a 6 m square (an L with 6 m arms), the letters on a
3 x 5 grid of 1.5 m cells. Their size does not matter for the goal, which
is always scaled to the boxes' total area; it matters for how they look
on the floor while being edited.
"""

from __future__ import annotations

import numpy as np

#: Stroke width of the figures (m); they fill a FIGURE x FIGURE square.
STROKE = 2.0
FIGURE = 6.0
#: Side of a letter's grid cell (m); a letter is 3 cells wide and 5 tall.
CELL = 1.5


def _figure(points) -> np.ndarray:
    return np.array(points, dtype=float)


def _letter(cells) -> np.ndarray:
    return np.array(cells, dtype=float) * CELL


def l_shape() -> np.ndarray:
    """Two 6 m arms, 2 m wide, meeting at the lower-left corner (area 20 m²)."""
    return _figure([(0, 0), (6, 0), (6, 2), (2, 2), (2, 6), (0, 6)])


def t_shape() -> np.ndarray:
    """A 6 x 2 m bar on a 2 x 4 m stem (area 20 m²)."""
    return _figure([(2, 0), (4, 0), (4, 4), (6, 4), (6, 6), (0, 6), (0, 4), (2, 4)])


def u_shape() -> np.ndarray:
    """A 6 m square less a 2 x 4 m slot from the top (area 28 m²)."""
    return _figure([(0, 0), (6, 0), (6, 6), (4, 6), (4, 2), (2, 2), (2, 6), (0, 6)])


def c_shape() -> np.ndarray:
    """A 6 m square less a 4 x 2 m slot from the right (area 28 m²)."""
    return _figure([(0, 0), (6, 0), (6, 2), (2, 2), (2, 4), (6, 4), (6, 6), (0, 6)])


def plus() -> np.ndarray:
    """Two 6 x 2 m bars crossing at their middles (area 20 m²)."""
    return _figure([(2, 0), (4, 0), (4, 2), (6, 2), (6, 4), (4, 4), (4, 6), (2, 6), (2, 4), (0, 4), (0, 2),
                    (2, 2)])


def arrow() -> np.ndarray:
    """A 3 x 2 m shaft and a head 3 m long, 6 m wide, pointing right (area 15 m²)."""
    return _figure([(0, 2), (3, 2), (3, 0), (6, 3), (3, 6), (3, 4), (0, 4)])


def house() -> np.ndarray:
    """A 6 x 4 m wall under a 3 m high roof (area 33 m²)."""
    return _figure([(0, 0), (6, 0), (6, 4), (3, 7), (0, 4)])


def letter_e() -> np.ndarray:
    """E: a stem and three bars, the middle one shorter (10 cells)."""
    return _letter([(0, 0), (3, 0), (3, 1), (1, 1), (1, 2), (2, 2), (2, 3), (1, 3), (1, 4), (3, 4), (3, 5),
                    (0, 5)])


def letter_f() -> np.ndarray:
    """F: a stem, a top bar and a shorter middle one (8 cells)."""
    return _letter([(0, 0), (1, 0), (1, 2), (2, 2), (2, 3), (1, 3), (1, 4), (3, 4), (3, 5), (0, 5)])


def letter_h() -> np.ndarray:
    """H: two stems joined in the middle (11 cells)."""
    return _letter([(0, 0), (1, 0), (1, 2), (2, 2), (2, 0), (3, 0), (3, 5), (2, 5), (2, 3), (1, 3), (1, 5),
                    (0, 5)])


def letter_s() -> np.ndarray:
    """S: three bars joined right below the middle and left above it (11 cells)."""
    return _letter([(0, 0), (3, 0), (3, 3), (1, 3), (1, 4), (3, 4), (3, 5), (0, 5), (0, 2), (2, 2), (2, 1),
                    (0, 1)])


def letter_z() -> np.ndarray:
    """Z: two bars joined by a slanted stroke one cell wide (9 cells)."""
    return _letter([(0, 0), (3, 0), (3, 1), (1, 1), (3, 4), (3, 5), (0, 5), (0, 4), (2, 4), (0, 1)])


#: The templates by the name the panel shows, in the order it lists them.
TEMPLATES = {
    "L": l_shape, "T": t_shape, "U": u_shape, "C": c_shape, "plus": plus, "arrow": arrow, "house": house,
    "letter E": letter_e, "letter F": letter_f, "letter H": letter_h, "letter S": letter_s,
    "letter Z": letter_z,
}


def template_names() -> list[str]:
    return list(TEMPLATES)


def template_vertices(name: str) -> np.ndarray:
    """The template's vertices (a fresh array: the caller may move them)."""
    return TEMPLATES[name]()


def placed(vertices: np.ndarray, centre: tuple[float, float], step: float = 0.0) -> np.ndarray:
    """``vertices`` moved so that their bounding box is centred on ``centre``, the
    move rounded to ``step`` (when positive) so that grid points stay on the grid."""
    v = np.asarray(vertices, dtype=float)
    shift = np.asarray(centre, dtype=float) - (v.min(axis=0) + v.max(axis=0)) / 2.0
    if step > 0:
        shift = np.round(shift / step) * step
    return v + shift
