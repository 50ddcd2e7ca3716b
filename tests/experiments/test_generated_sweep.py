"""A sweep over generated shapes (``phototaxis sweep --generated N``) and its report's distribution: the
plan names a case after each shape and keeps its family and parameters, refused shapes are counted and not
run, and the distribution's numbers by hand."""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from sandbox import commands
from sandbox.experiments import distribution, draws
from sandbox.experiments.plan import grid_cases
from sandbox.experiments.storage import load_meta
from sandbox.experiments.sweep import sweep_plan, write_meta
from sandbox.experiments.trials import SweepError
from sandbox.model.config import Config
from sandbox.shapes import generator
from tests.experiments.sweeping import parsed, replace_refusal


@pytest.fixture
def refusing(monkeypatch):
    """The model's refusal, replaced: it refuses the shapes named in the returned set."""
    return replace_refusal(monkeypatch)


def test_the_plan_names_a_case_after_each_shape_and_keeps_its_family_and_parameters(tmp_path, refusing):
    refusing.add("gen-curved-1000")
    args = parsed("--generated", "5", "--families", "convex,curved", "--generator-seed", "1", "--trials", "1",
                  "--steps", "300", "--out", str(tmp_path))
    cases, compare, generated = sweep_plan(args)
    assert [c.label for c in cases] == ["gen-convex-1000", "gen-convex-1001", "gen-curved-1001", "gen-convex-1002"]
    assert compare == [] and all(c.config.steps == 300 and c.config.shape == c.label for c in cases)
    write_meta(tmp_path, cases, compare, "phototaxis sweep ...", 1, 0, generated)

    meta = load_meta(tmp_path)[draws.META_KEY]
    assert meta["draws"] == [{"count": 5, "families": ["convex", "curved"], "generator_seed": 1}]
    records = {r["name"]: r for r in meta["shapes"]}
    assert list(records) == ["gen-convex-1000", "gen-curved-1000", "gen-convex-1001", "gen-curved-1001",
                             "gen-convex-1002"]
    assert records["gen-curved-1000"]["refused"] == "gen-curved-1000: too large, say"
    for case in cases:  # what sweep.json keeps makes the case's goal again, without the generator's random numbers
        record = records[case.label]
        assert (record["family"], record["seed"]) == generator.parse_name(case.label) and record["refused"] == ""
        assert np.array_equal(generator.from_params(record["family"], record["params"]), np.asarray(case.shape))


def test_a_second_run_into_the_folder_merges_the_draws(tmp_path, refusing):
    for seed in (0, 1):
        args = parsed("--generated", "2", "--families", "star", "--generator-seed", str(seed), "--out", str(tmp_path))
        cases, compare, generated = sweep_plan(args)
        write_meta(tmp_path, cases, compare, "phototaxis sweep ...", 1, 0, generated)
    meta = load_meta(tmp_path)[draws.META_KEY]
    assert [d["generator_seed"] for d in meta["draws"]] == [0, 1]
    assert [r["name"] for r in meta["shapes"]] == ["gen-star-0000", "gen-star-0001", "gen-star-1000", "gen-star-1001"]


def test_the_models_refusal_in_its_own_words():
    """A comb 14.7 m long, a quarter of which would lie outside a 12 m construction area, is refused as
    ``run`` would refuse it (before any outline is built)."""
    comb = generator.generate("rectilinear", 1)
    assert comb.kind == "comb" and np.ptp(comb.vertices, axis=0)[0] == pytest.approx(14.7, abs=0.05)
    why = draws.refusal(Config(construction_size=12.0), comb.vertices)
    assert "the goal is 14.7 x 7.3 m, larger than the 12 m construction area the boxes cannot leave" in why


@pytest.mark.parametrize("argv, message", [
    (["--generated", "0"], "--generated must be at least 1 (got 0)"),
    (["--generated", "3", "--families", "blob"], "--families: unknown shape family 'blob'"),
    (["--generated", "3", "--generator-seed", "-1"], "the generator seed must be 0 or more"),
])
def test_bad_draws_are_one_line(argv, message, tmp_path):
    with pytest.raises(SweepError, match=re.escape(message)):
        sweep_plan(parsed(*argv, "--out", str(tmp_path)))


def test_the_parts_of_a_draw_are_its_shapes_in_turn_each_once():
    """100 shapes in 4 parts: 25 each, consecutive, 5 of each family; 10 in 3: 3, 3 and 4. A part's shapes
    are the whole draw's there, so the parts' trials are the whole draw's."""
    assert [draws.part_bounds(k, 4, 100) for k in (1, 2, 3, 4)] == [(0, 25), (25, 50), (50, 75), (75, 100)]
    assert [draws.part_bounds(k, 3, 10) for k in (1, 2, 3)] == [(0, 3), (3, 6), (6, 10)]
    whole = draws.Draw.from_flags(10, "all", 2).shapes()
    parts = [draws.Draw.from_flags(10, "all", 2, f"{k}/3").shapes() for k in (1, 2, 3)]
    assert [s.name for part in parts for s in part] == [s.name for s in whole]
    fourth, fifth, first = generator.FAMILIES[3], generator.FAMILIES[4], generator.FAMILIES[0]
    assert [s.name for s in parts[1]] == [f"gen-{fourth}-2000", f"gen-{fifth}-2000", f"gen-{first}-2001"]
    assert all(np.array_equal(a.vertices, b.vertices) for a, b in zip(parts[2], whole[6:]))
    first_of_four = draws.Draw.from_flags(100, "all", 2, "1/4").shapes()
    assert len(first_of_four) == 25 and {s.family for s in first_of_four} == set(generator.FAMILIES)
    assert all(sum(s.family == f for s in first_of_four) == 5 for f in generator.FAMILIES)


def test_a_part_is_kept_with_its_draw_and_said_in_the_command(tmp_path, refusing):
    args = parsed("--generated", "4", "--families", "star", "--part", "2/2", "--candidates", "--out", str(tmp_path))
    cases, compare, generated = sweep_plan(args)
    assert {c.label.split(" / ")[0] for c in cases} == {"gen-star-0002", "gen-star-0003"}
    assert generated["draws"] == [{"count": 4, "families": ["star"], "generator_seed": 0, "part": [2, 2],
                                   "candidates": True}]
    from sandbox.experiments.sweep import _command_line

    assert "--generated 4 --families star --generator-seed 0 --part 2/2 --candidates" in _command_line(args)
    assert "part 2 of 2" in "\n".join(distribution.section(generated, [], None))


@pytest.mark.parametrize("argv, message", [
    (["--generated", "3", "--part", "2"], "--part takes K/N, the K-th of N parts, as 2/4 (got '2')"),
    (["--generated", "3", "--part", "a/b"], "--part takes K/N"),
    (["--generated", "3", "--part", "0/2"], "--part 0/2: K must be 1 to N"),
    (["--generated", "3", "--part", "3/2"], "--part 3/2: K must be 1 to N"),
    (["--generated", "3", "--part", "1/4"], "--part 1/4: a draw of 3 shape(s) has at most 3 part(s)"),
    (["--cases", "paper", "--part", "1/2"], "--part splits a draw of generated shapes: it goes with --generated N"),
])
def test_bad_parts_are_one_line(argv, message, tmp_path):
    with pytest.raises(SweepError, match=re.escape(message)):
        sweep_plan(parsed(*argv, "--out", str(tmp_path)))


def test_generated_is_one_of_cases_grid_and_generated(capsys):
    with pytest.raises(SystemExit):
        parsed("--generated", "3", "--cases", "paper", "--out", "x")
    assert "not allowed with argument" in capsys.readouterr().err


def trial(value: float, seed: int = 0) -> dict:
    return {"seed": seed, "outline": "offset", "samples": {"fraction_in_goal": np.array([0.1, value])}}


def test_the_distribution_by_hand():
    """Three convex shapes (0.8; 0.6 and 0.7 over two seeds: 0.65; 0.9), a curved one refused, a curved one
    at 0.5. By hand: the convex median 0.8, 10th percentile 0.65 + 0.2 x 0.15 = 0.68, mean 0.7833 ± 0.0726;
    over the four run, 10th percentile 0.5 + 0.3 x 0.15 = 0.545, median 0.725."""
    names = ["gen-convex-0000", "gen-curved-0000", "gen-convex-0001", "gen-curved-0001", "gen-convex-0002"]
    records = [{"name": n, "family": n.split("-")[1], "seed": int(n[-4:]), "kind": "", "params": {},
                "refused": "too large" if n == "gen-curved-0000" else ""} for n in names]
    by_case = {"gen-convex-0000": [trial(0.8)], "gen-convex-0001": [trial(0.6), trial(0.7, 1)],
               "gen-curved-0001": [trial(0.5)], "gen-convex-0002": [trial(0.9)]}
    results = distribution.shape_results({"shapes": records}, by_case)
    rows = {r.family: r for r in distribution.family_rows(results)}
    convex, curved, every = rows["convex"], rows["curved"], rows["all"]
    assert (convex.shapes, convex.refused, convex.built) == (3, 0, 3)
    assert convex.median == pytest.approx(0.8) and convex.p10 == pytest.approx(0.68)
    assert convex.mean == pytest.approx(0.78333, abs=1e-5)
    assert convex.sem == pytest.approx(np.std([0.8, 0.65, 0.9], ddof=1) / math.sqrt(3))
    assert (curved.shapes, curved.refused, curved.built, curved.median) == (2, 1, 1, 0.5)
    assert math.isnan(curved.sem)
    assert (every.shapes, every.refused, every.built) == (5, 1, 4)
    spread = distribution.percentiles(results)
    assert spread["p10"] == pytest.approx(0.545) and spread["p50"] == pytest.approx(0.725)
    assert (spread["min"], spread["max"]) == (0.5, 0.9)
    assert [r.name for r in distribution.worst(results, 2)] == ["gen-curved-0001", "gen-convex-0001"]
    text = "\n".join(distribution.section({"shapes": records, "draws": []}, results, None))
    assert "| convex | 3 | 0 | 3 | 0.800 | 0.680 | 0.783 ± 0.073 |" in text
    assert "- `gen-curved-0000` (curved): too large" in text


@pytest.mark.slow
def test_a_tiny_generated_sweep_and_its_report(tmp_path):
    """Three shapes, one seed, 300 steps: the trials run in worker processes like any sweep's, and the report
    holds the distribution, the shapes' file and the worst shapes' picture."""
    out = tmp_path / "generated"
    assert commands.main(["sweep", "--generated", "3", "--trials", "1", "--steps", "300", "--robots", "30",
                          "--boxes", "60", "--workers", "2", "--no-progress", "--out", str(out)]) == 0
    report = (out / "report.md").read_text()
    assert "## The distribution over generated shapes" in report
    assert "phototaxis sweep --generated 3 --families all --generator-seed 0 --trials 1" in report
    assert "![worst shapes](figures/worst_layouts.png)" in report and (out / "figures/worst_layouts.png").is_file()
    with (out / "generated.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["shape"] for r in rows] == ["gen-convex-0000", "gen-star-0000", "gen-rectilinear-0000"]
    for row in rows:
        params = json.loads(row["params"])
        assert np.array_equal(generator.from_params(row["family"], params),
                              generator.generate(row["family"], int(row["shape_seed"])).vertices)
        finals = json.loads(next(Path(out / "trials" / row["shape"]).glob("seed-0.json")).read_text())
        assert float(row["mean_fraction_in_goal"]) == pytest.approx(sum(finals["final"]["box_in_goal"]) / 60,
                                                                    abs=1e-4)


def test_a_grid_file_names_generated_shapes(tmp_path):
    """A generated shape's name is a shape like any other: in a grid file, ``run --shape`` or the config."""
    grid = tmp_path / "grid.toml"
    grid.write_text('[grid]\nshape = ["gen-star-0003", "square"]\n')
    cases, _ = grid_cases(str(grid), {}, {})
    assert [c.label for c in cases] == ["shape=gen-star-0003", "shape=square"]
    assert np.array_equal(np.asarray(cases[0].shape), generator.generate("star", 3).vertices)
