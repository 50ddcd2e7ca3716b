"""Goal shapes: polygon files in every format the sandbox reads, their
validation, and the built-in shapes.

- :mod:`.formats`     plain text, JSON / GeoJSON, WKT: parse and load
- :mod:`.svg`         SVG (through svgelements)
- :mod:`.svg_budget`  what an SVG asks for, counted before it is read
- :mod:`.isolated`    a file read in a child process, under a time and memory limit (uploads)
- :mod:`.validation`  what makes an outline usable
- :mod:`.geometry`    pure polygon geometry, below the shapes' other modules and the model
- :mod:`.builtin`     the shapes/ folder, by name (and generated shapes, by theirs)
- :mod:`.generator`   random goal shapes in families, each made again from its family and seed
"""

from sandbox.shapes.builtin import builtin_shape_names, shape_vertices
from sandbox.shapes.errors import ShapeError
from sandbox.shapes.formats import FORMATS, MAX_BYTES, load_polygon, parse_polygon, polygon_to_text
from sandbox.shapes.validation import MAX_VERTICES, validate_polygon

__all__ = ["FORMATS", "MAX_BYTES", "MAX_VERTICES", "ShapeError", "builtin_shape_names", "load_polygon",
           "parse_polygon", "polygon_to_text", "shape_vertices", "validate_polygon"]
