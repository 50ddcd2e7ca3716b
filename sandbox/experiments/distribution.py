"""How a draw of generated shapes builds (:mod:`.draws`): the distribution ``phototaxis report`` writes for
it. The unit is a shape: its value is the mean, over its trials (seeds), of the fraction of boxes in the
goal at the final step. Per family: how many shapes, how many the model refused (counted, never run),
the median, the 10th percentile and the mean ± standard error of the shapes' values; over all shapes the
percentiles; and the ten worst shapes, with a picture of their final layouts.

A sweep of every advice candidate of each shape (``sweep --generated N --candidates``,
:mod:`.draw_candidates`) gives each shape its candidates' values too: a shape's value is then its default
candidate's (what it gets without advice), and each refused shape says the best any strategy reached, so
the refusal rule can be read off the report: a refused shape no strategy builds
:data:`BUILDS` or more."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sandbox.experiments import stats
from sandbox.experiments.draw_candidates import SEPARATOR, split_label

#: The percentiles of the whole draw (numpy's linear interpolation between the shapes' values).
PERCENTILES = (10, 25, 50, 75, 90)
#: How many of the worst shapes are listed and drawn.
WORST = 10
METRIC = "fraction_in_goal"
#: A shape some strategy builds this well (its mean over seeds) must not be refused (issue 57's bar).
BUILDS = 0.75


@dataclass(frozen=True)
class ShapeResult:
    """One generated shape of the draw: its record (name, family, kind, seed, parameters, refusal) and the
    final fraction in the goal of each of its trials (none when refused or not yet run)."""

    record: dict
    values: tuple[float, ...]
    outline: str = ""
    #: The case whose trials gave ``values``: the shape's own, or its default candidate's.
    case: str = ""
    #: Each candidate run on it (candidate label, its trials' final values), in the sweep's order.
    candidates: tuple[tuple[str, tuple[float, ...]], ...] = ()

    @property
    def name(self) -> str:
        return self.record["name"]

    @property
    def family(self) -> str:
        return self.record["family"]

    @property
    def refused(self) -> str:
        return self.record.get("refused", "")

    @property
    def value(self) -> float:
        return float(np.mean(self.values)) if self.values else math.nan

    @property
    def best(self) -> tuple[str, float] | None:
        """The candidate that built it best (label, mean over its trials); None when none ran."""
        means = [(label, float(np.mean(values))) for label, values in self.candidates if values]
        return max(means, key=lambda m: m[1]) if means else None

    @property
    def candidates_planned(self) -> bool:
        """Whether a candidates sweep planned this shape (its record lists the candidates, maybe none)."""
        return "candidates" in self.record


@dataclass(frozen=True)
class FamilyRow:
    family: str
    shapes: int
    refused: int
    built: int
    median: float
    p10: float
    mean: float
    sem: float


def shape_results(generated: dict, by_case: dict[str, list[dict]]) -> list[ShapeResult]:
    """Every shape of the draw's record, in its order, with its trials' final values (its own case's, else
    its default candidate's) and its candidates'."""
    tried: dict[str, list[tuple[str, tuple[float, ...]]]] = {}
    for case, trials in by_case.items():
        split = split_label(case)
        if split is not None:
            tried.setdefault(split[0], []).append((split[1], _finals(trials)))
    results = []
    for record in generated.get("shapes", []):
        case = record["name"]
        if case not in by_case and record.get("default"):
            case = f"{record['name']}{SEPARATOR}{record['default']}"
        trials = by_case.get(case, [])
        outline = trials[0].get("outline", "") if trials else ""
        results.append(ShapeResult(record, _finals(trials), outline, case if trials else "",
                                   tuple(tried.get(record["name"], ()))))
    return results


def _finals(trials: list[dict]) -> tuple[float, ...]:
    return tuple(float(v) for v in stats.final_values(trials, METRIC)) if trials else ()


def _spread(values: list[float]) -> tuple[float, float, float, float]:
    """Median, 10th percentile, mean and standard error (NaN where there are too few values)."""
    if not values:
        return (math.nan,) * 4
    a = np.asarray(values, dtype=float)
    sem = float(np.std(a, ddof=1) / math.sqrt(len(a))) if len(a) > 1 else math.nan
    return float(np.median(a)), float(np.percentile(a, 10)), float(np.mean(a)), sem


def family_rows(results: list[ShapeResult]) -> list[FamilyRow]:
    """One row per family in the draw (in the order they first appear), then one for all of them."""
    families = list(dict.fromkeys(r.family for r in results))
    rows = []
    for family in [*families, "all"]:
        mine = [r for r in results if family in ("all", r.family)]
        built = [r.value for r in mine if r.values]
        rows.append(FamilyRow(family, len(mine), sum(1 for r in mine if r.refused), len(built), *_spread(built)))
    return rows


def percentiles(results: list[ShapeResult]) -> dict[str, float]:
    built = [r.value for r in results if r.values]
    if not built:
        return {}
    a = np.asarray(built, dtype=float)
    return {"min": float(a.min()), **{f"p{p}": float(np.percentile(a, p)) for p in PERCENTILES},
            "max": float(a.max())}


def worst(results: list[ShapeResult], count: int = WORST) -> list[ShapeResult]:
    """The ``count`` shapes with the lowest values (ties: by name)."""
    return sorted((r for r in results if r.values), key=lambda r: (r.value, r.name))[:count]


def write_csv(results: list[ShapeResult], path: Path) -> None:
    """One row per shape: its name, family, kind, seed, refusal, trials, value and parameters (JSON)."""
    with path.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["shape", "family", "kind", "shape_seed", "refused", "trials", "mean_fraction_in_goal",
                         "min", "max", "outline_family", "candidates_run", "best_candidate",
                         "best_fraction_in_goal", "params"])
        for r in results:
            best = r.best
            writer.writerow([r.name, r.family, r.record.get("kind", ""), r.record.get("seed", ""), r.refused,
                             len(r.values), stats.fmt(r.value, 4) if r.values else "",
                             stats.fmt(min(r.values), 4) if r.values else "",
                             stats.fmt(max(r.values), 4) if r.values else "", r.outline,
                             sum(1 for _, values in r.candidates if values), best[0] if best else "",
                             stats.fmt(best[1], 4) if best else "",
                             json.dumps(r.record.get("params", {}), separators=(",", ":"))])


def draw_worst(results: list[ShapeResult], by_case: dict[str, list[dict]], path: Path) -> Path | None:
    """The final layouts of the worst shapes (each trial nearest its shape's median)."""
    from sandbox.experiments import figures  # matplotlib: only when a report is drawn

    shown = {r.name: by_case[r.case] for r in worst(results)}
    return figures.plot_layouts(shown, path) if shown else None


def by_family(results: list[ShapeResult], by_case: dict[str, list[dict]]) -> dict[str, list[dict]]:
    """Every trial of the draw, by its shape's family (for the metrics over time, a line per family)."""
    grouped: dict[str, list[dict]] = {}
    for r in results:
        grouped.setdefault(r.family, []).extend(by_case.get(r.case, []))
    return {family: trials for family, trials in grouped.items() if trials}


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def section(generated: dict, results: list[ShapeResult], figure: str | None) -> list[str]:
    """The report's section on the draw, in markdown lines; ``figure`` the worst shapes' picture (relative)."""
    draws = "; ".join(f"{d['count']} shapes of {', '.join(d['families'])}, generator seed {d['generator_seed']}"
                      f"{', part {0} of {1}'.format(*d['part']) if d.get('part') else ''}"
                      f"{', every advice candidate of each' if d.get('candidates') else ''}"
                      for d in generated.get("draws", []))
    out = ["", "## The distribution over generated shapes", "",
           f"The draw: {draws}. Each shape is one case, named after its family and seed "
           f"(`phototaxis run --shape NAME` builds it again; docs/shapes.md). A shape's value is the mean over its "
           f"trials of the fraction of boxes in the goal at the final step; the statistics below are over "
           f"shapes. {_refused_said(results)}", "",
           _table(["family", "shapes", "refused", "run", "median", "10th percentile", "mean ± s.e."],
                  [[f"**{r.family}**" if r.family == "all" else r.family, str(r.shapes), str(r.refused),
                    str(r.built), stats.fmt(r.median), stats.fmt(r.p10),
                    f"{stats.fmt(r.mean)} ± {stats.fmt(r.sem)}"] for r in family_rows(results)])]
    spread = percentiles(results)
    if spread:
        out += ["", "Over all shapes run (percentiles by linear interpolation):", "",
                _table(list(spread), [[stats.fmt(v) for v in spread.values()]])]
    out += _worst_lines(results, figure)
    refused = [r for r in results if r.refused]
    if refused:
        out += ["", f"Refused ({len(refused)}), each with the model's reason"
                f"{' and the best any strategy reached' if any(r.candidates_planned for r in refused) else ''}:", ""]
        out += [f"- `{r.name}` ({r.family}{', ' + r.record['kind'] if r.record.get('kind') else ''}): "
                f"{r.refused}{_best_said(r)}" for r in refused]
    out += _refusal_check(results)
    out += ["", "`generated.csv`: every shape's family, kind, seed, refusal, value and parameters."]
    return out


def _worst_lines(results: list[ShapeResult], figure: str | None) -> list[str]:
    shown = worst(results)
    if not shown:
        return []
    rows = [[str(i + 1), f"`{r.name}`", r.family, r.record.get("kind", "") or "–", stats.fmt(r.value),
             ", ".join(stats.fmt(v) for v in r.values), r.outline or "–"] for i, r in enumerate(shown)]
    out = ["", f"### The {len(shown)} worst shapes", "",
           _table(["", "shape", "family", "kind", "mean", "trials", "outline"], rows)]
    if figure:
        out += ["", "Their final layouts (the trial nearest each shape's median; green boxes in the goal, orange "
                "outside, the dashed square the construction area):", "", f"![worst shapes]({figure})"]
    return out


def _best_said(result: ShapeResult) -> str:
    """What the candidates sweep found on a refused shape ('' when none was planned for it)."""
    if not result.candidates_planned:
        return ""
    planned = len(result.record["candidates"])
    if not planned:
        return ". No strategy's settings build it: none of the advice's candidates ran."
    best = result.best
    if best is None:
        return f". Its {planned} candidate(s) that build it have not run yet"
    ran = sum(1 for _, values in result.candidates if values)
    return f". The best any strategy reached: {best[0]} {stats.fmt(best[1])} ({ran} of {planned} candidates run)"


def _refusal_check(results: list[ShapeResult]) -> list[str]:
    """The refusal rule read off the candidates: every refused shape some strategy builds :data:`BUILDS` or
    more (none, when the rule is right). Only for a sweep that ran the candidates."""
    if not any(r.candidates_planned for r in results):
        return []
    refused = [r for r in results if r.refused]
    wrong = [r for r in refused if r.best is not None and r.best[1] >= BUILDS]
    unknown = [r for r in refused if r.candidates_planned and r.record["candidates"] and r.best is None]
    out = ["", f"The refusal rule against the candidates: {len(refused)} of {len(results)} shapes refused "
           f"({stats.fmt(100 * len(refused) / len(results), 1)} %); refused although some strategy builds them "
           f"{stats.fmt(BUILDS, 2)} or more: "
           + (", ".join(f"`{r.name}` ({r.best[0]} {stats.fmt(r.best[1])})" for r in wrong) if wrong else "none")
           + "."]
    if unknown:
        out[-1] += f" Not yet run: {', '.join(f'`{r.name}`' for r in unknown)}."
    return out


def _refused_said(results: list[ShapeResult]) -> str:
    """What the section's values and refusals are: a plain draw's, or a candidates sweep's."""
    if not any(r.candidates_planned for r in results):
        return "Shapes the model refuses are counted and never run."
    return ("Here every candidate of the advice ran on each shape (`sweep --candidates`): a shape's value is its "
            "default candidate's (the outline `auto` takes, no strategy). A shape the model refuses with these "
            "settings is counted and runs only the candidates whose own settings build it, so its line below says "
            "the best any strategy reached.")
