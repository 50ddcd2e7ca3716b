"""Argument parsing shared by every ``phototaxis`` command: one flag per
declared parameter, config files, cases and profiles, one-line usage errors.

The commands import this module; it imports none of them (the dispatcher is
:mod:`sandbox.commands`). Errors a user can fix (bad flags, bad files, bad
values) are :class:`UserError` and print as one line with exit code 2.
"""

from __future__ import annotations

import argparse
from typing import Any

from sandbox.model.config import CASES, STRATEGIES, Config, params, read_config_values

# Flags whose value is optional: given bare, they switch a strategy on at its default amount.
_STRATEGY_ON = {s.name: s.on_value for s in STRATEGIES}


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
    """Add one flag per declared parameter, plus --config, --case and --memory-budget (every command
    that builds worlds takes its settings here; the dispatcher applies the budget before it runs).

    Flags default to None so that only values the user typed override the
    config file and the case.
    """
    parser.add_argument("--config", metavar="FILE", help="TOML or JSON file of parameter values")
    parser.add_argument("--memory-budget", metavar="SIZE", default=None,
                        help="the memory a world may need, estimated from its settings before it is built (settings "
                             "over it are refused): a size such as 2G or 800M, or a share of this machine's memory "
                             "such as 50%%; default a quarter of the machine's memory, at most 1G (docs/security.md, "
                             "'What a world may cost'); also the environment variable PHOTOTAXIS_MEMORY_BUDGET")
    if with_case:
        parser.add_argument("--case", choices=list(CASES), help="one of the paper's seven cases (SPEC §7); flags override it")
    groups: dict[str, argparse._ArgumentGroup] = {}
    for p in params():
        group = groups.setdefault(p.group, parser.add_argument_group(f"{p.group} parameters"))
        unit = f" [{p.unit}]" if p.unit else ""
        rng = f" ({p.low:g}..{p.high:g})" if p.low is not None and p.high is not None else ""
        help_text = f"{p.help}{unit}{rng}; default {p.default!r}".replace("%", "%%")
        if p.name in _STRATEGY_ON:
            group.add_argument(flag_name(p.name), dest=p.name, nargs="?", const=_STRATEGY_ON[p.name],
                               default=None, metavar="AMOUNT",
                               help=f"{help_text}; bare flag = {_STRATEGY_ON[p.name]}")
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


def add_controller_argument(p: argparse.ArgumentParser) -> None:
    from sandbox.model.watchdog import DEFAULT_LIMIT

    p.add_argument("--controller", metavar="PATH.py:CLASS", default=None,
                   help="a light program of your own instead of the paper's controller: a class with "
                        "update(observation) returning one intensity per light (see README, 'Light programs')")
    p.add_argument("--program-time-limit", metavar="SECONDS", type=float, default=DEFAULT_LIMIT,
                   help=f"how long a light program's import, reset or update may take before it is stopped "
                        f"(default {DEFAULT_LIMIT:g})")


def program_time_limit(args: argparse.Namespace) -> float:
    """The --program-time-limit, checked."""
    limit = getattr(args, "program_time_limit", None)
    from sandbox.model.watchdog import DEFAULT_LIMIT

    if limit is None:
        return DEFAULT_LIMIT
    if not 0.05 <= limit <= 3600:
        raise UserError(f"--program-time-limit must be between 0.05 and 3600 seconds, got {limit:g}")
    return float(limit)


def controller_from_args(args: argparse.Namespace) -> tuple[str | None, Any]:
    """The --controller spec with its file made absolute, and the program it loads (a one-line
    UserError if it cannot be loaded); (None, None) without the flag. A sweep's workers and a
    server's simulation process load the spec again themselves; ``run`` uses the program."""
    from pathlib import Path

    from sandbox.model.programs import ProgramError, load_program

    spec = getattr(args, "controller", None)
    if not spec:
        return None, None
    path, sep, name = spec.rpartition(":")
    if sep and path.endswith(".py"):
        spec = f"{Path(path).resolve()}:{name}"
    try:
        return spec, load_program(spec, time_limit=program_time_limit(args))
    except ProgramError as exc:
        raise UserError(str(exc)) from None


def add_design_argument(p: argparse.ArgumentParser, help: str) -> None:
    p.add_argument("--design", metavar="FILE.npz", default=None, help=help)


def typed_settings(args: argparse.Namespace) -> list[str]:
    """The flags the user typed that choose a world's goal, settings, seed or light program."""
    chosen = [flag for flag, name in (("--config", "config"), ("--case", "case"), ("--controller", "controller"),
                                      ("--compare", "compare")) if getattr(args, name, None)]
    return chosen + [flag_name(p.name) for p in params() if getattr(args, p.name, None) is not None]


def design_from_args(args: argparse.Namespace) -> Any:
    """The --design file, loaded and checked (a :class:`sandbox.model.design.Design`); None without the flag.
    The file carries the goal, the settings and the seed: a flag that would choose them too is refused."""
    path = getattr(args, "design", None)
    if not path:
        return None
    from sandbox.model.design import DesignError, load

    typed = typed_settings(args)
    if typed:
        raise UserError(f"--design brings the file's own goal, settings and seed: "
                        f"leave out {', '.join(typed)}")
    try:
        return load(path)
    except DesignError as exc:
        raise UserError(str(exc)) from None
