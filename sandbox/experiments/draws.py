"""A draw of generated goal shapes as a sweep's cases (``phototaxis sweep --generated N``).

Each shape of the draw (:func:`sandbox.shapes.generator.draw`) is one case, named after the shape
(``gen-branching-0003``), its ``shape`` the shape's name, so that a trial, a report or ``phototaxis run
--shape gen-branching-0003`` makes the same goal again from the name alone. A shape the model refuses
(too large for the construction area, more vertices than the outlines afford, a smallest outline past the
arena: the checks a world makes before it is built) is not run but counted: its record keeps why.
``sweep.json`` keeps every shape's record (family, seed, kind, parameters, refusal) under ``generated``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.experiments.plan import Case, make_case
from sandbox.experiments.trials import SweepError
from sandbox.model.config import Config
from sandbox.shapes import ShapeError
from sandbox.shapes.generator import GeneratedShape, draw, families_from_text

#: The key of ``sweep.json`` that holds a draw.
META_KEY = "generated"


@dataclass(frozen=True)
class Draw:
    """What ``--generated``, ``--families``, ``--generator-seed`` and ``--part`` ask for."""

    count: int
    families: tuple[str, ...]
    generator_seed: int
    part: tuple[int, int] | None = None  # (k, n): the k-th of n runs of consecutive shapes, from 1

    @classmethod
    def from_flags(cls, count: int, families: str, generator_seed: int, part: str | None = None) -> "Draw":
        if count < 1:
            raise SweepError(f"--generated must be at least 1 (got {count})")
        try:
            chosen = families_from_text(families)
        except ShapeError as exc:
            raise SweepError(f"--families: {exc}") from None
        return cls(count, chosen, generator_seed, parse_part(part, count) if part else None)

    def shapes(self) -> list[GeneratedShape]:
        """The draw's shapes, or its part's: a part of a draw is the same shapes as the whole draw holds
        there (a draw's first k shapes never depend on its count)."""
        shapes = draw(self.count, self.families, self.generator_seed)
        if self.part is None:
            return shapes
        first, end = part_bounds(*self.part, self.count)
        return shapes[first:end]

    def record(self) -> dict:
        record = {"count": self.count, "families": list(self.families), "generator_seed": self.generator_seed}
        return {**record, "part": list(self.part)} if self.part else record


def parse_part(text: str, count: int) -> tuple[int, int]:
    """'2/4' -> (2, 4): the second of four parts of a draw of ``count`` shapes."""
    try:
        k, n = (int(number) for number in text.split("/"))
    except ValueError:  # not two numbers, or not two of them
        raise SweepError(f"--part takes K/N, the K-th of N parts, as 2/4 (got {text!r})") from None
    if not 1 <= k <= n:
        raise SweepError(f"--part {text}: K must be 1 to N")
    if n > count:
        raise SweepError(f"--part {text}: a draw of {count} shape(s) has at most {count} part(s)")
    return k, n


def part_bounds(k: int, n: int, count: int) -> tuple[int, int]:
    """The shapes of part k of n of a draw of ``count``, [first, end): consecutive, as even as count allows
    (100 in 4: 25 each; the families in turn, so each part holds each family about as often)."""
    return (k - 1) * count // n, k * count // n


def refusal(config: Config, vertices: np.ndarray) -> str:
    """Why the model refuses this goal under ``config``, in its own words ('' when it builds it): the same
    checks a world makes before it is built (:func:`sandbox.model.preview.preview_goal`)."""
    from sandbox.model.preview import preview_goal  # the outlines: only when a draw is planned

    try:
        preview_goal(config, vertices, config.flare)
    except ShapeError as exc:
        return str(exc)
    return ""


def generated_cases(wanted: Draw, base: dict, typed: dict) -> tuple[list[Case], dict]:
    """The cases of a draw (the shapes the model builds) and the record ``sweep.json`` keeps of it
    (:data:`META_KEY`): the draw asked for and every shape, refused ones with why."""
    cases, records = [], []
    for shape, case, why in planned(wanted, base, typed):
        records.append(shape_record(shape, why))
        if not why:
            cases.append(case)
    return cases, {"draws": [wanted.record()], "shapes": records}


def planned(wanted: Draw, base: dict, typed: dict) -> list[tuple[GeneratedShape, Case, str]]:
    """Every shape of the draw, its case (named after it) and why the model refuses it ('' when it builds it)."""
    try:
        shapes = wanted.shapes()
    except ShapeError as exc:
        raise SweepError(f"--generated: {exc}") from None
    out = []
    for shape in shapes:
        case = make_case(shape.name, {"shape": shape.name}, base, typed)
        out.append((shape, case, refusal(case.config, shape.vertices)))
    return out


def shape_record(shape: GeneratedShape, refused: str = "") -> dict:
    return {**shape.record(), "refused": refused}


def merged(old: dict, new: dict) -> dict:
    """A draw's record merged into the one a previous run into the same folder left: shapes by name."""
    if not old:
        return new
    draws = list(old.get("draws", []))
    draws += [d for d in new.get("draws", []) if d not in draws]
    shapes = {s["name"]: s for s in old.get("shapes", [])}
    shapes.update({s["name"]: s for s in new.get("shapes", [])})
    return {"draws": draws, "shapes": list(shapes.values())}
