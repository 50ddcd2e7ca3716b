"""The app's four rooms (docs/code.md, "The app in four rooms"): sandbox/app holds only rooms, imports
between rooms run downhill, and no two modules share a name that means different things."""

from __future__ import annotations

import ast
import re
from pathlib import Path

SANDBOX = Path(__file__).resolve().parent.parent / "sandbox"
APP = SANDBOX / "app"
ROOMS = ("web", "world", "view", "panel", "lesson")
#: room -> the rooms it may import (web and world stand alone; the view draws the world's snapshots; the
#: lesson, class mode, builds panels and floors for the students' worlds)
MAY_IMPORT = {"world": set(), "web": set(), "view": {"world"}, "panel": {"web", "world", "view"},
              "lesson": {"panel", "web", "world", "view"}}
#: module names used twice in sandbox/, each for one idea seen from two layers (a model and the panel
#: folder that shows it), with why
SAME_IDEA = {
    "challenge.py": "model/challenge scores a round; panel/challenge is the folder that plays it",
    "lamp.py": "model/lamp is the player's lamp; panel/lamp is the folder that moves it",
    "metrics.py": "model/metrics measures the run; panel/metrics is the folder that charts it",
    "run.py": "commands/run runs a world headless; panel/run is the folder that runs the live one",
    "controller.py": "model/chase/controller is the paper's controller (model/controller) with chase",
}


def imported_modules(path: Path) -> set[str]:
    """Every sandbox module ``path`` imports, at module level or inside a function."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("sandbox"):
            found.add(node.module)
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("sandbox"))
    return found


def room_of(dotted: str) -> str | None:
    parts = dotted.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["sandbox", "app"] and parts[2] in ROOMS else None


def test_the_app_holds_only_its_rooms():
    modules = sorted(p.name for p in APP.glob("*.py"))
    folders = sorted(p.name for p in APP.iterdir() if p.is_dir() and p.name != "__pycache__")
    assert modules == ["__init__.py"]
    assert folders == sorted(ROOMS)


def test_imports_between_rooms_run_downhill():
    wrong = []
    for room in ROOMS:
        for path in sorted((APP / room).rglob("*.py")):
            for dotted in imported_modules(path):
                other = room_of(dotted)
                if other and other != room and other not in MAY_IMPORT[room]:
                    wrong.append(f"{path.relative_to(SANDBOX)} imports {dotted}")
    assert not wrong, wrong


def test_the_rooms_import_no_command():
    wrong = [f"{path.relative_to(SANDBOX)} imports {dotted}" for path in sorted(APP.rglob("*.py"))
             for dotted in imported_modules(path) if dotted.startswith("sandbox.commands")]
    assert not wrong, wrong


def test_no_two_modules_share_a_name_that_means_two_things():
    seen: dict[str, list[str]] = {}
    for path in sorted(SANDBOX.rglob("*.py")):
        if path.name not in ("__init__.py", "__main__.py"):
            seen.setdefault(path.name, []).append(str(path.relative_to(SANDBOX)))
    twice = {name: where for name, where in seen.items() if len(where) > 1}
    assert set(twice) <= set(SAME_IDEA), {name: twice[name] for name in set(twice) - set(SAME_IDEA)}


def test_the_guard_sees_a_room_importing_uphill(tmp_path):
    # the check above reads real files; make sure it would see a violation
    wrong = tmp_path / "x.py"
    wrong.write_text("def f():\n    from sandbox.app.panel.common import notify\n", encoding="utf-8")
    assert room_of("sandbox.app.panel.common") == "panel"
    assert "sandbox.app.panel.common" in imported_modules(wrong)


#: words that say which thread runs a module's code
THREAD_WORDS = re.compile(r"thread|event loop|in the page|child process", re.IGNORECASE)


def test_every_module_of_the_app_opens_with_what_it_owns_and_which_thread_runs_it():
    silent = []
    for path in sorted(APP.rglob("*.py")):
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        if not THREAD_WORDS.search(doc.split("\n\n")[0]):
            silent.append(str(path.relative_to(SANDBOX)))
    assert not silent, f"say in the opening paragraph which thread runs it: {silent}"
