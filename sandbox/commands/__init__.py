"""The ``phototaxis`` command: a dispatcher over the subcommands.

Each subcommand lives in the module that holds its idea and offers
``add_parser(subparsers)``, which adds its parser and sets ``func``: a
callable taking the parsed arguments and returning an exit code.

- ``run``, ``bench``: :mod:`.run`, :mod:`.bench` (headless)
- ``regenerate``: :mod:`.regenerate`, from the table of what the repository commits that a command
  generates (:mod:`.generated`)
- ``serve``, ``record``: :mod:`.serve`, :mod:`.record`
- ``sweep``, ``report``, ``advise``: :mod:`sandbox.experiments.sweep`, :mod:`sandbox.experiments.report`,
  :mod:`sandbox.experiments.advise`

Only the chosen subcommand's module is imported (not to avoid a cycle:
there is none, :mod:`sandbox.cli` imports no command), so that ``phototaxis
run`` starts without loading the web server or matplotlib.
"""

from __future__ import annotations

import importlib
import sys
from typing import Sequence

from sandbox.app.web.stopping import term_stops

# sandbox.cli and the error classes are imported where used: they load numpy and shapely, a second and
# more on a busy machine, and ``serve`` should take a SIGTERM as a clean stop before that (main).

#: subcommand name -> module offering add_parser
SUBCOMMANDS = {
    "run": "sandbox.commands.run",
    "bench": "sandbox.commands.bench",
    "serve": "sandbox.commands.serve",
    "record": "sandbox.commands.record",
    "sweep": "sandbox.experiments.sweep",
    "report": "sandbox.experiments.report",
    "advise": "sandbox.experiments.advise",
    "regenerate": "sandbox.commands.regenerate",
}


def build_parser(only: str | None = None) -> Parser:
    from sandbox.cli import Parser

    parser = Parser(
        prog="phototaxis",
        description="A light-powered phototaxic robot swarm that pushes boxes into a goal shape. "
        "With no command, starts the browser sandbox (same as 'phototaxis serve').",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for name, module in SUBCOMMANDS.items():
        if only is None or name == only:
            importlib.import_module(module).add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0].startswith("-") and argv[0] not in ("-h", "--help"):
        argv = ["serve", *argv]
    only = argv[0] if argv and argv[0] in SUBCOMMANDS else None
    if only != "serve":
        return _dispatch(argv, only)
    with term_stops():  # the server stops cleanly at any moment, while its modules load too
        return _dispatch(argv, only)


def _dispatch(argv: list[str], only: str | None) -> int:
    from sandbox.cli import UserError
    from sandbox.model.config import ConfigError
    from sandbox.shapes import ShapeError

    from sandbox.model import budget

    try:  # read before any module makes a Config (some make one as they load), so a bad value is one line
        budget.memory_budget()
    except ConfigError as exc:
        print(f"phototaxis: error: {exc}", file=sys.stderr)
        return 2
    parser = build_parser(only)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        if getattr(args, "memory_budget", None) is not None:
            _set_budget(args.memory_budget)
        return int(args.func(args) or 0)
    except (UserError, ConfigError, ShapeError) as exc:
        print(f"phototaxis {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _set_budget(text: str) -> None:
    """--memory-budget, for this command and the processes it starts (they read the environment)."""
    from sandbox.cli import UserError
    from sandbox.model import budget

    try:
        budget.set_budget(text)
    except ValueError as exc:
        raise UserError(f"--memory-budget: {exc}") from None
