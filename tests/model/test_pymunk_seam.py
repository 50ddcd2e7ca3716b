"""Only sandbox/model/pymunk_seam.py names pymunk's private code, its table lists exactly the pieces it
uses, and the installed pymunk has each of them (as tests/app/web/test_viser_seam.py does for viser).

pymunk's private names are read from the installed pymunk's own source, so a new pymunk brings its
own; Chipmunk's C functions and types (``cpBody...``), reached only through pymunk's private cffi
module, count as private too."""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import numpy as np
import pymunk
import pytest

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from sandbox.model import pymunk_seam
from sandbox.model.pymunk_seam import BODY, C_FUNCTION, C_TYPE, USES, PymunkMismatch, Use, missing
from tests.private_names import is_private, is_private_module, is_self, private_names_defined_in

ROOT = Path(__file__).resolve().parents[2]
SANDBOX = ROOT / "sandbox"
SEAM = SANDBOX / "model" / "pymunk_seam.py"
#: A name of Chipmunk's C library (a function, a type).
CHIPMUNK_NAME = re.compile(r"cp[A-Z]\w*")


@functools.cache
def pymunks_private_names() -> frozenset[str]:
    """Every private name pymunk's own code defines: its private modules, the module- and class-level names
    of its modules, and every ``self._x`` they assign."""
    paths = sorted(Path(pymunk.__file__).resolve().parent.glob("*.py"))
    names = {path.stem for path in paths if is_private(path.stem)} | private_names_defined_in(paths)
    return frozenset(names)


def private_uses(source: str, private: frozenset[str]) -> list[tuple[int, str]]:
    """(line, name) of each piece of pymunk's private code ``source`` names, outside docstrings: a private
    pymunk module it imports (and what it imports from one), one of pymunk's private names looked up on an
    object other than its own ``self`` / ``cls``, and Chipmunk's C names, as attributes or strings."""
    if ("pymunk" not in source and not CHIPMUNK_NAME.search(source)
            and not private.intersection(re.findall(r"_\w+", source))):
        return []  # (no name to find: not worth parsing)
    found, docstrings = [], set()
    for node in ast.walk(ast.parse(source)):  # (a node comes before its children)
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Expr):
            docstrings.add(id(node.value))
        elif isinstance(node, ast.Import):
            found += [(line, part) for alias in node.names if is_private_module(alias.name, "pymunk")
                      for part in alias.name.split(".")[1:] if is_private(part)]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if is_private_module(node.module, "pymunk"):
                found += [(line, part) for part in node.module.split(".")[1:] if is_private(part)]
                found += [(line, alias.name) for alias in node.names]
            elif node.module.split(".")[0] == "pymunk":
                found += [(line, alias.name) for alias in node.names if is_private(alias.name)]
        elif isinstance(node, ast.Attribute) and not is_self(node.value) and (
                node.attr in private or CHIPMUNK_NAME.fullmatch(node.attr)):
            found.append((line, node.attr))
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
              and (node.value in private or CHIPMUNK_NAME.fullmatch(node.value))):
            found.append((line, node.value))
    return found


def declared(uses: tuple[Use, ...]) -> set[str]:
    """The names the rows of ``uses`` declare: their names, and the private parts of where they are."""
    return {name for use in uses for name in
            [*use.names, *(part for part in re.split(r"[.:]", use.where) if is_private(part))]}


def seam_code() -> str:
    """The seam's source without its table (whose strings name every piece whether used or not)."""
    tree = ast.parse(SEAM.read_text(encoding="utf-8"))
    tree.body = [node for node in tree.body
                 if not (isinstance(node, ast.AnnAssign) and getattr(node.target, "id", "") == "USES")]
    return ast.unparse(tree)


# ------------------------------------------------------------------ no trespass
def test_pymunks_private_names_are_read_from_pymunk_itself():
    private = pymunks_private_names()
    assert {"_chipmunk_cffi", "_body", "_space", "_shapes", "_callbacks"} <= private
    assert not {"_", "__init__", "batch", "Body", "velocity"} & private


def test_the_guard_sees_every_way_to_reach_pymunks_private_code():
    private = pymunks_private_names()
    samples = {"from pymunk._chipmunk_cffi import ffi, lib": 3, "import pymunk._chipmunk_cffi": 1,
               "from pymunk import _chipmunk_cffi": 1, "pointer = body._body": 1, "lib.cpBodySetVelocity(b, v)": 1,
               "ffi.cast('cpBodyVelocityFunc', 1)": 1, "getattr(body, '_space')": 1,
               # our own private state, pymunk's public API, and words in a docstring are fine
               "self._body = 1\nself._space.step(1)": 0, "import pymunk.batch\npymunk.Body().velocity": 0,
               "def f():\n    '''cpBodySetVelocity through _body'''": 0}
    for source, count in samples.items():
        assert len(private_uses(source, private)) == count, source


def test_only_the_seam_names_pymunks_private_code():
    private = pymunks_private_names()
    found = {str(path.relative_to(ROOT)): uses for path in sorted(SANDBOX.rglob("*.py")) if path != SEAM
             for uses in [private_uses(path.read_text(encoding="utf-8"), private)] if uses}
    assert not found, f"pymunk's private code outside sandbox/model/pymunk_seam.py (add it there, with a row): {found}"


# ------------------------------------------------------------------ the table says what the seam uses
def test_the_table_lists_exactly_what_the_seam_uses():
    used = {name for _, name in private_uses(seam_code(), pymunks_private_names())}
    assert {"_chipmunk_cffi", "_body", "cpBodySetVelocity", "cpBodyVelocityFunc"} <= used
    assert used - declared(USES) == set(), "the seam uses these without a row in USES"
    assert declared(USES) - used == set(), "rows of USES that the seam no longer uses"


@pytest.mark.parametrize("row", range(len(USES)), ids=[use.what for use in USES])
def test_removing_a_row_still_used_fails(row):
    used = {name for _, name in private_uses(seam_code(), pymunks_private_names())}
    assert used - declared(USES[:row] + USES[row + 1:]), f"nothing would notice row {USES[row].what!r} removed"


# ------------------------------------------------------------------ the installed pymunk
def test_the_installed_pymunk_has_every_piece_of_the_table_and_is_the_one_pinned():
    assert missing() == []
    pymunk_seam.check()
    assert pymunk.version == pymunk_seam.WRITTEN_FOR
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    assert f"pymunk=={pymunk_seam.WRITTEN_FOR}" in dependencies


def test_each_way_of_checking_finds_a_missing_piece():
    cffi = pymunk_seam.CFFI
    rows = {
        Use("-", "pymunk._no_such_module", "-"): "pymunk._no_such_module",
        Use("-", cffi, "-", names=("lib", "gone")): f"{cffi}:gone",
        Use("-", f"{cffi}:no_such_object", "-", C_FUNCTION, names=("cpX",)): f"{cffi}:no_such_object",
        Use("-", f"{cffi}:lib", "-", C_FUNCTION, names=("cpBodySetVelocity", "cpNoSuchFunction")):
            f"{cffi}:lib.cpNoSuchFunction",
        Use("-", f"{cffi}:ffi", "-", C_TYPE, names=("cpBodyVelocityFunc", "cpNoSuchType")): f"{cffi}:ffi.cpNoSuchType",
        Use("-", "pymunk:Body._body", "-", BODY, names=("_body", "_no_such_state")): "pymunk:Body._no_such_state",
    }
    for row, piece in rows.items():
        assert missing((row,)) == [piece], row


def test_a_world_is_refused_in_one_line_on_a_pymunk_without_a_piece(monkeypatch):
    from sandbox.model.config import Config
    from sandbox.model.world import World

    monkeypatch.setattr(pymunk_seam, "USES", USES + (Use("-", f"{pymunk_seam.CFFI}:lib", "-", C_FUNCTION,
                                                         names=("cpNoSuchFunction",)),))
    monkeypatch.setattr(pymunk_seam, "_installed_lacks", functools.cache(lambda: tuple(pymunk_seam.missing(pymunk_seam.USES))))
    with pytest.raises(PymunkMismatch) as refused:
        World(Config(robots=1, boxes=1), np.random.default_rng(0))
    said = str(refused.value)
    assert "\n" not in said and f"pymunk {pymunk.version} lacks" in said, said
    assert "lib.cpNoSuchFunction" in said and said.endswith(f"install pymunk=={pymunk_seam.WRITTEN_FOR}"), said
