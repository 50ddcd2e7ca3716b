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
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from sandbox.experiments import advise as advice
from sandbox.experiments.advise import Candidate, Ranked
from sandbox.experiments.pace import A_FEW_SECONDS
from sandbox.experiments.storage import write_whole
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
    unmeasured: tuple[str, ...] = ()  # candidates the advice ran that the truth lacks (judged with every_one)

    @property
    def status(self) -> str:
        if math.isnan(self.at_100k) or self.unmeasured:
            return "not measured"
        return "right" if round(self.best_at_100k - self.at_100k, 3) <= TOLERANCE else "wrong"

    def row(self) -> str:
        at = "not measured" if math.isnan(self.at_100k) else f"{100 * self.at_100k:.1f} %"
        return (f"| {self.shape} | {self.first} {100 * self.first_fraction:.1f} % | {at} | {self.best} "
                f"{100 * self.best_at_100k:.1f} % | {self.status} |")


def judge(shape: str, ranking: list[Ranked], truth: dict[tuple[str, str], list[float]], *,
          every_one: bool = False) -> Verdict:
    """The first of ``ranking`` against the best of ``truth`` among the candidates the advice ran. With
    ``every_one`` a shape is judged only when the truth has every one of them: a best among some is not known
    to be the best (a candidates sweep still running)."""
    name = shape_name(shape)
    means = {r.candidate.label: float(np.mean(truth[(name, r.candidate.label)]))
             for r in ranking if (name, r.candidate.label) in truth}
    best = max(means, key=means.__getitem__) if means else "none measured"
    first = ranking[0].candidate.label
    unmeasured = tuple(r.candidate.label for r in ranking if r.candidate.label not in means) if every_one else ()
    return Verdict(name, first, ranking[0].fraction, means.get(first, math.nan), best, means.get(best, math.nan),
                   unmeasured)


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
        out += [f"not measured: {v.shape}: first {v.first} ({_missing(v, steps)})"
                for v in self.verdicts if v.status == "not measured"]
        judged = [v for v in self.verdicts if v.status != "not measured"]
        if judged and len(judged) < len(self.verdicts):
            out.insert(1, f"Of the {len(judged)} shapes whose candidates were all measured: {self.count('right')} "
                          f"right ({100 * self.count('right') / len(judged):.1f} %).")
        return out


def _missing(verdict: Verdict, steps: int) -> str:
    if verdict.unmeasured:
        return f"no trial at {steps:,} steps in the truth of {', '.join(verdict.unmeasured)}"
    return f"no trial of it at {steps:,} steps in the truth"


def _pct(fraction: float) -> str:
    return "–" if math.isnan(fraction) else f"{100 * fraction:.1f} %"


def advise_draw(config: Config, shapes: Iterable, *, workers: int, steps: int = advice.STEPS,
                heard: Callable[[str], None] | None = None, store: Path | None = None
                ) -> tuple[list[Timed], list[str]]:
    """The default advice on every generated shape (``shapes``: :class:`GeneratedShape`) the model builds under
    ``config``, timed; and the names of those it refuses (:func:`sandbox.experiments.draws.refusal`). With a
    ``store`` folder each shape's advice is kept there as it ends and read back on the next call with the same
    settings, so a long draw resumes where it stopped and can be judged again on a grown truth."""
    from sandbox.experiments.draws import refusal

    if store:
        try:  # a folder that cannot be one fails here, before any advice runs
            store.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"cannot keep the advice in {store}: {exc.strerror or exc}") from None
    runs, refused = [], []
    for shape in shapes:
        if refusal(config.replace(shape=shape.name), shape.vertices):
            refused.append(shape.name)
            continue
        kept = load_timed(store, shape.name, config, steps) if store else None
        if kept is None:
            if heard:
                heard(shape.name)
            kept = timed_advice(shape.name, config, workers=workers, steps=steps)
            if store:
                save_timed(store, kept, config, steps)
        runs.append(kept)
    return runs, refused


def _settings(shape: str, config: Config, steps: int) -> dict:
    """What a kept advice was run with: the whole configuration on the shape, and the steps a trial."""
    return {"config": config.replace(shape=shape).to_dict(), "steps": steps, "seeds": advice.SEEDS}


def save_timed(store: Path, run: Timed, config: Config, steps: int) -> None:
    """``store/<shape>.json``: the advice ``run`` and the settings it ran with (written whole)."""
    ranking = [{"outline": r.candidate.outline, "strategies": [list(s) for s in r.candidate.strategies],
                "fractions": r.fractions, "distances": r.distances, "cpu_seconds": r.cpu_seconds}
               for r in run.ranking]
    record = {"settings": _settings(run.shape, config, steps), "shape": run.shape, "verdict": run.verdict,
              "seconds": run.seconds, "cpu_seconds": run.cpu_seconds, "estimates": run.estimates,
              "ranking": ranking}
    write_whole(store / f"{run.shape}.json", json.dumps(record))


def load_timed(store: Path, shape: str, config: Config, steps: int) -> Timed | None:
    """The advice on ``shape`` kept in ``store``, or None when none is (or a torn file); a ValueError when it ran
    with other settings (its folder belongs to another draw or other flags)."""
    path = store / f"{shape}.json"
    try:
        record = json.loads(path.read_text())
        ranking = [Ranked(Candidate(r["outline"], tuple((name, float(amount)) for name, amount in r["strategies"])),
                          list(r["fractions"]), list(r["distances"]), float(r["cpu_seconds"]))
                   for r in record["ranking"]]
        settings = record["settings"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not ranking:
        return None  # nothing to judge: run it again
    if settings != json.loads(json.dumps(_settings(shape, config, steps))):
        raise ValueError(f"{path} holds the advice on {shape} run with other settings; use another --out or "
                         f"delete it")
    return Timed(shape, ranking, record["verdict"], record["seconds"], record["cpu_seconds"],
                 [tuple(e) for e in record["estimates"]])


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
