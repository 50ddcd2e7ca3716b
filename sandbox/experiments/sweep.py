"""``phototaxis sweep``: many trials in parallel, locally or on a Dask cluster.

A sweep is the cases of :mod:`.plan` times a number of seeds. Trials run in
local worker processes or on a Dask cluster (``--scheduler``, see
:mod:`.executors`), are saved as they finish (:mod:`.storage`), and are
turned into the paper's tables and figures (:mod:`.report`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shlex
import signal
import sys
from pathlib import Path
from typing import Any

from sandbox.cli import (UserError, add_config_arguments, add_controller_argument, controller_from_args,
                         program_time_limit)
from sandbox.experiments import draws
from sandbox.experiments.executors import dask_executor, local_executor, run_trials
from sandbox.experiments.plan import Case, grid_cases, make_trials, paper_cases
from sandbox.experiments.report import build_report
from sandbox.experiments.storage import SWEEP_FILE, ResultStore, load_meta, write_whole
from sandbox.experiments.trials import SweepError, check_program
from sandbox.model import watchdog
from sandbox.model.config import CASES, Config, params, read_config_values
from sandbox.shapes.generator import FAMILIES, SEEDS_PER_DRAW


def _typed_flags(args: argparse.Namespace) -> dict[str, Any]:
    return {p.name: getattr(args, p.name) for p in params() if getattr(args, p.name, None) is not None}


def _base(args: argparse.Namespace) -> dict[str, Any]:
    """The config file's values (checked, not yet applied: see make_case)."""
    return read_config_values(args.config) if getattr(args, "config", None) else {}


# ---------------------------------------------------------- sweep.json


def write_meta(out: Path, cases: list[Case], compare: list, command: str, trials: int, seed_start: int,
               generated: dict | None = None) -> None:
    """Record the sweep's cases in ``sweep.json``, merged with a previous run's into the same folder; and a
    draw of generated shapes (:mod:`.draws`), refused ones too, when it runs one."""
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
    if generated:
        meta[draws.META_KEY] = draws.merged(meta.get(draws.META_KEY, {}), generated)
    write_whole(out / SWEEP_FILE, json.dumps(meta, indent=1, default=str))


def _command_line(args: argparse.Namespace) -> str:
    """The sweep command for the report, with paths made relative (a report
    should not carry the folders of the machine it ran on)."""
    parts = ["phototaxis", "sweep"]
    if getattr(args, "generated", None) is not None:
        parts += ["--generated", str(args.generated), "--families", args.families,
                  "--generator-seed", str(args.generator_seed)]
        if getattr(args, "part", None):
            parts += ["--part", args.part]
        parts += ["--candidates"] if getattr(args, "candidates", False) else []
    else:
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


def sweep_cases(args: argparse.Namespace) -> tuple[list[Case], list]:
    """The cases a parsed ``sweep`` command runs and its extra pairs to compare, built and checked (its
    grid file, parameters and shapes) without running anything: ``regenerate --dry-run`` checks with it."""
    cases, compare, _ = sweep_plan(args)
    return cases, compare


def sweep_plan(args: argparse.Namespace) -> tuple[list[Case], list, dict]:
    """:func:`sweep_cases`, and the record of a draw of generated shapes ({} for any other sweep)."""
    base, typed = _base(args), _typed_flags(args)
    if getattr(args, "generated", None) is not None:
        wanted = draws.Draw.from_flags(args.generated, args.families, args.generator_seed,
                                       getattr(args, "part", None))
        if getattr(args, "candidates", False):
            from sandbox.experiments.draw_candidates import candidate_cases  # the advice's candidates

            cases, generated = candidate_cases(wanted, base, typed)
        else:
            cases, generated = draws.generated_cases(wanted, base, typed)
        return cases, [], generated
    if getattr(args, "part", None):
        raise SweepError("--part splits a draw of generated shapes: it goes with --generated N")
    if getattr(args, "candidates", False):
        raise SweepError("--candidates runs the advice's candidates of a draw: it goes with --generated N")
    if args.grid:
        return (*grid_cases(args.grid, base, typed), {})
    return paper_cases(args.cases or "paper", base, typed), [], {}


def sweep_command(args: argparse.Namespace) -> int:

    watchdog.on_stuck = watchdog.exit_on_stuck("phototaxis sweep")
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
    cases, compare, generated = sweep_plan(args)
    out = Path(args.out)
    store = ResultStore(out)
    store.check_writable()
    write_meta(out, cases, compare, _command_line(args), args.trials, seed_start, generated)
    trials = make_trials(cases, args.trials, seed_start, controller_from_args(args)[0], program_time_limit(args))
    if trials and trials[0].controller:
        check_program(trials[0])  # a program that fails at once says so here, not after the workers start

    if args.scheduler:
        executor = lambda: dask_executor(args.scheduler)  # noqa: E731
        where = f"the Dask cluster at {args.scheduler}"
    else:
        workers = args.workers or _cpu_count()
        executor = lambda: local_executor(workers)  # noqa: E731
        where = f"{workers} local worker process(es)"
    steps = sorted({t.config["steps"] for t in trials})
    if generated:
        refused = [s for s in generated["shapes"] if s["refused"]]
        if getattr(args, "candidates", False):
            print(f"sweep: {len(generated['shapes'])} generated shape(s), {len(refused)} refused by the model "
                  f"(counted; {sum(len(s['candidates']) for s in refused)} of their candidates build them and run); "
                  f"every advice candidate of each", file=sys.stderr)
        else:
            print(f"sweep: {len(generated['shapes'])} generated shape(s), {len(refused)} refused by the model "
                  f"(counted, not run)", file=sys.stderr)
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
        report = build_report(out, figures=not args.no_figures)
        print(f"report: {report}", file=sys.stderr)
    return 1 if outcome.failures else 0


def add_parser(subparsers: Any) -> argparse.ArgumentParser:

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
        "generated shapes: --generated N draws N shapes of --families (the families in turn), one case\n"
        "each, named gen-FAMILY-SEED; the report adds their distribution and the ten worst.\n"
        "--candidates: every advice candidate of each shape instead (bench --advice --generated).\n\n"
        "examples:\n"
        "  phototaxis sweep --cases paper --trials 20 --out runs/paper\n"
        "  phototaxis sweep --generated 100 --trials 2 --steps 100000 --out runs/generated\n"
        "  phototaxis sweep --grid grid.toml --trials 10 --scheduler tcp://head:8786 --out runs/grid")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--cases", default=None, metavar="paper|NAME,NAME,...",
                      help=f"'paper' (the seven cases of SPEC §7) or names among: {', '.join(CASES)} "
                      "[default: paper]")
    what.add_argument("--grid", metavar="FILE.toml", help="a TOML grid of parameter values (see the docs)")
    what.add_argument("--generated", type=int, default=None, metavar="N",
                      help="N goal shapes from the shape generator, one case each (docs/shapes.md)")
    p.add_argument("--families", default="all", metavar="all|FAMILY,...",
                   help=f"with --generated: the generator's families to draw, in turn: all, or names among "
                   f"{', '.join(FAMILIES)} [default: all]")
    p.add_argument("--generator-seed", type=int, default=0, metavar="S",
                   help=f"with --generated: the draw; draw S takes each family's shapes from seed "
                   f"S x {SEEDS_PER_DRAW:,} on, so two draws share none [default: 0]")
    p.add_argument("--part", default=None, metavar="K/N",
                   help="with --generated: only the K-th of N runs of consecutive shapes of the draw (100 in 4: "
                   "25 each, each family about as often): a long draw split over machines or days, each part "
                   "into its own --out; a part's shapes and trials are those the whole draw runs there")
    p.add_argument("--candidates", action="store_true",
                   help="with --generated: every candidate the advice tries (phototaxis advise) on each shape, one "
                   "case a shape and candidate, named 'gen-star-0003 / offset + chase'; the truth bench --advice "
                   "--generated checks the advice against, and what a refused shape builds with any strategy")
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
    p.add_argument("--no-figures", action="store_true",
                   help="the report's tables without its figures (phototaxis report draws them later)")
    add_controller_argument(p)
    add_config_arguments(p, with_case=False)
    p.set_defaults(func=sweep_command)
    return p
