"""What a sweep runs: its *cases* (named configurations) and their trials.

The cases come from the paper (``--cases paper`` or a comma-separated list
of names), from a grid file that sweeps any declared parameter, or from a
draw of generated shapes (``--generated N``, :mod:`.draws`: one case a shape).

Grid file (TOML)::

    # values for every trial; explicit command-line flags override them
    [base]
    steps = 50000

    # every combination of these values is one case
    [grid]
    shape = ["square", "star", "my-shapes/house.txt"]   # paths relative to this file
    robots = [100, 200]
    flare = [0.0, 1.75]

    # optional named cases; a grid key `case` picks among these and the paper's names
    [cases.star-all]
    shape = "star"
    switch = 0.25
    no_corners = 0.5

    # optional: extra pairs of case labels to compare with KS tests
    compare = [["shape=square,robots=100,flare=0", "shape=square,robots=100,flare=1.75"]]

Precedence, lowest first: defaults, ``--config`` file, the grid's ``[base]``,
explicit flags, then each case's own values (a paper case, a ``[cases.*]``
table, the grid values).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sandbox.experiments.trials import SweepError, Trial, slug
from sandbox.model.config import CASES, Config, ConfigError, param_names
from sandbox.shapes import ShapeError, shape_vertices

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover
    import tomli as tomllib

GRID_KEYS = {"base", "grid", "cases", "compare"}


@dataclass(frozen=True)
class Case:
    label: str
    overrides: dict  # what this case sets on top of the base
    config: Config
    shape: list | None  # resolved goal vertices (None: circle)


def _resolve_shape(config: Config, label: str) -> list | None:
    try:
        vertices = shape_vertices(config.shape)
    except ShapeError as exc:
        raise SweepError(f"case {label!r}: {exc}") from None
    return None if vertices is None else vertices.tolist()


def make_case(label: str, overrides: dict, base: dict, typed: dict, where: str = "") -> Case:
    """The case ``label``: ``overrides`` on the base and the flags, its shape's vertices resolved."""
    # One replace, so that a profile named anywhere only fills in what none of them sets.
    try:
        config = Config().replace(**{**base, **typed, **overrides})
    except ConfigError as exc:
        raise SweepError(f"{where}case {label!r}: {exc}") from None
    if "seed" in overrides:
        raise SweepError(f"{where}case {label!r} sets 'seed'; seeds are chosen with --seeds and --trials")
    return Case(label, dict(overrides), config, _resolve_shape(config, label))


def paper_cases(names: str, base: dict, typed: dict) -> list[Case]:
    wanted = list(CASES) if names.strip() == "paper" else [n.strip() for n in names.split(",") if n.strip()]
    if not wanted:
        raise SweepError("--cases is empty; give 'paper' or case names separated by commas")
    unknown = [n for n in wanted if n not in CASES]
    if unknown:
        raise SweepError(f"unknown case(s) {', '.join(map(repr, unknown))}; the cases are: paper, {', '.join(CASES)}")
    if len(set(wanted)) != len(wanted):
        raise SweepError("--cases lists a case twice")
    return [make_case(n, CASES[n], base, typed) for n in wanted]


def _value_text(name: str, value: Any) -> str:
    if name == "shape" and ("/" in str(value) or "." in str(value)):
        return Path(str(value)).stem
    return f"{value:g}" if isinstance(value, float) else str(value)


def grid_cases(path: str, base: dict, typed: dict) -> tuple[list[Case], list[tuple[str, str]]]:
    """Read a grid file (format in this module's docstring) into cases and extra KS pairs."""
    file = Path(path)
    where = f"grid file {file}: "
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SweepError(f"cannot read grid file {file}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SweepError(f"{where}not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{where}not valid TOML: {exc}") from None
    unknown = set(data) - GRID_KEYS
    if unknown:
        raise SweepError(f"{where}unknown section or key {sorted(unknown)[0]!r}; "
                         f"expected [base], [grid], [cases.NAME] and compare")
    names = set(param_names())

    def check_table(table: Any, what: str, *, allow_case: bool = False) -> dict:
        if not isinstance(table, dict):
            raise SweepError(f"{where}{what} must be a table of parameter = value")
        for key in table:
            if key not in names and not (allow_case and key == "case"):
                hint = [n for n in names if n.replace("_", "") == key.replace("_", "").replace("-", "")]
                extra = f" (did you mean {hint[0]!r}?)" if hint else "; see 'phototaxis sweep --help' for the names"
                if key == "compare":
                    extra = " (in TOML, put compare = [...] above the first [table], or it belongs to that table)"
                raise SweepError(f"{where}unknown parameter {key!r} in {what}{extra}")
            if key == "seed":
                raise SweepError(f"{where}'seed' in {what}: seeds are chosen with --seeds and --trials")
        return table

    def fix_shape(table: dict) -> dict:
        """Shape paths are relative to the grid file."""
        if "shape" in table and isinstance(table["shape"], str):
            candidate = (file.parent / table["shape"]).expanduser()
            if not Path(table["shape"]).is_absolute() and candidate.is_file():
                return {**table, "shape": str(candidate.resolve())}
        return table

    base_table = fix_shape(check_table(data.get("base", {}), "[base]"))
    base = {**base, **base_table}
    try:
        Config().replace(**base)
    except ConfigError as exc:
        raise SweepError(f"{where}[base]: {exc}") from None
    named = {}
    for name, table in check_table_of_tables(data.get("cases", {}), where).items():
        named[name] = fix_shape(check_table(table, f"[cases.{name}]"))
    grid = check_table(data.get("grid", {}), "[grid]", allow_case=True)
    axes: list[tuple[str, list]] = []
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise SweepError(f"{where}[grid] {key} must be a non-empty list of values, e.g. {key} = [1, 2]")
        axes.append((key, values))
    if named and "case" not in grid:
        axes.insert(0, ("case", list(named)))
    if not axes:
        raise SweepError(f"{where}nothing to sweep: add a [grid] table of parameter = [values] or [cases.NAME] tables")
    for key, values in axes:
        if key == "case":
            bad = [v for v in values if v not in named and v not in CASES]
            if bad:
                raise SweepError(f"{where}[grid] case {bad[0]!r} is neither a [cases.NAME] table nor one of "
                                 f"{', '.join(CASES)}")
    labelled = [k for k, vs in axes if len(vs) > 1] or [axes[0][0]]
    cases = []
    for combo in itertools.product(*(vs for _, vs in axes)):
        overrides: dict[str, Any] = {}
        parts = []
        for (key, _), value in zip(axes, combo):
            if key == "case":
                overrides.update(named.get(value, CASES.get(value, {})))
                if key in labelled:
                    parts.append(str(value))
            else:
                overrides.update(fix_shape({key: value}))
                if key in labelled:
                    parts.append(f"{key}={_value_text(key, value)}")
        cases.append(make_case(",".join(parts), overrides, base, typed, where))
    labels = [c.label for c in cases]
    dupes = sorted({slug(x) for x in labels if [slug(y) for y in labels].count(slug(x)) > 1})
    if dupes:
        raise SweepError(f"{where}two cases get the same name {dupes[0]!r}; give the values distinct names")
    compare = data.get("compare", [])
    if not (isinstance(compare, list) and all(isinstance(p, list) and len(p) == 2 for p in compare)):
        raise SweepError(f"{where}compare must be a list of [case, case] pairs")
    for pair in compare:
        for label in pair:
            if label not in labels:
                raise SweepError(f"{where}compare names unknown case {label!r}; the cases are: {', '.join(labels)}")
    return cases, [tuple(p) for p in compare]


def check_table_of_tables(data: Any, where: str) -> dict:
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise SweepError(f"{where}cases must be tables: [cases.NAME] with parameter = value lines")
    return data


def make_trials(cases: list[Case], trials: int, seed_start: int, controller: str | None = None,
                program_time_limit: float | None = None) -> list[Trial]:
    out = []
    for case in cases:
        for seed in range(seed_start, seed_start + trials):
            config = case.config.replace(seed=seed).to_dict()
            out.append(Trial(case.label, seed, config, case.shape, controller, program_time_limit))
    return out
