"""``phototaxis regenerate``: rebuild what the repository commits that a command generates (the
evaluations' reports and figures under ``static/``, the demo recordings) from the table in
:mod:`.generated`, or, with ``--dry-run``, check that table without running it.

The check parses every command with the real ``phototaxis`` parser, builds every sweep's cases (so a
grid file, a parameter or a shape that is gone fails here, not hours into a run), and asks that every
report read a sweep of its own row, every ``--against`` folder exist or be made by an earlier row,
and every output lie under ``static/``. A full run takes about twelve CPU-hours; the check a second
(tests/test_repository.py runs it). It runs from the repository's root, where the table's paths are.
"""

from __future__ import annotations

import argparse
import contextlib
import fnmatch
import functools
import io
import shlex
import sys
from pathlib import Path
from typing import Any

from sandbox.cli import UserError
from sandbox.commands.generated import RUNS, TABLE, Generated

STATIC = "static"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "regenerate", help="rebuild the committed evaluations' reports and figures and the demo recordings",
        description="Run the sweeps, reports and recordings whose output the repository commits under static/ "
                    "(about twelve CPU-hours in all), from the repository's root. Sweeps keep their trials in "
                    "--runs and resume there when run again.")
    p.add_argument("--dry-run", action="store_true",
                   help="check every command and source and print what would run; run nothing")
    p.add_argument("--only", metavar="NAME,NAME", default=None,
                   help=f"these rows only: {', '.join(row.name for row in TABLE)}")
    p.add_argument("--runs", metavar="DIR", default="runs/regenerate",
                   help="where the sweeps keep their trials (default runs/regenerate; delete it after changing "
                        "the model, or the sweeps resume with trials of the model before)")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="local worker processes of each sweep")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=regenerate_command)
    return p


def chosen(only: str | None) -> list[Generated]:
    """The rows named by --only (all without it), in the table's order."""
    if only is None:
        return list(TABLE)
    names = [name.strip() for name in only.split(",") if name.strip()]
    known = {row.name for row in TABLE}
    if unknown := [name for name in names if name not in known]:
        raise UserError(f"--only: no row {unknown[0]!r}; the rows are: {', '.join(row.name for row in TABLE)}")
    return [row for row in TABLE if row.name in names]


def commands_of(row: Generated, runs: str, extra: dict[str, list[str]] | None = None) -> list[list[str]]:
    """The row's argv, its {runs} filled in, with the flags in ``extra`` added to the subcommands named."""
    extra = extra or {}
    return [[part.replace(RUNS, runs) for part in argv] + extra.get(argv[0], []) for argv in row.commands]


# ------------------------------------------------------------------ check


@functools.lru_cache(maxsize=None)
def _parser(command: str) -> argparse.ArgumentParser:
    from sandbox.commands import build_parser

    return build_parser(command)


def parse(argv: list[str]) -> argparse.Namespace:
    """``argv`` parsed by the real phototaxis parser; a ValueError with its one-line message if refused."""
    from sandbox.commands import SUBCOMMANDS

    if argv[0] not in SUBCOMMANDS:
        raise ValueError(f"no phototaxis command {argv[0]!r}")
    errors = io.StringIO()
    try:
        with contextlib.redirect_stderr(errors):
            return _parser(argv[0]).parse_args(argv)
    except SystemExit:
        raise ValueError(errors.getvalue().strip().splitlines()[-1]) from None


def problems(rows: list[Generated], runs: str = "runs/regenerate") -> list[str]:
    """Everything that would stop ``rows`` from running, one line each (none: the table can run)."""
    from sandbox.experiments.sweep import sweep_cases
    from sandbox.experiments.trials import SweepError

    found, made = [], []  # made: what the rows checked so far write
    for row in rows:
        swept = []
        for argv in commands_of(row, runs):
            where = f"{row.name}: phototaxis {shlex.join(argv)}"
            try:
                args = parse(argv)
            except ValueError as exc:
                found.append(f"{where}: {exc}")
                continue
            if argv[0] == "sweep":
                swept.append(args.out)
                try:
                    sweep_cases(args)
                except SweepError as exc:
                    found.append(f"{where}: {exc}")
            elif argv[0] == "report":
                found += [f"{where}: {p}" for p in _report_problems(args, row, swept, made)]
            written = getattr(args, "out", None) if argv[0] != "sweep" else None
            if written is not None and not _writes_into(written, row):
                found.append(f"{where}: writes {written}, not into {row.out} under {STATIC}/")
        made.append(row.out)
    return found


def _report_problems(args: argparse.Namespace, row: Generated, swept: list[str], made: list[str]) -> list[str]:
    found = []
    if args.dir not in swept:
        found.append(f"reads {args.dir}, which no sweep of its row writes")
    against = getattr(args, "against", None)
    if against is not None and against not in made and not (Path(against) / "final.csv").is_file():
        found.append(f"--against {against}: no {against}/final.csv, and no row before it writes one")
    return found


def _writes_into(path: str, row: Generated) -> bool:
    under_static = Path(path).parts[:1] == (STATIC,) and ".." not in Path(path).parts
    return under_static and (path == row.out or fnmatch.fnmatch(path, row.out))


# -------------------------------------------------------------------- run


def regenerate_command(args: argparse.Namespace) -> int:
    if not Path(STATIC).is_dir():
        raise UserError(f"run it from the repository's root, the folder that holds {STATIC}/ "
                        f"(it reads and writes the committed evaluations there)")
    rows = chosen(args.only)
    if found := problems(rows, args.runs):
        for line in found:
            print(f"phototaxis regenerate: {line}", file=sys.stderr)
        return 2
    extra = _extra_flags(args)
    if args.dry_run:
        _print_plan(rows, args.runs, extra)
        return 0
    return _run(rows, args.runs, extra)


def _extra_flags(args: argparse.Namespace) -> dict[str, list[str]]:
    sweep = ["--workers", str(args.workers)] if args.workers else []
    quiet = ["--no-progress"] if args.no_progress else []
    return {"sweep": sweep + quiet, "record": quiet}


def _print_plan(rows: list[Generated], runs: str, extra: dict[str, list[str]]) -> None:
    for row in rows:
        print(f"{row.name} -> {row.out}: {row.what}")
        for argv in commands_of(row, runs, extra):
            print(f"  phototaxis {shlex.join(argv)}")
    count = sum(len(row.commands) for row in rows)
    print(f"{len(rows)} row(s), {count} command(s): every command parses and every source is there")


def _run(rows: list[Generated], runs: str, extra: dict[str, list[str]]) -> int:
    from sandbox.commands import main

    for number, row in enumerate(rows, 1):
        for argv in commands_of(row, runs, extra):
            print(f"regenerate [{number}/{len(rows)}] {row.name}: phototaxis {shlex.join(argv)}", file=sys.stderr)
            code = main(argv)
            if code:
                print(f"phototaxis regenerate: {row.name} stopped (exit code {code}); run the same command again "
                      f"to resume (the sweeps keep their finished trials in {runs})", file=sys.stderr)
                return code
    return 0
