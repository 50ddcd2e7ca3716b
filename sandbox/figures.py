"""Plots of a sweep (the paper's Figures 4-7), drawn with matplotlib's object API (no GUI backend).

- :func:`plot_metric`: a metric over steps, the mean over trials and a shaded
  one-standard-deviation band per case (Figures 4 and 5).
- :func:`plot_layouts`: the final box layout of one representative trial
  per case (Figures 6 and 7).

Each writes a PNG and an SVG and returns the PNG's path.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from . import stats

IN_GOAL, OUTSIDE, ROBOT, GOAL = "#2e7d32", "#e65100", "#607d8b", "#000000"


def _colours(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return [cmap(i % cmap.N) for i in range(n)]


def _save(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path.with_suffix(".png"), dpi=150, bbox_inches="tight")
    fig.savefig(path.with_suffix(".svg"), bbox_inches="tight")
    return path.with_suffix(".png")


def plot_metric(by_case: dict[str, list[dict]], metric: str, path: Path) -> Path:
    fig = Figure(figsize=(8.0, 4.8))
    ax = fig.add_subplot()
    for colour, (case, trials) in zip(_colours(len(by_case)), by_case.items()):
        steps, mean, std, n = stats.series(trials, metric)
        if not len(steps):
            continue
        ax.plot(steps, mean, color=colour, lw=1.6, label=f"{case} (n={n})")
        ax.fill_between(steps, mean - std, mean + std, color=colour, alpha=0.15, lw=0)
    ax.set_xlabel("world step")
    ax.set_ylabel(stats.LABELS[metric])
    if metric == "fraction_in_goal":
        ax.set_ylim(0, 1)
    else:
        ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.set_title(f"{stats.LABELS[metric].capitalize()}: mean ± 1 s.d. over trials")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    return _save(fig, path)


def _hexagons(centres: np.ndarray, angles: np.ndarray, circumradius: float) -> np.ndarray:
    k = np.arange(6) * (math.pi / 3)
    a = angles[:, None] + k[None, :]
    return np.stack([centres[:, 0:1] + circumradius * np.cos(a), centres[:, 1:2] + circumradius * np.sin(a)], axis=-1)


def draw_layout(ax, trial: dict, *, margin: float = 1.0) -> None:
    """One trial's final layout around the construction area: goal outline, boxes, robots."""
    from .config import Config

    cfg = Config(**trial["config"])
    final = trial["final"]
    centre = cfg.arena_size / 2.0
    half = cfg.construction_size / 2.0 + margin
    boxes = np.asarray(final["box_positions"], dtype=float).reshape(-1, 2)
    angles = np.asarray(final["box_angles"], dtype=float)
    inside = np.asarray(final["box_in_goal"], dtype=bool)
    if len(boxes):
        hexes = _hexagons(boxes, angles, cfg.box_circumradius)
        ax.add_collection(PolyCollection(hexes, facecolors=[IN_GOAL if i else OUTSIDE for i in inside],
                                         edgecolors="none"))
    robots = np.asarray(final["robot_positions"], dtype=float).reshape(-1, 2)
    if len(robots):
        points_per_metre = ax.get_window_extent().width / ax.figure.dpi * 72 / (2 * half)
        ax.scatter(robots[:, 0], robots[:, 1], s=(2 * cfg.robot_radius * points_per_metre) ** 2,
                   c=ROBOT, alpha=0.5, lw=0)
    goal = np.asarray(final["goal_outline"], dtype=float)
    ax.add_patch(_closed(goal, GOAL))
    c = cfg.construction_size / 2.0
    ax.plot(centre + np.array([-c, c, c, -c, -c]), centre + np.array([-c, -c, c, c, -c]), color="#9e9e9e", lw=0.8,
            ls="--")
    ax.set_xlim(centre - half, centre + half)
    ax.set_ylim(centre - half, centre + half)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def _closed(vertices: np.ndarray, colour: str):
    from matplotlib.patches import Polygon

    return Polygon(vertices, closed=True, fill=False, edgecolor=colour, lw=1.2)


def plot_layouts(by_case: dict[str, list[dict]], path: Path) -> Path:
    n = len(by_case)
    cols = min(4, n)
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(3.2 * cols, 3.5 * rows))
    for i, (case, trials) in enumerate(by_case.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        trial = stats.representative(trials)
        draw_layout(ax, trial)
        frac = trial["samples"]["fraction_in_goal"][-1]
        ax.set_title(f"{case}\nseed {trial['seed']}, {frac:.1%} in goal", fontsize=9)
    fig.suptitle("Final box layouts (trial nearest each case's median; green: in goal, orange: outside, "
                 "grey dots: robots)", fontsize=9)
    fig.tight_layout()
    return _save(fig, path)
