"""Every advice candidate of each generated shape as a sweep's cases (``phototaxis sweep --generated N
--candidates``): the ground truth the advisor is checked against on a draw (``bench --advice --generated``),
and what a refused shape would build with any strategy (the refusal rule's check, in the report).

One case a shape and candidate (:func:`sandbox.experiments.advise.candidates`: the outline families that can
run the goal, with the strategies that mean something on each), named ``gen-star-0003 / offset + chase``
(:func:`case_label`, read back by :func:`split_label`). Its ``shape`` is the shape's name and its outline and
strategies the candidate's, so its rows of ``final.csv`` are read as that candidate of that shape by
:func:`sandbox.experiments.advice_check.measured`, like the committed evaluations' rows.

A shape the model refuses with the default settings still gets the candidates whose own settings build it
(a flare changes the outlines' sizes): if one builds it well, the refusal was wrong. The shape's record in
``sweep.json`` keeps the candidates run (``candidates``) and the one it gets without advice (``default``).
"""

from __future__ import annotations

from sandbox.experiments import draws
from sandbox.experiments.advise import Candidate, candidates, default_candidate
from sandbox.experiments.plan import Case, make_case
from sandbox.shapes import ShapeError
from sandbox.shapes.generator import GeneratedShape, parse_name

#: Between a shape's name and a candidate's label in a case's name.
SEPARATOR = " / "


def case_label(shape: str, candidate: Candidate) -> str:
    """'gen-star-0003' and offset + chase -> 'gen-star-0003 / offset + chase'."""
    return f"{shape}{SEPARATOR}{candidate.label}"


def split_label(label: str) -> tuple[str, str] | None:
    """(shape, candidate label) of a candidate case's name; None for any other case."""
    shape, sep, candidate = label.partition(SEPARATOR)
    return (shape, candidate) if sep and candidate and parse_name(shape) is not None else None


def candidate_case(shape: GeneratedShape, candidate: Candidate, base: dict, typed: dict) -> Case:
    """The case that runs ``candidate`` on ``shape``: its outline and every strategy's amount over the flags."""
    overrides = {"shape": shape.name, "outline": candidate.outline, **candidate.every_strategy}
    return make_case(case_label(shape.name, candidate), overrides, base, typed)


def shape_candidates(shape: GeneratedShape, case: Case, refused: str) -> tuple[list[Candidate], str]:
    """The candidates to run on a shape and the one it gets without advice ('' when none): all of them for a
    shape the model builds; for a refused one those whose own settings build it (none when even fitting the
    goal fails)."""
    try:
        every = candidates(case.config, shape.vertices)
        default = default_candidate(case.config, shape.vertices).label
    except ShapeError:
        return [], ""
    if refused:
        every = [c for c in every if not draws.refusal(c.config(case.config), shape.vertices)]
    return every, default


def candidate_cases(wanted: draws.Draw, base: dict, typed: dict) -> tuple[list[Case], dict]:
    """The cases of every shape's candidates and the draw's record for ``sweep.json`` (:data:`draws.META_KEY`):
    each shape's record as a plain draw keeps it, with its candidates' labels and its default's."""
    cases, records = [], []
    for shape, case, why in draws.planned(wanted, base, typed):
        chosen, default = shape_candidates(shape, case, why)
        cases += [candidate_case(shape, c, base, typed) for c in chosen]
        records.append({**draws.shape_record(shape, why), "candidates": [c.label for c in chosen],
                        "default": default})
    return cases, {"draws": [{**wanted.record(), "candidates": True}], "shapes": records}
