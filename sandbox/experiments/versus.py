"""A sweep set beside an earlier one (``phototaxis report DIR --against OTHER``):
per case, both metrics with standard errors, their KS tests, and the light
energy each controller spent.

OTHER is a report folder (its ``final.csv``, one row per trial, as every
report writes). Its light energy is what its trials recorded. Reports
written before final.csv had that column lack it: the paper's open loop
(no *chase*) lights what it lights whatever the robots and boxes do, so its
energy is computed exactly from the controller alone; a closed loop's
cannot be, and shows as n/a.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from sandbox.experiments import stats
from sandbox.experiments.trials import SweepError
from sandbox.model.config import Config, coerce, param_names
from sandbox.model.programs import PAPER_CONTROLLER

METRICS = ("fraction_in_goal", "mean_outside_distance")


def read_final_csv(folder: str | Path) -> dict[str, list[dict]]:
    """Trials by case from a report folder's final.csv."""
    path = Path(folder) / "final.csv"
    if not path.is_file():
        raise SweepError(f"--against {folder}: no final.csv there (give a folder 'phototaxis report' wrote)")
    by_case: dict[str, list[dict]] = {}
    with path.open(newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            by_case.setdefault(row["case"], []).append(row)
    return by_case


def open_loop_energy(config: Config) -> float:
    """Sum of all intensities over ``config.steps`` steps of the paper's
    controller: what it lights never depends on the world, so no physics is run."""
    from sandbox.model.controller import Controller
    from sandbox.model.family import make_goal
    from sandbox.shapes import shape_vertices

    controller = Controller(config, make_goal(config, shape_vertices(config.shape)))
    energy = 0.0
    pattern_sum = float(controller.intensities.sum())
    for _ in range(config.steps):
        if controller.advance():
            pattern_sum = float(controller.intensities.sum())
        energy += pattern_sum
    return energy


def _config_of(row: dict) -> Config:
    """The configuration a final.csv row records (its parameter columns, as text)."""
    known = set(param_names())
    return Config(**{key: coerce(key, text) for key, text in row.items() if key in known and text not in (None, "")})


def their_light_energy(rows: list[dict]) -> float:
    """Mean light energy of a case's trials in a final.csv: as recorded, or, for
    an older file without the column, computed when they ran the paper's open
    loop (else NaN)."""
    recorded = [row.get("light_energy") or "" for row in rows]
    if all(recorded):
        return float(np.mean([float(value) for value in recorded]))
    config = _config_of(rows[0])
    if config.chase > 0 or rows[0].get("controller", "") not in ("", PAPER_CONTROLLER):
        return float("nan")
    return open_loop_energy(config)


def _millions(energy: float) -> str:
    return "n/a" if np.isnan(energy) else f"{energy / 1e6:.2f}"


def _mean_se(values: np.ndarray, digits: int) -> str:
    se = values.std(ddof=1) / np.sqrt(len(values)) if len(values) > 1 else float("nan")
    return f"{stats.fmt(values.mean(), digits)} ± {stats.fmt(se, digits)}"


def versus_section(by_case: dict[str, list[dict]], against: str | Path, label: str) -> tuple[list[str], list[dict]]:
    """Markdown lines and CSV rows setting this sweep's cases beside the same cases in ``against``."""
    from scipy.stats import ks_2samp

    other = read_final_csv(against)
    rows, table = [], []
    for case, trials in by_case.items():
        if case not in other:
            continue
        row = {"case": case, "trials": len(trials), "against_trials": len(other[case])}
        cells = [case]
        for metric in METRICS:
            ours = stats.final_values(trials, metric)
            theirs = np.array([float(r[metric]) for r in other[case]])
            p = ks_2samp(ours, theirs).pvalue
            row.update({f"{metric}_mean": ours.mean(), f"{metric}_against_mean": theirs.mean(), f"{metric}_ks_p": p})
            digits = 3 if metric == "fraction_in_goal" else 2
            cells += [_mean_se(theirs, digits), _mean_se(ours, digits), stats.fmt_p(p)]
        energy = np.array([float(t["light_energy"]) for t in trials if "light_energy" in t])
        theirs_energy = their_light_energy(other[case])
        row.update({"light_energy_mean": energy.mean() if len(energy) else float("nan"),
                    "light_energy_against": theirs_energy})
        cells += [_millions(theirs_energy), _millions(energy.mean()) if len(energy) else "n/a"]
        rows.append(row)
        table.append(cells)
    if not table:
        raise SweepError(f"--against {against}: no case in common")
    header = ["case", f"in goal: {label}", "in goal: here", "KS p", f"stray distance (m): {label}",
              "stray distance: here", "KS p", f"light energy (M): {label}", "light energy: here"]
    lines = ["", f"## Beside {label} ({Path(against).as_posix()})", "",
             "Final fraction of boxes in the goal and mean distance of the stray boxes (mean ± standard error), "
             "with two-sample KS tests (`scipy.stats.ks_2samp`, two-sided) between the two sets of trials. "
             "Light energy: the sum of all intensities over all steps, in millions (a light fully on for one step "
             "is 1), as the trials recorded it (for an older report without it, the open loop's is computed from "
             "its controller alone).", "",
             "| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(cells) + " |" for cells in table]
    return lines, rows
