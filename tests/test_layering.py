"""Imports only go downhill: no circle between modules of ``sandbox``, and no arrow back up between its
layers (docs/code.md, "Layers").

The import graph is read from the source with ``ast``, without importing anything: every ``import`` and
``from ... import`` of a ``sandbox`` module counts, at module level, inside a function, and under
``if TYPE_CHECKING`` too (an annotation that names a module above is an arrow up all the same, and two
modules that name each other's types are one idea in two files). ``from package import name`` is an
arrow to the submodule when ``name`` is one, else to the package. What is not seen: the packages Python
imports on the way to a module (``sandbox.model`` before ``sandbox.model.goal``: a package's
``__init__`` is the door, not a dependency), and modules named only in strings, as the dispatcher's
``SUBCOMMANDS`` table and the fork server's preload do (both live at the top).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SANDBOX = Path(__file__).resolve().parent.parent / "sandbox"

#: The layers, lowest first: a module may import modules of its own unit and of lower layers only. A module's
#: unit is the longest name below that it starts with (``sandbox.shapes.geometry`` before ``sandbox.shapes``).
LAYERS: tuple[tuple[str, ...], ...] = (
    # what everything may use: numba loaded at first use, how a process is started; then polygon geometry
    ("sandbox.lazy_numba", "sandbox.processes"),
    ("sandbox.shapes.geometry",),
    ("sandbox.shapes",),        # goal polygons from files, and their checks
    ("sandbox.model",),         # the simulation (headless)
    ("sandbox.cli",),           # the flags every command shares, read into a Config
    ("sandbox.experiments", "sandbox.rl"),  # sweeps and reports; the Gymnasium environment
    ("sandbox.app",),           # the browser sandbox
    # the entry points: the dispatcher (it starts serve, record, bench --live), the fork server's preload (the
    # app's simulation process), the package's lazy ``Config`` and ``Simulation``; ``python -m sandbox``
    ("sandbox.commands", "sandbox.warm", "sandbox"),
    ("sandbox.__main__",),
)
#: The only unit that may import viser, and the commands that start it (``serve``, ``record``'s HTML replays,
#: ``bench --live``).
VISER_UNIT = "sandbox.app"
VISER_COMMANDS = {"sandbox.commands.serve", "sandbox.commands.record", "sandbox.commands.live_bench"}


# ------------------------------------------------------------------ reading the graph
def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(source: str, module: str, is_package: bool, modules: set[str]) -> set[str]:
    """Every module of ``modules`` (and every outside top-level package, such as ``viser``) that ``source``
    imports anywhere in it: module level, functions, ``if TYPE_CHECKING``."""
    package = module if is_package else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(_known(alias.name, modules) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(node, package)
            for alias in node.names:
                child = f"{base}.{alias.name}"
                found.add(child if child in modules else _known(base, modules))
    found.discard(module)
    return found


def _absolute(node: ast.ImportFrom, package: str) -> str:
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    base = parts[:len(parts) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _known(name: str, modules: set[str]) -> str:
    """``name`` if it is a module of ours, else its nearest enclosing module of ours, else its top package."""
    probe = name
    while probe and probe not in modules:
        probe = probe.rpartition(".")[0]
    return probe or name.split(".")[0]


def import_graph(root: Path = SANDBOX) -> dict[str, set[str]]:
    """module -> the modules of ``root`` (and outside top-level packages) it imports."""
    paths = {module_name(path, root): path for path in sorted(root.rglob("*.py"))}
    modules = set(paths)
    return {name: imports(path.read_text(encoding="utf-8"), name, path.name == "__init__.py", modules)
            for name, path in paths.items()}


# ------------------------------------------------------------------ what is wrong with it
def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One circle through each strongly connected group of modules (Tarjan), as ``[a, b, ..., a]``."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[set[str]] = []

    def visit(node: str) -> None:  # (the graph has a few hundred modules: recursion is fine)
        index[node] = low[node] = len(index)
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if target not in graph:
                continue
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            group = set()
            while True:
                member = stack.pop()
                group.add(member)
                if member == node:
                    break
            if len(group) > 1:
                groups.append(group)

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return [_circle(graph, group) for group in groups]


def _circle(graph: dict[str, set[str]], group: set[str]) -> list[str]:
    """A shortest circle from the group's first module back to itself, through the group."""
    start = min(group)
    paths = {start: [start]}
    frontier = [start]
    while frontier:
        following = []
        for node in frontier:
            for target in sorted(graph[node] & group):
                if target == start:
                    return paths[node] + [start]
                if target not in paths:
                    paths[target] = paths[node] + [target]
                    following.append(target)
        frontier = following
    raise AssertionError(f"no circle in {group}")


def unit_of(module: str) -> tuple[int, str] | None:
    """The (layer, unit) a module of ``sandbox`` belongs to (None for an outside package)."""
    matches = [(len(unit), layer, unit) for layer, units in enumerate(LAYERS) for unit in units
               if module == unit or module.startswith(unit + ".")]
    return max(matches)[1:] if matches else None


def arrows_up(graph: dict[str, set[str]]) -> list[str]:
    """Every import from a unit to another unit of its own layer or a higher one."""
    found = []
    for module, targets in sorted(graph.items()):
        layer, unit = unit_of(module)
        for target in sorted(targets):
            there = unit_of(target)
            if there is not None and there[1] != unit and there[0] >= layer:
                found.append(f"{module} -> {target}")
    return found


def viser_outside_the_app(graph: dict[str, set[str]]) -> list[str]:
    return [module for module, targets in sorted(graph.items())
            if "viser" in targets and unit_of(module)[1] != VISER_UNIT and module not in VISER_COMMANDS]


# ------------------------------------------------------------------ the rules
@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    return import_graph()


def test_every_module_belongs_to_a_layer(graph):
    assert all(unit_of(module) is not None for module in graph)
    assert len(graph) > 100 and "sandbox.model.simulation" in graph["sandbox.experiments.trials"]


def test_no_module_imports_itself_back(graph):
    found = cycles(graph)
    assert not found, "import circles (break each by moving what both need below them):\n" + \
        "\n".join(" -> ".join(circle) for circle in found)


def test_imports_only_go_downhill(graph):
    found = arrows_up(graph)
    assert not found, "imports against the layers of tests/test_layering.py (LAYERS, lowest first):\n" + \
        "\n".join(found)


def test_only_the_app_imports_viser(graph):
    assert "viser" in graph["sandbox.app.web.gate"]
    assert not viser_outside_the_app(graph), viser_outside_the_app(graph)


# ------------------------------------------------------------------ the reader itself
def test_the_reader_sees_every_kind_of_import(tmp_path):
    root = tmp_path / "sandbox"
    sources = {
        "__init__.py": "",
        "a/__init__.py": "from . import b\n",
        "a/b.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from sandbox.a.c import C\n",
        "a/c.py": "import sandbox.d.e\nfrom ..d import e as f\n\ndef g():\n    from sandbox.d import E\n",
        "d/__init__.py": "E = 1\n",
        "d/e.py": "import viser\nimport numpy.linalg\nfrom sandbox.a.b import x\n",
    }
    for name, text in sources.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    graph = import_graph(root)
    assert graph == {"sandbox": set(), "sandbox.a": {"sandbox.a.b"}, "sandbox.a.b": {"typing", "sandbox.a.c"},
                     "sandbox.a.c": {"sandbox.d.e", "sandbox.d"}, "sandbox.d": set(),
                     "sandbox.d.e": {"viser", "numpy", "sandbox.a.b"}}
    assert cycles(graph) == [["sandbox.a.b", "sandbox.a.c", "sandbox.d.e", "sandbox.a.b"]]


def test_an_arrow_up_and_viser_below_the_app_are_seen():
    graph = {"sandbox.shapes.validation": {"sandbox.model.geometry"}, "sandbox.model.goal": {"sandbox.shapes.errors"},
             "sandbox.experiments.advise": {"sandbox.rl.env", "sandbox.cli"}, "sandbox.model.x": {"viser"},
             "sandbox.shapes.geometry": {"sandbox.shapes.errors"}, "sandbox.app.server": {"viser"},
             "sandbox.commands.bench": {"sandbox.app.compare"}}
    assert arrows_up(graph) == ["sandbox.experiments.advise -> sandbox.rl.env",
                                "sandbox.shapes.geometry -> sandbox.shapes.errors",
                                "sandbox.shapes.validation -> sandbox.model.geometry"]
    assert viser_outside_the_app(graph) == ["sandbox.model.x"]
