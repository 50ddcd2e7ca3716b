"""Statistics over trials: per-case summary tables and Kolmogorov–Smirnov tests (SPEC §6).

Input everywhere is a mapping ``case -> list of trial results`` as loaded by
:meth:`sandbox.sweep.ResultStore.load` (each with ``samples``, a dict of
numpy arrays from the trial's CSV).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np

#: The case pairs the paper compares with two-sample KS tests (its Tables IV and V).
PAPER_PAIRS = [
    ("square", "square-flare"),
    ("square-flare", "square-flare-switch"),
    ("square", "square-flare-switch"),
    ("star", "star-switch"),
    ("star-switch", "star-switch-nocorners"),
    ("star", "star-switch-nocorners"),
]

LABELS = {
    "fraction_in_goal": "fraction of boxes in the goal",
    "mean_outside_distance": "mean distance of boxes outside the goal (m)",
}


@dataclass(frozen=True)
class Summary:
    case: str
    metric: str
    n: int
    step: int
    mean: float
    median: float
    std: float
    sem: float
    low: float
    high: float


def final_values(trials: list[dict], metric: str) -> np.ndarray:
    return np.array([t["samples"][metric][-1] for t in trials], dtype=float)


def after_first_cycle(trials: list[dict], metric: str) -> np.ndarray:
    """The metric at the first sample after each trial's first full cycle (NaN if it never finished one)."""
    out = []
    for t in trials:
        s = t["samples"]
        idx = np.flatnonzero(s["cycle"] >= 1)
        out.append(s[metric][idx[0]] if len(idx) else math.nan)
    return np.array(out, dtype=float)


def over_last_whole_cycle(trials: list[dict], metric: str) -> np.ndarray:
    """Each trial's mean of the metric over the samples of its last whole cycle: those taken while
    ``cycle`` (the cycles finished) was one less than at its last sample (NaN before a second cycle
    starts). An open loop runs the same schedule in every seed, so every trial's last step falls at the
    same phase of its cycle; a shape whose fraction swings within a cycle is better told by this mean."""
    out = []
    for t in trials:
        s = t["samples"]
        cycle = np.asarray(s["cycle"], dtype=float)
        last = cycle[-1] - 1 if len(cycle) else -1
        inside = cycle == last
        out.append(float(np.mean(np.asarray(s[metric], dtype=float)[inside])) if last >= 0 and inside.any()
                   else math.nan)
    return np.array(out, dtype=float)


def describe(case: str, metric: str, values: np.ndarray, step: int) -> Summary:
    values = values[np.isfinite(values)]
    n = len(values)
    if n == 0:
        return Summary(case, metric, 0, step, *([math.nan] * 6))
    std = float(np.std(values, ddof=1)) if n > 1 else math.nan
    return Summary(case, metric, n, step, float(np.mean(values)), float(np.median(values)), std,
                   std / math.sqrt(n) if n > 1 else math.nan, float(np.min(values)), float(np.max(values)))


def summaries(by_case: dict[str, list[dict]], metric: str, *, when: str = "final") -> list[Summary]:
    rows = []
    for case, trials in by_case.items():
        if when == "final":
            values = final_values(trials, metric)
            step = int(max(t["samples"]["step"][-1] for t in trials))
        elif when == "last-cycle":
            values = over_last_whole_cycle(trials, metric)
            step = -1
        else:
            values = after_first_cycle(trials, metric)
            step = -1
        rows.append(describe(case, metric, values, step))
    return rows


@dataclass(frozen=True)
class KSTest:
    a: str
    b: str
    metric: str
    n_a: int
    n_b: int
    statistic: float
    pvalue: float
    mean_a: float
    mean_b: float


def ks_tests(by_case: dict[str, list[dict]], pairs: list[tuple[str, str]], metric: str) -> list[KSTest]:
    """Two-sample KS test of the final-step metric for each pair whose cases both have trials."""
    from scipy.stats import ks_2samp

    rows = []
    for a, b in pairs:
        if a not in by_case or b not in by_case:
            continue
        xa, xb = final_values(by_case[a], metric), final_values(by_case[b], metric)
        if len(xa) == 0 or len(xb) == 0:
            continue
        res = ks_2samp(xa, xb)
        rows.append(KSTest(a, b, metric, len(xa), len(xb), float(res.statistic), float(res.pvalue),
                           float(np.mean(xa)), float(np.mean(xb))))
    return rows


def default_pairs(cases: list[str], extra: list[tuple[str, str]] | None = None) -> list[tuple[str, str]]:
    """The paper's pairs present in ``cases``, plus ``extra``; all pairs of a small sweep with neither."""
    pairs = [p for p in PAPER_PAIRS if p[0] in cases and p[1] in cases]
    for p in extra or []:
        if tuple(p) not in pairs:
            pairs.append(tuple(p))
    if not pairs and 2 <= len(cases) <= 6:
        pairs = list(combinations(cases, 2))
    return pairs


def series(trials: list[dict], metric: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Steps, mean and standard deviation over trials of a metric, on the steps all trials share."""
    common = None
    for t in trials:
        steps = set(t["samples"]["step"].tolist())
        common = steps if common is None else common & steps
    steps = np.array(sorted(common or []), dtype=int)
    if len(steps) == 0:
        return steps, np.array([]), np.array([]), 0
    table = np.array([[dict(zip(t["samples"]["step"].tolist(), t["samples"][metric]))[s] for s in steps]
                      for t in trials], dtype=float)
    std = table.std(axis=0, ddof=1) if len(trials) > 1 else np.zeros(len(steps))
    return steps, table.mean(axis=0), std, len(trials)


def representative(trials: list[dict], metric: str = "fraction_in_goal") -> dict:
    """The trial whose final metric is closest to the case's median (ties: lowest seed)."""
    values = final_values(trials, metric)
    median = float(np.median(values))
    order = sorted(range(len(trials)), key=lambda i: (abs(values[i] - median), trials[i]["seed"]))
    return trials[order[0]]


def fmt(x: float, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.{digits}f}"


def fmt_p(p: float) -> str:
    if not math.isfinite(p):
        return "–"
    return f"{p:.2e}" if p < 1e-3 else f"{p:.3f}"
