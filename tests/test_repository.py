"""The repository holds the product (issue 55): ``static/`` is what a reader reads, small and without
code; no module of ``sandbox/`` reads it but the table of what ``phototaxis regenerate`` makes; that
table is checked as ``regenerate --dry-run`` checks it and covers every committed evaluation; what a run
writes and git does not keep is ignored; every report's one figure is committed and small. These read
the tracked files (``git ls-files``): a fresh clone is what they judge."""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from sandbox import commands
from sandbox.commands import regenerate
from sandbox.commands.generated import TABLE, Generated

ROOT = Path(__file__).resolve().parent.parent
STATIC_BUDGET = 5_000_000  # bytes
FIGURE_BUDGET = 150_000  # bytes: sandbox.experiments.figures.COMPACT_BYTES
#: The modules that may name static/: the table of what regenerate writes there, and the command.
MAY_NAME_STATIC = {"sandbox/commands/generated.py", "sandbox/commands/regenerate.py"}
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def git(*args: str) -> str:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("needs a git checkout")
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout


def tracked(folder: str = "static") -> list[str]:
    return git("ls-files", "-z", "--", folder).split("\0")[:-1]


def ignored(paths: list[str]) -> set[str]:
    """The paths .gitignore leaves out, whether or not they exist."""
    done = subprocess.run(["git", "check-ignore", "--no-index", "--stdin"], cwd=ROOT, input="\n".join(paths),
                          capture_output=True, text=True)
    return set(done.stdout.split())


# ------------------------------------------------------------- static/


def test_static_is_under_five_megabytes():
    sizes = {path: (ROOT / path).stat().st_size for path in tracked() if (ROOT / path).is_file()}
    largest = sorted(sizes, key=sizes.get, reverse=True)[:3]
    assert sum(sizes.values()) < STATIC_BUDGET, f"static/ holds {sum(sizes.values()):,} bytes; largest: {largest}"


def test_static_holds_no_code():
    code = [path for path in tracked() if Path(path).suffix in (".py", ".sh", ".ipynb")]
    assert not code, f"lab scripts in static/ (the product is sandbox/; a measurement is a design note): {code}"


def test_every_report_shows_its_one_figure_committed_and_small():
    files = set(tracked())
    reports = [path for path in files if path.endswith("/report.md")]
    assert len(reports) >= 14
    for report in reports:
        images = IMAGE.findall((ROOT / report).read_text(encoding="utf-8"))
        assert len(images) == 1, f"{report} shows {len(images)} figures, not its one"
        figure = (Path(report).parent / images[0]).as_posix()
        assert figure in files, f"{report} shows {figure}, which git does not keep"
        assert (ROOT / figure).stat().st_size <= FIGURE_BUDGET, f"{figure} is over {FIGURE_BUDGET:,} bytes"


# ------------------------------------------------------------ sandbox/


def names_static(tree: ast.AST) -> list[int]:
    """Lines of ``tree`` that import ``static`` or hold a string naming static/, docstrings and
    ``help=`` texts (examples for a user) aside."""
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                skip.add(id(first.value))
        if isinstance(node, ast.keyword) and node.arg == "help":
            skip.update(id(part) for part in ast.walk(node.value))
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "static" for a in node.names):
            lines.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "static":
            lines.append(node.lineno)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
            if re.search(r"(^|[^\w.])static(/|$)", node.value):
                lines.append(node.lineno)
    return lines


def test_no_product_module_reads_static():
    found = []
    for path in sorted((ROOT / "sandbox").rglob("*.py")):
        name, text = path.relative_to(ROOT).as_posix(), path.read_text(encoding="utf-8")
        if name not in MAY_NAME_STATIC and "static" in text:  # parse only the modules that could
            found += [f"{name}:{line}" for line in names_static(ast.parse(text))]
    assert not found, f"sandbox/ reads static/ (what a command generates belongs in generated.py): {found}"


def test_the_static_check_sees_an_import_and_a_path_but_not_a_docstring():
    tree = ast.parse('"""Measured in static/paper."""\nimport static.x\nopen("static/paper/final.csv")\n'
                     'p.add_argument("--out", help="e.g. static/paper")\nx = "staticmethod"\n')
    assert names_static(tree) == [2, 3]


# --------------------------------------------------- regenerate's table


def test_regenerate_dry_run_checks_the_whole_table(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    assert commands.main(["regenerate", "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert all(f"{row.name} -> {row.out}:" in out for row in TABLE)
    assert "phototaxis sweep --cases paper --trials 10 --no-report --out runs/regenerate/paper" in out


def test_the_table_covers_every_committed_report():
    committed = {str(Path(path).parent) for path in tracked() if path.endswith("/report.md")}
    assert committed == {row.out for row in TABLE if row.is_report}


def test_what_a_run_writes_and_git_does_not_keep_is_ignored():
    git("status")  # skips without a checkout
    dropped, kept = [], []
    for row in TABLE:
        if row.is_report:
            dropped += [f"{row.out}/results.csv", f"{row.out}/figures/final_layouts.svg"]
            dropped += [f"{row.out}/figures/{name}.{ext}" for name in ("fraction_in_goal", "mean_outside_distance")
                        for ext in ("png", "svg")]
            kept += [f"{row.out}/{name}" for name in ("report.md", "summary.csv", "final.csv", "ks_tests.csv",
                                                      "figures/final_layouts.png")]
        else:
            dropped += [argv[argv.index("--out") + 1] for argv in row.commands]
    assert ignored(dropped) == set(dropped)
    assert not ignored(kept)


def row(*commands: tuple[str, ...], out: str = "static/x") -> Generated:
    return Generated("x", "a test row", out, commands)


def test_the_check_names_each_problem_in_one_line(monkeypatch):
    monkeypatch.chdir(ROOT)
    sweep = ("sweep", "--cases", "circle", "--trials", "1", "--out", "{runs}/x")
    assert regenerate.problems([row(sweep, ("report", "{runs}/x", "--out", "static/x"))]) == []
    cases = {
        "no grid": row(("sweep", "--grid", "static/gone.toml", "--trials", "1", "--out", "{runs}/x")),
        "a flag gone": row(("sweep", "--cases", "circle", "--hold-steps-gone", "3", "--out", "{runs}/x")),
        "an unknown case": row(("sweep", "--cases", "hexagon", "--out", "{runs}/x")),
        "no such command": row(("plot", "x")),
        "a report of no sweep": row(("report", "{runs}/y", "--out", "static/x")),
        "against nothing": row(sweep, ("report", "{runs}/x", "--out", "static/x", "--against", "static/gone")),
        "outside static": row(sweep, ("report", "{runs}/x", "--out", "elsewhere/x"), out="elsewhere/x"),
        "a recording elsewhere": row(("record", "--case", "circle", "--out", "static/other.html"),
                                     out="static/demo-*.html"),
    }
    for why, broken in cases.items():
        found = regenerate.problems([broken])
        assert len(found) == 1 and "\n" not in found[0] and found[0].startswith("x: phototaxis "), (why, found)


def test_regenerate_runs_only_from_the_repositorys_root(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert commands.main(["regenerate", "--dry-run"]) == 2
    assert "run it from the repository's root" in capsys.readouterr().err
    monkeypatch.chdir(ROOT)
    assert commands.main(["regenerate", "--only", "paper,nothing"]) == 2
    assert "--only: no row 'nothing'" in capsys.readouterr().err


def test_a_row_picked_runs_its_commands_in_order(monkeypatch):
    """Without --dry-run each command goes to the dispatcher, {runs} filled in; the first to fail stops it."""
    ran = []
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(commands, "main", lambda argv: ran.append(argv) or (3 if argv[0] == "report" else 0))
    assert regenerate.regenerate_command(regenerate_args(only="hold,sleep", runs="r", workers=2)) == 3
    assert ran == [["sweep", "--grid", "static/experiments/hold.toml", "--trials", "6", "--no-report", "--out",
                    "r/hold", "--workers", "2"],
                   ["report", "r/hold", "--out", "static/experiments/hold"]]


def regenerate_args(**given):
    import argparse

    values = dict(dry_run=False, only=None, runs="runs/regenerate", workers=None, no_progress=False)
    return argparse.Namespace(**{**values, **given})


def test_compact_png_fits_its_budget(tmp_path):
    """A final-layouts-like picture (many small flat discs on white), 1937 px wide as matplotlib draws it."""
    from PIL import Image, ImageDraw

    from sandbox.experiments.figures import COMPACT_BYTES, COMPACT_WIDTH, compact_png

    image = Image.new("RGB", (1937, 1200), "white")
    draw = ImageDraw.Draw(image)
    for i in range(3000):
        x, y = (i * 7919) % 1937, (i * 104729) % 1200
        draw.ellipse((x, y, x + 9, y + 9), fill=("#2e7d32", "#e65100", "#607d8b")[i % 3])
    size = compact_png(image, tmp_path / "f.png")
    written = Image.open(tmp_path / "f.png")
    assert size == (tmp_path / "f.png").stat().st_size <= COMPACT_BYTES
    assert written.mode == "P" and written.width <= COMPACT_WIDTH
