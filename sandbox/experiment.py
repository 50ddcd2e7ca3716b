"""Experiments: ``phototaxis sweep`` and ``phototaxis report``.

A sweep is a list of *cases* (named configurations) times a number of
seeds. The cases come from the paper (SPEC §7: ``--cases paper`` or a
comma-separated list of names) or from a grid file that sweeps any declared
parameter. Trials run in local worker processes or on a Dask cluster
(``--scheduler``), are saved as they finish (:mod:`sandbox.sweep`), and are
turned into the paper's tables and figures (:mod:`sandbox.report`).

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

import argparse
import contextlib
import itertools
import json
import os
import shlex
import signal
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .config import CASES, Config, ConfigError, param_names, params, read_config_values
from .shapes import ShapeError, shape_vertices
from .sweep import ResultStore, SweepError, Trial, dask_executor, local_executor, run_trials, slug

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


# ------------------------------------------------------------- planning


def _typed_flags(args: argparse.Namespace) -> dict[str, Any]:
    return {p.name: getattr(args, p.name) for p in params() if getattr(args, p.name, None) is not None}


def _base(args: argparse.Namespace) -> dict[str, Any]:
    """The config file's values (checked, not yet applied: see _make_case)."""
    return read_config_values(args.config) if getattr(args, "config", None) else {}


def _resolve_shape(config: Config, label: str) -> list | None:
    try:
        vertices = shape_vertices(config.shape)
    except ShapeError as exc:
        raise SweepError(f"case {label!r}: {exc}") from None
    return None if vertices is None else vertices.tolist()


def _make_case(label: str, overrides: dict, base: dict, typed: dict, where: str = "") -> Case:
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
    return [_make_case(n, CASES[n], base, typed) for n in wanted]


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
        cases.append(_make_case(",".join(parts), overrides, base, typed, where))
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


def make_trials(cases: list[Case], trials: int, seed_start: int) -> list[Trial]:
    out = []
    for case in cases:
        for seed in range(seed_start, seed_start + trials):
            config = case.config.replace(seed=seed).to_dict()
            out.append(Trial(case.label, seed, config, case.shape))
    return out


# ---------------------------------------------------------- sweep.json


def write_meta(out: Path, cases: list[Case], compare: list, command: str, trials: int, seed_start: int) -> None:
    """Record the sweep's cases in ``sweep.json``, merged with a previous run's into the same folder."""
    from .report import SWEEP_FILE, load_meta

    meta = load_meta(out)
    known = {c["label"]: c for c in meta.get("cases", [])}
    for case in cases:
        old = known.get(case.label)
        new = {**case.config.to_dict(), "seed": None}
        if old is not None and old.get("config") != new:
            diff = sorted(k for k in new if old.get("config", {}).get(k) != new[k])
            raise SweepError(f"{out} already holds case {case.label!r} with other parameters "
                             f"({', '.join(diff[:3])} differ); use another --out or delete that folder")
        known[case.label] = {"label": case.label, "overrides": case.overrides, "config": new}
    pairs = [list(p) for p in meta.get("compare", [])]
    pairs += [list(p) for p in compare if list(p) not in pairs]
    meta.update(command=command, cases=list(known.values()), compare=pairs,
                trials=max(trials, int(meta.get("trials", 0))), seed_start=seed_start)
    tmp = out / (SWEEP_FILE + ".tmp")
    tmp.write_text(json.dumps(meta, indent=1, default=str))
    os.replace(tmp, out / SWEEP_FILE)


def _command_line(args: argparse.Namespace) -> str:
    """The sweep command for the report, with paths made relative (a report
    should not carry the folders of the machine it ran on)."""
    parts = ["phototaxis", "sweep"]
    parts += ["--grid", _portable(args.grid)] if args.grid else ["--cases", args.cases]
    parts += ["--trials", str(args.trials)]
    if args.seeds is not None:
        parts += ["--seeds", str(args.seeds)]
    if args.config:
        parts += ["--config", _portable(args.config)]
    for name, value in _typed_flags(args).items():
        parts += ["--" + name.replace("_", "-"), _portable(str(value)) if name == "shape" else str(value)]
    parts += ["--out", _portable(args.out)]
    return shlex.join(parts)


def _portable(path: str) -> str:
    """``path`` relative to the working folder if it lies under it, else only its last part."""
    p = Path(path)
    if not p.is_absolute():
        return path
    try:
        return p.relative_to(Path.cwd()).as_posix()
    except ValueError:
        return p.name


# ------------------------------------------------------------------ CLI


def _cpu_count() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def _term_as_interrupt():
    """Treat SIGTERM (kill, a batch system's time limit) like Ctrl-C: stop workers, keep finished trials."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def sweep_command(args: argparse.Namespace) -> int:
    from .cli import UserError

    try:
        return _sweep(args)
    except SweepError as exc:
        raise UserError(str(exc)) from None


def _sweep(args: argparse.Namespace) -> int:
    if args.trials < 1:
        raise SweepError(f"--trials must be at least 1 (got {args.trials})")
    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers must be at least 1 (got {args.workers})")
    if args.seeds is not None and args.seeds < 0:
        raise SweepError(f"--seeds must be 0 or more (got {args.seeds})")
    base, typed = _base(args), _typed_flags(args)
    seed_start = args.seeds if args.seeds is not None else Config().replace(**{**base, **typed}).seed
    if args.grid:
        cases, compare = grid_cases(args.grid, base, typed)
    else:
        cases, compare = paper_cases(args.cases or "paper", base, typed), []
    out = Path(args.out)
    store = ResultStore(out)
    store.check_writable()
    write_meta(out, cases, compare, _command_line(args), args.trials, seed_start)
    trials = make_trials(cases, args.trials, seed_start)

    if args.scheduler:
        executor = lambda: dask_executor(args.scheduler)  # noqa: E731
        where = f"the Dask cluster at {args.scheduler}"
    else:
        workers = args.workers or _cpu_count()
        executor = lambda: local_executor(workers)  # noqa: E731
        where = f"{workers} local worker process(es)"
    steps = sorted({t.config["steps"] for t in trials})
    print(f"sweep: {len(cases)} case(s) x {args.trials} trial(s) of {', '.join(map(str, steps))} steps "
          f"(seeds {seed_start}..{seed_start + args.trials - 1}) on {where}; results in {out}", file=sys.stderr)
    try:
        with store.lock(), _term_as_interrupt():
            outcome = run_trials(trials, store, executor, progress=not args.no_progress)
    except KeyboardInterrupt:
        print(f"sweep interrupted: finished trials are saved in {out}; run the same command again to resume",
              file=sys.stderr)
        raise
    # Failures of earlier runs that have since succeeded are forgotten.
    store.save_failures(outcome.failures)
    print(f"sweep: {outcome.done} trial(s) run, {outcome.skipped} already done, {len(outcome.failures)} failed "
          f"({outcome.seconds:.0f} s)", file=sys.stderr)
    if not args.no_report and outcome.done + outcome.skipped:
        from .report import build_report

        report = build_report(out)
        print(f"report: {report}", file=sys.stderr)
    return 1 if outcome.failures else 0


def report_command(args: argparse.Namespace) -> int:
    from .cli import UserError
    from .report import build_report

    try:
        report = build_report(args.dir, args.out)
    except SweepError as exc:
        raise UserError(str(exc)) from None
    print(report)
    return 0


def add_sweep_parser(subparsers: Any) -> argparse.ArgumentParser:
    from .cli import add_config_arguments

    p = subparsers.add_parser(
        "sweep", help="run many trials in parallel and write the paper's tables and figures",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Run cases x seeds as independent trials, locally or on a Dask cluster. Each trial is\n"
        "saved under OUT/trials as it finishes; re-running the same command resumes. Then writes\n"
        "OUT/report.md with summary tables, Kolmogorov-Smirnov tests and figures. Every model\n"
        "parameter flag below sets the base for all cases (e.g. --steps 100000 --robots 200);\n"
        "a case's own values (shape, strategies, grid values) win over them.",
        epilog="grid file example (every combination of the [grid] values is one case):\n"
        "  [base]\n  steps = 50000\n  [grid]\n  shape = [\"square\", \"star\", \"my/house.txt\"]\n"
        "  robots = [100, 200]\n  flare = [0.0, 1.75]\n"
        "optional: [cases.NAME] tables of values, a [grid] key case = [NAME, ...] (also the\n"
        "paper's case names), and compare = [[CASE, CASE], ...] for extra KS tests.\n\n"
        "examples:\n"
        "  phototaxis sweep --cases paper --trials 20 --out runs/paper\n"
        "  phototaxis sweep --grid grid.toml --trials 10 --scheduler tcp://head:8786 --out runs/grid")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--cases", default=None, metavar="paper|NAME,NAME,...",
                      help=f"'paper' (the seven cases of SPEC §7) or names among: {', '.join(CASES)} "
                      "[default: paper]")
    what.add_argument("--grid", metavar="FILE.toml", help="a TOML grid of parameter values (see the docs)")
    p.add_argument("--trials", type=int, default=10, help="trials (seeds) per case [default: 10]")
    p.add_argument("--seeds", type=int, default=None, metavar="START",
                   help="first seed; trial i of every case uses seed START+i [default: the base seed, 0]")
    p.add_argument("--workers", type=int, default=None, help="local worker processes [default: one per core]")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on the Dask cluster whose scheduler is at ADDRESS, e.g. tcp://10.0.0.1:8786 "
                   "(needs pip install 'phototaxis-sandbox[cluster]')")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for results (created; resumed if present)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-report", action="store_true", help="only run the trials; build the report later")
    add_config_arguments(p, with_case=False)
    p.set_defaults(func=sweep_command)
    return p


def add_report_parser(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "report", help="rebuild tables, figures and report.md from a sweep's stored results",
        description="Read DIR/trials (written by 'phototaxis sweep') and write report.md, summary.csv, "
        "ks_tests.csv, results.csv, final.csv and figures/ into DIR, or into --out.")
    p.add_argument("dir", metavar="DIR", help="the folder a sweep wrote (its --out)")
    p.add_argument("--out", metavar="DEST", default=None,
                   help="write the report here instead (e.g. static/paper), without the raw trial files")
    p.set_defaults(func=report_command)
    return p
