"""The committed evaluation of the paper's seven cases (static/paper, 10 seeds x 100,000 steps with
the default profile): that it was made with today's defaults, that its means are within tolerance of
the authors' program and meet the paper's findings, and that the program's numbers in
sandbox/experiments/reference.py are its measured ones. These read committed files: they check the
report's claims, not the model (tests/model/test_fidelity.py runs the model against the program)."""

from __future__ import annotations

import csv
import statistics
from pathlib import Path

import pytest

from sandbox.experiments import reference
from sandbox.model.config import case_config, coerce, param_names

ROOT = Path(__file__).resolve().parents[2]
OURS = ROOT / "static" / "paper" / "final.csv"
THEIRS = ROOT.parent / "shared" / "reference" / "push-cpp" / "final.csv"
THEIR_SERIES = THEIRS.with_name("series.csv")


def case_means(path: Path) -> dict[str, tuple[float, float]]:
    """case -> (mean final fraction in goal, mean final stray distance) over a final.csv's seeds."""
    rows: dict[str, list[tuple[float, float]]] = {}
    with path.open(newline="") as handle:
        for row in csv.DictReader(handle):
            rows.setdefault(row["case"], []).append((float(row["fraction_in_goal"]),
                                                     float(row["mean_outside_distance"])))
    return {case: (statistics.fmean(f for f, _ in values), statistics.fmean(d for _, d in values))
            for case, values in rows.items()}


def test_the_committed_evaluation_is_the_default_model_on_ten_seeds():
    with OURS.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert {r["profile"] for r in rows} == {"authors-code"} and {r["steps"] for r in rows} == {"100000"}
    assert {r["case"] for r in rows} == set(reference.PROGRAM)
    assert all(sum(r["case"] == case for r in rows) == 10 for case in reference.PROGRAM)


def test_the_committed_evaluation_was_made_with_todays_defaults():
    """Every parameter its rows record has the value the case has today; a parameter added since (no
    column) must keep the model it had, which the golden digests check."""
    with OURS.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    changed = set()
    for row in rows:
        today = case_config(row["case"]).replace(seed=int(row["seed"]), steps=int(row["steps"]))
        changed |= {(name, row[name], getattr(today, name)) for name in param_names()
                    if name in row and coerce(name, row[name]) != getattr(today, name)}
    assert not changed, f"static/paper/final.csv was run with other values (name, then, now): {sorted(changed)}"


@pytest.mark.parametrize("case", list(reference.PROGRAM))
def test_each_case_is_within_tolerance_of_the_authors_program(case):
    fraction, distance = case_means(OURS)[case]
    (program_fraction, _), (program_distance, _) = reference.PROGRAM[case]
    assert abs(fraction - program_fraction) <= reference.FRACTION_TOLERANCE, (fraction, program_fraction)
    assert abs(distance - program_distance) <= reference.DISTANCE_TOLERANCE, (distance, program_distance)


@pytest.mark.parametrize("finding", reference.FINDINGS, ids=lambda f: f.text)
def test_the_papers_findings_hold(finding):
    value = finding.measure(case_means(OURS))
    assert finding.holds(value), f"{finding.text}: {finding.shown.format(value)}"


@pytest.mark.skipif(not THEIRS.exists(), reason="needs ../shared/reference beside the checkout")
def test_the_programs_numbers_are_those_measured():
    """reference.PROGRAM holds the means of the program's own runs (../shared/reference/push-cpp)."""
    measured = case_means(THEIRS)
    for case, ((fraction, _), (distance, _)) in reference.PROGRAM.items():
        assert measured[case][0] == pytest.approx(fraction, abs=5e-4)
        assert measured[case][1] == pytest.approx(distance, abs=5e-4)


@pytest.mark.skipif(not THEIR_SERIES.exists(), reason="needs ../shared/reference beside the checkout")
def test_the_programs_first_contraction_is_that_measured():
    """reference.PROGRAM_CIRCLE_FIRST_CONTRACTION holds the means of the program's circle series."""
    fractions: dict[int, list[float]] = {}
    with THEIR_SERIES.open(newline="") as handle:
        for row in csv.DictReader(handle):
            if row["case"] == "circle":
                fractions.setdefault(int(row["step"]), []).append(float(row["fraction_in_goal"]))
    for step, fraction in reference.PROGRAM_CIRCLE_FIRST_CONTRACTION.items():
        assert len(fractions[step]) == 4 and statistics.fmean(fractions[step]) == pytest.approx(fraction, abs=5e-4)
