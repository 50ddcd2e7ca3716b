"""The ``phototaxis`` command line.

Subcommands live in their own modules and are listed in ``SUBCOMMANDS``:
each entry names a module and a function ``f(subparsers)`` there that adds
the subcommand's parser and sets its ``func`` default: a callable taking the
parsed arguments and returning an exit code. Modules are imported only when needed, so the headless
commands never import the browser app.

Errors a user can fix (bad flags, bad files, bad values) print one line and
exit with code 2; a traceback means a bug.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import Any, Sequence

from .config import CASES, STRATEGY_DEFAULTS, Config, ConfigError, params, read_config_values
from .shapes import ShapeError

#: subcommand name -> (module, function that adds its parser)
SUBCOMMANDS = {
    "run": ("sandbox.run", "add_parser"),
    "bench": ("sandbox.bench", "add_parser"),
    "serve": ("sandbox.app", "add_parser"),
    "record": ("sandbox.record", "add_parser"),
    "sweep": ("sandbox.experiment", "add_sweep_parser"),
    "report": ("sandbox.experiment", "add_report_parser"),
}

# Flags whose value is optional: given bare, they switch a strategy on at its default amount.
_STRATEGY_FLAGS = {"flare": "--flare", "switch": "--switch", "no_corners": "--no-corners"}


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line, not the whole usage text
    (every parameter is a flag, so the usage is long)."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


class UserError(Exception):
    """Raised by subcommands for errors to show as one line, exit code 2."""


def flag_name(name: str) -> str:
    return "--" + name.replace("_", "-")


def add_config_arguments(parser: argparse.ArgumentParser, *, with_case: bool = True) -> None:
    """Add one flag per declared parameter, plus --config and --case.

    Flags default to None so that only values the user typed override the
    config file and the case.
    """
    parser.add_argument("--config", metavar="FILE", help="TOML or JSON file of parameter values")
    if with_case:
        parser.add_argument("--case", choices=list(CASES), help="one of the paper's seven cases (SPEC §7); flags override it")
    groups: dict[str, argparse._ArgumentGroup] = {}
    for p in params():
        group = groups.setdefault(p.group, parser.add_argument_group(f"{p.group} parameters"))
        unit = f" [{p.unit}]" if p.unit else ""
        rng = f" ({p.low:g}..{p.high:g})" if p.low is not None and p.high is not None else ""
        help_text = f"{p.help}{unit}{rng}; default {p.default!r}".replace("%", "%%")
        if p.name in _STRATEGY_FLAGS:
            group.add_argument(_STRATEGY_FLAGS[p.name], dest=p.name, nargs="?", const=STRATEGY_DEFAULTS[p.name],
                               default=None, metavar="AMOUNT",
                               help=f"{help_text}; bare flag = {STRATEGY_DEFAULTS[p.name]}")
        else:
            kwargs: dict[str, Any] = dict(dest=p.name, default=None, help=help_text)
            if p.choices:
                kwargs["choices"] = p.choices
            else:
                kwargs["metavar"] = p.type.__name__.upper()
            group.add_argument(flag_name(p.name), **kwargs)


def config_from_args(args: argparse.Namespace) -> Config:
    """Defaults, then the config file, then the case, then explicit flags.

    The profile (from whichever of those names it last) supplies the values
    that none of them sets: a value given anywhere wins over the profile.
    """
    explicit: dict[str, Any] = {}
    if getattr(args, "config", None):
        explicit.update(read_config_values(args.config))
    if getattr(args, "case", None):
        explicit.update(CASES[args.case])
    explicit.update({p.name: getattr(args, p.name) for p in params() if getattr(args, p.name, None) is not None})
    return Config().replace(**explicit)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    parser = Parser(
        prog="phototaxis",
        description="A light-powered phototaxic robot swarm that pushes boxes into a goal shape. "
        "With no command, starts the browser sandbox (same as 'phototaxis serve').",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for name, (module, adder) in SUBCOMMANDS.items():
        if only is not None and name != only:
            continue
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name in (module, "viser", "matplotlib", "scipy", "dask", "distributed", "imageio", "PIL"):
                _missing_command(sub, name, exc)
                continue
            raise
        getattr(mod, adder)(sub)
    return parser


def _missing_command(sub: Any, name: str, exc: ModuleNotFoundError) -> None:
    p = sub.add_parser(name, help=f"(unavailable: {exc.name} is not installed)")

    def fail(_args: argparse.Namespace) -> int:
        raise UserError(f"'phototaxis {name}' needs the Python package {exc.name!r}; install it with "
                        f"pip install -e '.[all]'")

    p.set_defaults(func=fail)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0].startswith("-") and argv[0] not in ("-h", "--help"):
        argv = ["serve", *argv]
    only = argv[0] if argv and argv[0] in SUBCOMMANDS else None
    parser = build_parser(only)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (UserError, ConfigError, ShapeError) as exc:
        print(f"phototaxis {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
