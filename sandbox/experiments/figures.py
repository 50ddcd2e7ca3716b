"""Plots of a sweep (the paper's Figures 4-7), drawn with matplotlib's object API (no GUI backend).

- :func:`plot_metric`: a metric over steps, the mean over trials and a shaded
  one-standard-deviation band per case (Figures 4 and 5).
- :func:`plot_layouts`: the final box layout of one representative trial
  per case (Figures 6 and 7).

Each writes a PNG and an SVG and returns the PNG's path. The layouts' PNG is
the one figure ``report.md`` shows, and the one the repository keeps of each
committed evaluation, so it is written compact (:func:`compact_png`); the SVG
keeps every detail.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
from PIL import Image
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from sandbox.experiments import stats
from sandbox.model.config import config_from_record

IN_GOAL, OUTSIDE, ROBOT, GOAL = "#2e7d32", "#e65100", "#607d8b", "#000000"


def _colours(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return [cmap(i % cmap.N) for i in range(n)]


#: The compact PNG: at most this wide, in a palette of this many colours, and narrower until it fits in
#: this many bytes (never narrower than the last). The layouts use a handful of flat colours, so the
#: palette loses nothing a reader sees; 1000 px keeps a 4-column grid's captions legible.
COMPACT_WIDTH, COMPACT_COLOURS, COMPACT_BYTES, COMPACT_NARROWEST = 1000, 32, 150_000, 600


def _save(fig: Figure, path: Path, *, compact: bool = False) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    png = path.with_suffix(".png")
    if compact:
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=150, bbox_inches="tight")
        buffer.seek(0)
        compact_png(Image.open(buffer), png)
    else:
        fig.savefig(png, dpi=150, bbox_inches="tight")
    fig.savefig(path.with_suffix(".svg"), bbox_inches="tight")
    return png


def compact_png(image: Image.Image, path: Path) -> int:
    """Write ``image`` as a small PNG (see COMPACT_WIDTH): scaled down, palette-coded; its size in bytes."""
    image = image.convert("RGB")
    width = min(COMPACT_WIDTH, image.width)
    while True:
        scaled = image if width == image.width else image.resize(
            (width, round(image.height * width / image.width)), Image.Resampling.LANCZOS)
        buffer = io.BytesIO()
        scaled.quantize(COMPACT_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE).save(
            buffer, format="PNG", optimize=True)
        if buffer.tell() <= COMPACT_BYTES or width <= COMPACT_NARROWEST:
            break
        width = max(COMPACT_NARROWEST, int(width * 0.85))
    path.write_bytes(buffer.getvalue())
    return buffer.tell()


#: The paper plots its square/circle cases and its star cases apart.
PAPER_PANELS = (("circle", "square", "square-flare", "square-flare-switch"),
                ("star", "star-switch", "star-switch-nocorners"))
STYLES = ("-", "--", "-.", ":")


def panels(cases: list[str]) -> list[list[str]]:
    """Cases per panel: the paper's two groups when both are present, else one panel."""
    groups = [[c for c in group if c in cases] for group in PAPER_PANELS]
    rest = [c for c in cases if not any(c in g for g in groups)]
    if all(groups) and not rest:
        return groups
    return [list(cases)]


def plot_metric(by_case: dict[str, list[dict]], metric: str, path: Path) -> Path:
    """Mean over trials and a shaded ±1 s.d. band per case (the paper's Figures 4 and 5)."""
    groups = panels(list(by_case))
    colour = dict(zip(by_case, _colours(len(by_case))))
    fig = Figure(figsize=(6.4 * len(groups) if len(groups) > 1 else 8.0, 4.6), layout="constrained")
    axes = fig.subplots(1, len(groups), sharey=True, squeeze=False)[0]
    for ax, group in zip(axes, groups):
        for i, case in enumerate(group):
            steps, mean, std, n = stats.series(by_case[case], metric)
            if not len(steps):
                continue
            ax.plot(steps, mean, color=colour[case], lw=1.6, ls=STYLES[i % len(STYLES)], label=f"{case} (n={n})")
            ax.fill_between(steps, mean - std, mean + std, color=colour[case], alpha=0.15, lw=0)
        ax.set_xlabel("world step")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best" if len(groups) > 1 else "center left",
                  bbox_to_anchor=None if len(groups) > 1 else (1.01, 0.5), frameon=len(groups) > 1)
    axes[0].set_ylabel(stats.LABELS[metric])
    if metric == "fraction_in_goal":
        axes[0].set_ylim(0, 1)
    else:
        axes[0].set_ylim(bottom=0)
    fig.suptitle(f"{stats.LABELS[metric].capitalize()}: mean ± 1 s.d. over trials", fontsize=11)
    return _save(fig, path)


def _hexagons(centres: np.ndarray, angles: np.ndarray, circumradius: float) -> np.ndarray:
    k = np.arange(6) * (math.pi / 3)
    a = angles[:, None] + k[None, :]
    return np.stack([centres[:, 0:1] + circumradius * np.cos(a), centres[:, 1:2] + circumradius * np.sin(a)], axis=-1)


def draw_layout(ax, trial: dict, *, margin: float = 1.0) -> None:
    """One trial's final layout around the construction area: goal outline, boxes, robots."""
    cfg = config_from_record(trial["config"])
    final = trial["final"]
    centre = cfg.centre
    goal = np.asarray(final["goal_outline"], dtype=float)
    reach = float(np.abs(goal - centre).max()) if len(goal) else 0.0
    half = max(cfg.construction_size / 2.0, reach) + margin
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
    fig = Figure(figsize=(3.2 * cols, 3.7 * rows + 0.4), layout="constrained")
    for i, (case, trials) in enumerate(by_case.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        trial = stats.representative(trials)
        draw_layout(ax, trial)
        frac = trial["samples"]["fraction_in_goal"][-1]
        ax.set_title(f"{case}\nseed {trial['seed']}, {frac:.1%} in goal", fontsize=9)
    fig.suptitle("Final box layouts (trial nearest each case's median; green: in goal, orange: outside, "
                 "grey dots: robots)", fontsize=9)
    return _save(fig, path, compact=True)
