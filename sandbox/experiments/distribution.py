"""How a draw of generated shapes builds (:mod:`.draws`): the distribution ``phototaxis report`` writes for
it. The unit is a shape: its value is the mean, over its trials (seeds), of the fraction of boxes in the
goal at the final step. Per family: how many shapes, how many the model refused (counted, never run),
the median, the 10th percentile and the mean ± standard error of the shapes' values; over all shapes the
percentiles; and the ten worst shapes, with a picture of their final layouts."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sandbox.experiments import stats

#: The percentiles of the whole draw (numpy's linear interpolation between the shapes' values).
PERCENTILES = (10, 25, 50, 75, 90)
#: How many of the worst shapes are listed and drawn.
WORST = 10
METRIC = "fraction_in_goal"


@dataclass(frozen=True)
class ShapeResult:
    """One generated shape of the draw: its record (name, family, kind, seed, parameters, refusal) and the
    final fraction in the goal of each of its trials (none when refused or not yet run)."""

    record: dict
    values: tuple[float, ...]
    outline: str = ""

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
    """Every shape of the draw's record, in its order, with its trials' final values."""
    results = []
    for record in generated.get("shapes", []):
        trials = by_case.get(record["name"], [])
        values = tuple(float(v) for v in stats.final_values(trials, METRIC)) if trials else ()
        outline = trials[0].get("outline", "") if trials else ""
        results.append(ShapeResult(record, values, outline))
    return results


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
                         "min", "max", "outline_family", "params"])
        for r in results:
            writer.writerow([r.name, r.family, r.record.get("kind", ""), r.record.get("seed", ""), r.refused,
                             len(r.values), stats.fmt(r.value, 4) if r.values else "",
                             stats.fmt(min(r.values), 4) if r.values else "",
                             stats.fmt(max(r.values), 4) if r.values else "", r.outline,
                             json.dumps(r.record.get("params", {}), separators=(",", ":"))])


def draw_worst(results: list[ShapeResult], by_case: dict[str, list[dict]], path: Path) -> Path | None:
    """The final layouts of the worst shapes (each trial nearest its shape's median)."""
    from sandbox.experiments import figures  # matplotlib: only when a report is drawn

    shown = {r.name: by_case[r.name] for r in worst(results)}
    return figures.plot_layouts(shown, path) if shown else None


def by_family(results: list[ShapeResult], by_case: dict[str, list[dict]]) -> dict[str, list[dict]]:
    """Every trial of the draw, by its shape's family (for the metrics over time, a line per family)."""
    grouped: dict[str, list[dict]] = {}
    for r in results:
        grouped.setdefault(r.family, []).extend(by_case.get(r.name, []))
    return {family: trials for family, trials in grouped.items() if trials}


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def section(generated: dict, results: list[ShapeResult], figure: str | None) -> list[str]:
    """The report's section on the draw, in markdown lines; ``figure`` the worst shapes' picture (relative)."""
    draws = "; ".join(f"{d['count']} shapes of {', '.join(d['families'])}, generator seed {d['generator_seed']}"
                      for d in generated.get("draws", []))
    out = ["", "## The distribution over generated shapes", "",
           f"The draw: {draws}. Each shape is one case, named after its family and seed "
           f"(`phototaxis run --shape NAME` builds it again; docs/shapes.md). A shape's value is the mean over its "
           f"trials of the fraction of boxes in the goal at the final step; the statistics below are over "
           f"shapes. Shapes the model refuses are counted and never run.", "",
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
        out += ["", f"Refused ({len(refused)}):", ""]
        out += [f"- `{r.name}` ({r.family}{', ' + r.record['kind'] if r.record.get('kind') else ''}): {r.refused}"
                for r in refused]
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
