"""Nothing a user names is ever markup (issue 54, item 1): :func:`sandbox.app.panel.plain.plain` on
hostile text, and a reading of ``sandbox/app``'s code that every piece of text reaching a markdown
panel is our own words, a number, or passed through ``plain``. (The same names in a real browser:
tests/browser/test_browser_names.py.)"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

from sandbox.app.panel.plain import plain

ROOT = Path(__file__).resolve().parents[3]
APP = ROOT / "sandbox" / "app"


# ---------------------------------------------------------------- the escape


@pytest.mark.parametrize("text, markdown", [
    ("star.txt", r"star\.txt"),
    ("<style>*{display:none}", "\\<style\\>\\*\\{display\\:\u2060none\\}"),
    ('<iframe srcdoc="<img src=x onerror=alert(1)>">.txt',
     r'\<iframe srcdoc\=\"\<img src\=x onerror\=alert\(1\)\>\"\>\.txt'),
    ("![x](https://evil.example/p.png)", "\\!\\[x\\]\\(https\\:\u2060\\/\\/evil\\.example\\/p\\.png\\)"),
    ("[click](javascript:alert(1))", "\\[click\\]\\(javascript\\:\u2060alert\\(1\\)\\)"),
    ("www.evil.example WWW.x a@b.co", "www\u2060\\.evil\\.example WWW\u2060\\.x a\\@\u2060b\\.co"),
    ("&lt;b&gt; &#60;", r"\&lt\;b\&gt\; \&\#60\;"),
    ("`code` **bold** _it_ ~~gone~~", r"\`code\` \*\*bold\*\* \_it\_ \~\~gone\~\~"),
    ("# title", r"\# title"),
    ("a | b", r"a \| b"),
    ("back\\slash", r"back\\slash"),
    ("line one\n\n    # two\r\n- three\tfour", r"line one \# two \- three four"),
    ("nul\x00bell\x07c1\x85sep\u2028end", "nul bell c1 sep end"),
    ("Zoë 12 ∑ 😀", "Zoë 12 ∑ 😀"),
    (42, "42"),
])
def test_plain_escapes_every_markdown_and_html_character(text, markdown):
    assert plain(text) == markdown


def test_plain_leaves_no_unescaped_markup_character_in_any_ascii_text():
    every_ascii = "".join(map(chr, range(128)))
    escaped = plain(every_ascii * 2)
    # Take the escapes away: no punctuation is left bare, no line is broken.
    bare = re.sub(r"\\[!-/:-@\[-`{-~]", "", escaped)
    assert not re.search(r"[!-/:-@\[-`{-~]", bare) and "\n" not in escaped


# ---------------------------------------------------------------- every markdown writer

#: Text that reaches a markdown panel without ``plain``, read and found to be ours: each entry is
#: (module, the expression as written) -> why it is safe. A new entry needs the same care: a name,
#: a file's word or an error message never belongs here.
OURS = {
    # numbers the app counts or measures
    ("panel/advice.py", "self._progress"): "(trials done, trials in all): two ints",
    ("panel/challenge.py", "gain.boxes"): "a count of boxes",
    ("panel/challenge.py", "gain.started"): "a count of boxes",
    ("panel/advice.py", "self.seeds"): "an int",
    ("panel/challenge.py", "gain.brought"): "a count of boxes",
    ("panel/draw.py", "n"): "a count of points",
    ("panel/draw.py", "selected"): "a point's index",
    ("panel/inspector.py", "index"): "a robot's index",
    ("panel/metrics.py", "s.boxes_escaped"): "a count of boxes",
    ("panel/presenter.py", "cfg.robots"): "an int, in the model's range",
    ("panel/presenter.py", "cfg.boxes"): "an int, in the model's range",
    ("panel/run.py", "snap.cycle"): "an int",
    ("panel/run.py", "snap.seed"): "an int",
    ("panel/run.py", "cfg.robots"): "an int, in the model's range",
    ("panel/run.py", "cfg.boxes"): "an int, in the model's range",
    ("sandbox/experiments/advise.py", "enumerate(results, 1)"): "a rank (the candidate's label is below)",
    ("sandbox/experiments/pace.py", "divmod(seconds, 60)"): "minutes and seconds: ints",
    ("sandbox/experiments/pace.py", "seconds"): "seconds: an int",
    ("sandbox/model/explain.py", "strays.count"): "a count of boxes",
    ("sandbox/model/explain.py", "strays.near_goal"): "a count of boxes",
    ("sandbox/model/explain.py", "strays.against_wall"): "a count of boxes",
    ("sandbox/model/explain.py", "strays.elsewhere"): "a count of boxes",
    ("sandbox/model/explain.py", "strays.heaps"): "(corner, count): the corner's name is one of explain.py's own",
    # words of the model's own
    ("panel/run.py", "snap.phase"): "one of the model's three phase names",
    ("panel/inspector.py", "zip(names, pal.SENSOR_COLOUR_NAMES, r.sensors)"):
        "the photocells' names (model/robots.py), their dots' colours (palette.py) and readings",
    ("panel/strategies.py", "snap.family"): "'scaled' or 'offset', the model's",
    ("panel/strategies.py", "words"): "the strategies' labels and the model's clauses on why each is inert "
                                      "(model/notes.py OFFSET_INERT)",
    ("sandbox/experiments/advise.py", "r.candidate.label"): "an outline and strategies, named by advise.py",
    ("sandbox/experiments/advise.py", "a.candidate.label"): "an outline and strategies, named by advise.py",
    ("sandbox/experiments/advise.py", "b.candidate.label"): "an outline and strategies, named by advise.py",
    ("sandbox/experiments/advise.py", "best.candidate.label"): "an outline and strategies, named by advise.py",
    ("sandbox/experiments/advise.py", "other.candidate.label"): "an outline and strategies, named by advise.py",
}


def _module_path(name: str) -> Path | None:
    """The file of a ``sandbox`` module, or None for anything else (viser, numpy...)."""
    if not name.startswith("sandbox"):
        return None
    base = ROOT.joinpath(*name.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.exists():
            return candidate
    return None


@functools.cache
def _parsed(path: Path) -> ast.Module:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        for child in ast.iter_child_nodes(node):
            child.parent = node  # type: ignore[attr-defined]
    return tree


def _enclosing(node: ast.AST, kinds: tuple) -> ast.AST | None:
    node = getattr(node, "parent", None)
    while node is not None and not isinstance(node, kinds):
        node = getattr(node, "parent", None)
    return node


def _own_nodes(scope: ast.AST):
    """The nodes of a function or module body, without those of the functions and classes inside it."""
    stack = list(ast.iter_child_nodes(scope))
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            stack.extend(ast.iter_child_nodes(node))


#: A format that only a number takes: a text given it raises instead of showing.
_NUMERIC_FORMAT = re.compile(r"[,_]|[bcdeEfFgGnoxX%]$")
#: Calls whose result is a number, or the text of one.
_NUMBERS = {"int", "float", "len", "round", "abs", "sum"}
#: Calls whose result is one of their arguments, or made of them: the arguments are what to check.
_SAME_AS_ARGUMENTS = {"str", "min", "max", "sorted", "reversed", "list", "tuple"}
#: Methods of a text that add nothing to it: the text itself is what to check.
_SAME_TEXT = {"upper", "lower", "strip", "rstrip", "lstrip", "capitalize", "title", "replace"}

FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef)


class Reader:
    """Follows an expression written into markdown back to where its text comes from."""

    def __init__(self) -> None:
        self.findings: list[str] = []
        self.reviewed: set[tuple[str, str]] = set()  # the entries of OURS met
        self._checked: set[tuple] = set()

    def check(self, node: ast.AST, path: Path) -> None:
        """Every piece of ``node`` (in file ``path``) is ours, a number or ``plain``'s: else a finding."""
        key = (path, id(node))
        if key in self._checked:
            return
        self._checked.add(key)
        if isinstance(node, ast.Constant):
            return
        if isinstance(node, ast.JoinedStr):
            for value in node.values:
                if isinstance(value, ast.FormattedValue):
                    spec = ast.unparse(value.format_spec)[2:-1] if value.format_spec is not None else ""
                    if not _NUMERIC_FORMAT.search(spec):
                        self.check(value.value, path)
            return
        if isinstance(node, (ast.BinOp,)):
            self.check(node.left, path)
            self.check(node.right, path)
            return
        if isinstance(node, ast.IfExp):
            self.check(node.body, path)
            self.check(node.orelse, path)
            return
        if isinstance(node, ast.BoolOp):
            for value in node.values:
                self.check(value, path)
            return
        if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
            for element in node.elts:
                self.check(element, path)
            return
        if isinstance(node, (ast.ListComp, ast.GeneratorExp, ast.SetComp)):
            self.check(node.elt, path)
            return
        if isinstance(node, ast.Starred):
            self.check(node.value, path)
            return
        if isinstance(node, ast.Subscript):
            self.check(node.value, path)
            return
        if isinstance(node, ast.Call) and self._call(node, path):
            return
        if isinstance(node, ast.Name) and self._name(node, path):
            return
        if isinstance(node, ast.Attribute) and self._attribute(node, path):
            return
        self._found(node, path)

    def _found(self, node: ast.AST, path: Path) -> None:
        module = (path.relative_to(APP) if path.is_relative_to(APP)
                  else path.relative_to(ROOT) if path.is_relative_to(ROOT) else Path(path.name)).as_posix()
        if (module, ast.unparse(node)) in OURS:
            self.reviewed.add((module, ast.unparse(node)))
        else:
            self.findings.append(f"{module}:{node.lineno}: {ast.unparse(node)}")

    # --------------------------------------------------- calls
    def _call(self, node: ast.Call, path: Path) -> bool:
        func = node.func
        if isinstance(func, ast.Name):
            if func.id == "plain" or func.id in _NUMBERS:
                return True
            if func.id in _SAME_AS_ARGUMENTS:
                for arg in node.args:
                    self.check(arg, path)
                return True
            return self._returns_of(func.id, path, node)
        if isinstance(func, ast.Attribute):
            if func.attr == "join":
                self.check(func.value, path)
                for arg in node.args:
                    self.check(arg, path)
                return True
            if func.attr in _SAME_TEXT or func.attr == "format":
                self.check(func.value, path)
                for arg in [*node.args, *(k.value for k in node.keywords)]:
                    self.check(arg, path)
                return True
            if isinstance(func.value, ast.Name) and func.value.id in ("self", "cls"):
                return self._returns_of(func.attr, path, node, method=True)
            if isinstance(func.value, ast.Name):  # module.function
                imported = self._imported_module(func.value.id, path)
                if imported is not None:
                    return self._returns_of(func.attr, imported, node)
        return False

    def _returns_of(self, name: str, path: Path, call: ast.Call, method: bool = False) -> bool:
        """What the function ``name`` (of ``path``, or imported there) returns is checked instead."""
        found = self._definition(name, path, method, call)
        if found is None:
            return False
        definition, where = found
        if isinstance(definition, FUNCTIONS):
            for node in _own_nodes(definition):
                if isinstance(node, ast.Return) and node.value is not None:
                    self.check(node.value, where)
            return True
        return False

    def _definition(self, name: str, path: Path, method: bool, near: ast.AST) -> tuple[ast.AST, Path] | None:
        tree = _parsed(path)
        if method:
            owner = _enclosing(near, (ast.ClassDef,))
            scopes = [owner] if owner is not None else []
        else:
            scopes = [tree]
        for scope in scopes:
            for statement in scope.body:
                if isinstance(statement, (*FUNCTIONS, ast.ClassDef)) and statement.name == name:
                    return statement, path
                if isinstance(statement, (ast.Assign, ast.AnnAssign)):
                    targets = statement.targets if isinstance(statement, ast.Assign) else [statement.target]
                    if any(isinstance(t, ast.Name) and t.id == name for t in targets) and statement.value:
                        return statement, path
        if not method:
            for statement in tree.body:
                if isinstance(statement, ast.ImportFrom) and statement.module:
                    for alias in statement.names:
                        if (alias.asname or alias.name) == name:
                            source = _module_path(statement.module)
                            if source is not None:
                                return self._definition(alias.name, source, False, near)
        return None

    def _imported_module(self, name: str, path: Path) -> Path | None:
        for statement in _parsed(path).body:
            if isinstance(statement, ast.ImportFrom) and statement.module:
                for alias in statement.names:
                    if (alias.asname or alias.name) == name:
                        return _module_path(f"{statement.module}.{alias.name}")
            if isinstance(statement, ast.Import):
                for alias in statement.names:
                    if alias.asname == name:
                        return _module_path(alias.name)
        return None

    # --------------------------------------------------- names
    def _name(self, node: ast.Name, path: Path) -> bool:
        scope = _enclosing(node, (*FUNCTIONS, ast.Lambda))
        while scope is not None:
            values = self._bound_in(node.id, scope)
            if values == [None]:  # a parameter: whoever calls could pass anything
                return False
            if values is not None:
                for value in values:
                    self.check(value, path)
                return True
            scope = _enclosing(scope, (*FUNCTIONS, ast.Lambda))
        found = self._definition(node.id, path, False, node)
        if found is not None and isinstance(found[0], (ast.Assign, ast.AnnAssign)):
            self.check(found[0].value, found[1])
            return True
        return False

    @staticmethod
    def _bound_in(name: str, scope: ast.AST) -> list | None:
        """The values ``name`` is given in ``scope`` (a for loop's: its iterable; a comprehension's
        variable: its iterable), or None if ``scope`` does not bind it. A parameter: [None] (unknown)."""
        values: list = []
        arguments = scope.args if isinstance(scope, (*FUNCTIONS, ast.Lambda)) else None
        if arguments is not None:
            every = [*arguments.posonlyargs, *arguments.args, *arguments.kwonlyargs,
                     *(a for a in (arguments.vararg, arguments.kwarg) if a is not None)]
            if any(a.arg == name for a in every):
                return [None]
        for node in _own_nodes(scope):
            if isinstance(node, ast.Assign):
                if any(isinstance(n, ast.Name) and n.id == name for t in node.targets for n in ast.walk(t)):
                    values.append(node.value)
            elif isinstance(node, (ast.AugAssign, ast.AnnAssign)) and isinstance(node.target, ast.Name):
                if node.target.id == name and node.value is not None:
                    values.append(node.value)
            elif isinstance(node, (ast.For, ast.comprehension)):
                if any(isinstance(n, ast.Name) and n.id == name for n in ast.walk(node.target)):
                    values.append(node.iter)
            elif isinstance(node, ast.NamedExpr) and node.target.id == name:
                values.append(node.value)
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                  and node.func.attr in ("append", "extend", "insert")
                  and isinstance(node.func.value, ast.Name) and node.func.value.id == name):
                values.extend(node.args[-1:])  # what is added to a list
        return values or None

    def _attribute(self, node: ast.Attribute, path: Path) -> bool:
        """``module.CONSTANT`` of a sandbox module is read there; any other attribute is unknown."""
        if isinstance(node.value, ast.Name):
            imported = self._imported_module(node.value.id, path)
            if imported is not None:
                found = self._definition(node.attr, imported, False, node)
                if found is not None and isinstance(found[0], (ast.Assign, ast.AnnAssign)):
                    self.check(found[0].value, found[1])
                    return True
        return False


def markdown_writes(path: Path):
    """Every expression ``path`` writes into a markdown panel: ``add_markdown``'s content and every
    assignment to a handle's ``.content``."""
    for node in ast.walk(_parsed(path)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "add_markdown":
            yield from node.args[:1]
            yield from (k.value for k in node.keywords if k.arg == "content")
        elif isinstance(node, ast.Assign) and any(isinstance(t, ast.Attribute) and t.attr == "content"
                                                  for t in node.targets):
            yield node.value


def test_every_markdown_writer_shows_text_from_outside_through_plain():
    """A name (a file's, a goal's, a player's, a program's) or an error message written into
    markdown must go through ``plain``: this follows each markdown write in ``sandbox/app`` through
    its f-strings, joins, local variables and the functions it calls (in ``sandbox``) down to
    constants, numbers formatted as numbers, ``plain(...)`` calls and the reviewed :data:`OURS`;
    anything else (an attribute, a parameter, a call it cannot read) is a finding."""
    reader = Reader()
    writes = 0
    for path in sorted(APP.rglob("*.py")):
        for expression in markdown_writes(path):
            writes += 1
            reader.check(expression, path)
    assert writes > 40  # the reader found the panel's writers
    assert not reader.findings, ("text reaching markdown without plain() (wrap it, or add it to OURS if "
                                 "it is our own words):\n" + "\n".join(sorted(set(reader.findings))))
    assert not set(OURS) - reader.reviewed, f"OURS lists what no markdown shows any more: {set(OURS) - reader.reviewed}"


def test_the_reader_catches_a_name_written_into_markdown(tmp_path):
    """The check itself: a name through a parameter, an attribute or a helper is found; plain() and
    numbers pass."""
    source = tmp_path / "sample.py"
    source.write_text(
        "from sandbox.app.panel.plain import plain\n"
        "def label(snap):\n    return f'goal *{snap.shape_name}*'\n"
        "class Folder:\n"
        "    def show(self, snap, player):\n"
        "        self.a.content = label(snap)\n"
        "        self.b.content = f'**{player}**'\n"
        "        self.c.content = f'**{plain(player)}**: {snap.step:,} steps'\n"
        "        rows = ''.join(f'| {name} |' for name in snap.names)\n"
        "        self.gui.add_markdown(rows)\n")
    reader = Reader()
    for expression in markdown_writes(source):
        reader.check(expression, source)
    found = {finding.split(": ", 1)[1] for finding in reader.findings}
    assert found == {"snap.shape_name", "player", "snap.names"}
