"""The built-in goal shapes: the files of the repository's shapes/ folder,
by name."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from sandbox.shapes.errors import ShapeError
from sandbox.shapes.formats import EXTENSIONS, load_polygon
from sandbox.shapes.generator import generated_vertices

# ``builtin`` is a link to the repository's shapes/ folder, copied into
# wheels, so built-in names work in editable and regular installs.
SHAPES_DIR = (Path(__file__).parent / "builtin").resolve()


def _shapes_dir() -> Path:
    override = os.environ.get("PHOTOTAXIS_SHAPES_DIR")
    return Path(override) if override else SHAPES_DIR


def _builtin_files() -> dict[str, Path]:
    folder = _shapes_dir()
    if not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.iterdir())
            if p.is_file() and p.suffix.lower() in EXTENSIONS and not p.name.startswith(".")}


def builtin_shape_names() -> list[str]:
    """"circle" first, then the stems of the files in the shapes folder, sorted."""
    return ["circle"] + sorted(_builtin_files())


def shape_vertices(spec: str) -> np.ndarray | None:
    """Vertices for a built-in shape name, a file path or a generated shape's name (``gen-star-0007``,
    :mod:`sandbox.shapes.generator`); None for "circle"."""
    spec = str(spec).strip()
    if spec.lower() == "circle":
        return None
    builtins = {name.lower(): path for name, path in _builtin_files().items()}
    if spec.lower() in builtins:
        return load_polygon(builtins[spec.lower()])
    if spec and Path(spec).expanduser().is_file():
        return load_polygon(spec)
    generated = generated_vertices(spec)
    if generated is not None:
        return generated
    raise ShapeError(f"{spec or '<empty>'}: not a built-in shape, an existing file or a generated shape "
                     f"(gen-FAMILY-SEED); built-in shapes are: {', '.join(builtin_shape_names())}")
