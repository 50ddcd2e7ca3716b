"""Reading a library's private names from its own source, for the seam tests (viser's in
tests/app/web/test_viser_seam.py, pymunk's in tests/model/test_pymunk_seam.py): what counts as private,
and which private names a set of modules defines."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Iterable


def is_private(name: str) -> bool:
    return name.startswith("_") and name != "_" and not (name.startswith("__") and name.endswith("__"))


def is_self(node: ast.expr) -> bool:
    return isinstance(node, ast.Name) and node.id in ("self", "cls")


def is_private_module(dotted: str, package: str) -> bool:
    """``dotted`` is one of ``package``'s private modules (``viser._messages``, ``pymunk._chipmunk_cffi``)."""
    parts = dotted.split(".")
    return parts[0] == package and any(is_private(part) for part in parts[1:])


def private_names_defined_in(paths: Iterable[Path]) -> set[str]:
    """The private module- and class-level names (functions, classes, assignments, imports) the modules at
    ``paths`` define, and every ``self._x`` they assign."""
    names: set[str] = set()
    for path in paths:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for scope in [tree, *(node for node in ast.walk(tree) if isinstance(node, ast.ClassDef))]:
            for statement in scope.body:
                names.update(_defined_by(statement))
        names.update(node.attr for node in ast.walk(tree)
                     if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) and is_self(node.value))
    return {name for name in names if is_private(name)}


def _defined_by(statement: ast.stmt) -> list[str]:
    if isinstance(statement, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return [statement.name]
    if isinstance(statement, (ast.Import, ast.ImportFrom)):
        return [alias.asname or alias.name.split(".")[0] for alias in statement.names]
    targets = (statement.targets if isinstance(statement, ast.Assign)
               else [statement.target] if isinstance(statement, (ast.AnnAssign, ast.AugAssign)) else [])
    return [node.id for target in targets for node in ast.walk(target) if isinstance(node, ast.Name)]
