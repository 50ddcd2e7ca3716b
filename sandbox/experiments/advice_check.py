"""Is the advice right, and how long does it take? The default advice on every shape in ``shapes/``, the
circle and the drawing templates (``phototaxis bench --advice``, from the repository's root, where the
tables are; which shapes and tables: ``sandbox.commands.generated``): its first choice against the best
candidate of the committed 100,000-step evaluations, its time and CPU time, and its time-left estimate
at each finished trial against the time in fact left.

The advice's first choice is *right* when, at 100,000 steps, it builds the shape within
:data:`TOLERANCE` (one point of the boxes) of the best candidate measured there; *not measured* when the
evaluations never ran it. The evaluations' trials are their seeds 0-3 (the paper's cases with chase, in
``static/closed-loop``, ran ten: their first four are taken, as everywhere else).
"""

from __future__ import annotations

import csv
import glob
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from sandbox.experiments import advise as advice
from sandbox.experiments.advise import Candidate, Ranked
from sandbox.experiments.pace import A_FEW_SECONDS
from sandbox.model.config import STRATEGY_NAMES, Config

#: How far below the best at 100,000 steps the first choice may build the shape (a fraction of the boxes).
TOLERANCE = 0.01

SEEDS = 4
STEPS = 100_000


def shape_name(shape: str) -> str:
    """'static/shapes/templates/shapes/letter-H.txt' -> 'letter-H'; 'circle' stays."""
    return Path(shape).name.removesuffix(".txt")


def label_of(row: dict) -> str:
    """The candidate a trial of an evaluation ran: the family its goal took (evaluations made before the
    offset outline ran the paper's scaled outline) and the strategies on."""
    family = row.get("outline_family") or row.get("outline") or "scaled"
    on = tuple((name, float(row[name])) for name in STRATEGY_NAMES if float(row.get(name) or 0) > 0)
    return Candidate(family, on).label


def measured(rows: Iterable[dict], steps: int = STEPS) -> dict[tuple[str, str], list[float]]:
    """{(shape, candidate label): fractions in the goal at 100,000 steps (``steps``), seeds 0-3}."""
    out: dict[tuple[str, str], list[float]] = {}
    for row in rows:
        if int(row["seed"]) < SEEDS and int(row["final_step"]) == steps and row.get("notches", "lit") == "lit":
            out.setdefault((shape_name(row["shape"]), label_of(row)), []).append(float(row["fraction_in_goal"]))
    return out


def read_evaluations(files: Iterable[str], steps: int = STEPS) -> dict[tuple[str, str], list[float]]:
    """The trials of the evaluations' final.csv ``files`` (those missing skipped), as :func:`measured`."""
    rows = []
    for file in files:
        if Path(file).exists():
            with open(file, newline="") as f:
                rows += list(csv.DictReader(f))
    return measured(rows, steps)


@dataclass
class Timed:
    """One shape's advice as a user gets it: the ranking and verdict, its wall and CPU seconds, and at each
    finished trial but the last (elapsed s, time left estimated, time in fact left)."""

    shape: str
    ranking: list[Ranked]
    verdict: str
    seconds: float
    cpu_seconds: float
    estimates: list[tuple[float, float | None, float]] = field(default_factory=list)

    @property
    def worst_estimate(self) -> float:
        """The largest relative error (0.3: 30 % off) of a time left said as a figure, at least
        :data:`~sandbox.experiments.pace.A_FEW_SECONDS` (nan: none was)."""
        errors = [abs(guess - actual) / actual for _, guess, actual in self.estimates
                  if guess is not None and guess >= A_FEW_SECONDS]
        return max(errors, default=math.nan)

    @property
    def a_few_seconds_at_most(self) -> float:
        """The most seconds in fact left when "a few seconds left" was said (nan: it never was)."""
        return max((actual for _, guess, actual in self.estimates if guess is not None and guess < A_FEW_SECONDS),
                   default=math.nan)


def timed_advice(shape: str, config: Config, *, workers: int, steps: int = advice.STEPS,
                 clock: Callable[[], float] = time.monotonic) -> Timed:
    """The default advice on ``shape`` (the config's other settings), timed; ``steps`` per trial."""
    from sandbox.shapes import shape_vertices

    config, vertices = config.replace(shape=shape), shape_vertices(shape)
    heard: list[tuple[float, float | None]] = []
    started = clock()
    ranking = advice.advise(config, vertices, workers=workers, steps=steps,
                            progress=lambda done, total, left: heard.append((clock() - started, left)))
    seconds = clock() - started
    return Timed(shape, ranking, advice.verdict(ranking, advice.default_candidate(config, vertices)), seconds,
                 sum(r.cpu_seconds for r in ranking), [(at, left, seconds - at) for at, left in heard[:-1]])


@dataclass(frozen=True)
class Verdict:
    """One shape: the advice's first choice against the best measured at 100,000 steps."""

    shape: str
    first: str
    first_fraction: float  # the advice's own trials
    at_100k: float  # the first choice at 100,000 steps (nan: not measured)
    best: str
    best_at_100k: float

    @property
    def status(self) -> str:
        if math.isnan(self.at_100k):
            return "not measured"
        return "right" if round(self.best_at_100k - self.at_100k, 3) <= TOLERANCE else "wrong"

    def row(self) -> str:
        at = "not measured" if math.isnan(self.at_100k) else f"{100 * self.at_100k:.1f} %"
        return (f"| {self.shape} | {self.first} {100 * self.first_fraction:.1f} % | {at} | {self.best} "
                f"{100 * self.best_at_100k:.1f} % | {self.status} |")


def judge(shape: str, ranking: list[Ranked], truth: dict[tuple[str, str], list[float]]) -> Verdict:
    """The first of ``ranking`` against the best of ``truth`` among the candidates the advice ran."""
    name = shape_name(shape)
    means = {r.candidate.label: float(np.mean(truth[(name, r.candidate.label)]))
             for r in ranking if (name, r.candidate.label) in truth}
    best = max(means, key=means.__getitem__) if means else "none measured"
    first = ranking[0].candidate.label
    return Verdict(name, first, ranking[0].fraction, means.get(first, math.nan), best, means.get(best, math.nan))


def shapes_checked(patterns: Iterable[str]) -> list[str]:
    """The shape files the glob ``patterns`` name, in order ('circle' and other names as they are)."""
    return [found for pattern in patterns for found in (sorted(glob.glob(pattern)) if "*" in pattern else [pattern])]


def table(runs: list[Timed], truth: dict[tuple[str, str], list[float]], cores: int, steps: int = advice.STEPS,
          truth_steps: int = STEPS) -> str:
    """A Markdown table: each shape's verdict and check, then what the advice took (``steps`` a trial; the
    truth at ``truth_steps``)."""
    rows = [f"| shape | the advice's first ({steps:,} steps) | the first at {truth_steps:,} steps | the best at "
            f"{truth_steps:,} steps | within {100 * TOLERANCE:.0f} point? | seconds | CPU seconds (/ {cores} cores) | "
            "time left: worst error (a few seconds said with at most) |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for run in runs:
        worst = "none" if math.isnan(run.worst_estimate) else f"{100 * run.worst_estimate:.0f} %"
        if not math.isnan(run.a_few_seconds_at_most):
            worst += f" ({run.a_few_seconds_at_most:.1f} s)"
        rows.append(f"{judge(run.shape, run.ranking, truth).row()} {run.seconds:.1f} | {run.cpu_seconds:.1f} "
                    f"({run.cpu_seconds / cores:.1f}) | {worst} |")
    return "\n".join(rows)


# ------------------------------------------------------- on a draw of generated shapes
#: On a draw, the share of the shapes advised whose first choice must be right (issue 57).
DRAW_SHARE = 0.9


@dataclass(frozen=True)
class DrawCheck:
    """The advice on a draw (``bench --advice --generated N``): each shape advised's verdict, and the shapes
    the model refuses (not advised: the advice has nothing to run)."""

    verdicts: list[Verdict]
    refused: list[str]

    def count(self, status: str) -> int:
        return sum(1 for v in self.verdicts if v.status == status)

    @property
    def share_right(self) -> float:
        """Right over every shape advised: one never measured counts against the advice, it is not known right."""
        return self.count("right") / len(self.verdicts) if self.verdicts else math.nan

    @property
    def passes(self) -> bool:
        return bool(self.verdicts) and self.share_right >= DRAW_SHARE

    def summary(self, steps: int = STEPS) -> list[str]:
        """In lines: the share right against :data:`DRAW_SHARE`, then every wrong and unmeasured shape."""
        share = "no shape advised" if not self.verdicts else f"{100 * self.share_right:.1f} %"
        out = [f"First choice within {100 * TOLERANCE:.0f} point of the best at {steps:,} steps: "
               f"{self.count('right')} of {len(self.verdicts)} shapes advised ({share}; at least "
               f"{100 * DRAW_SHARE:.0f} % wanted): {'passes' if self.passes else 'FAILS'}. Wrong: "
               f"{self.count('wrong')}, not measured: {self.count('not measured')}, refused by the model (not "
               f"advised): {len(self.refused)}."]
        out += [f"wrong: {v.shape}: first {v.first} {_pct(v.at_100k)}, best {v.best} {_pct(v.best_at_100k)}"
                for v in self.verdicts if v.status == "wrong"]
        out += [f"not measured: {v.shape}: first {v.first} (no trial of it at {steps:,} steps in the truth)"
                for v in self.verdicts if v.status == "not measured"]
        return out


def _pct(fraction: float) -> str:
    return "–" if math.isnan(fraction) else f"{100 * fraction:.1f} %"


def advise_draw(config: Config, shapes: Iterable, *, workers: int, steps: int = advice.STEPS,
                heard: Callable[[str], None] | None = None) -> tuple[list[Timed], list[str]]:
    """The default advice on every generated shape (``shapes``: :class:`GeneratedShape`) the model builds under
    ``config``, timed; and the names of those it refuses (:func:`sandbox.experiments.draws.refusal`)."""
    from sandbox.experiments.draws import refusal

    runs, refused = [], []
    for shape in shapes:
        if refusal(config.replace(shape=shape.name), shape.vertices):
            refused.append(shape.name)
            continue
        if heard:
            heard(shape.name)
        runs.append(timed_advice(shape.name, config, workers=workers, steps=steps))
    return runs, refused


def truth_files(folders: Iterable[str]) -> list[str]:
    """The ``final.csv`` of each folder a candidates sweep's report wrote (a file is taken as it is); a
    ValueError naming the first missing one."""
    files = [str(f) if Path(f).is_file() or str(f).endswith(".csv") else str(Path(f) / "final.csv")
             for f in folders]  # a folder, even one not yet written: its report's final.csv
    missing = [f for f in files if not Path(f).is_file()]
    if missing:
        raise ValueError(f"no {missing[0]}: run 'phototaxis report {Path(missing[0]).parent} --no-figures' on the "
                         f"candidates sweep first (phototaxis sweep --generated N --candidates)")
    return files
