"""The advice checked on a draw of generated shapes (issue 57, items 3 and 4): every advice candidate of each
shape as a sweep's cases (``sweep --generated N --candidates``), named so that the advice's check reads them
back as that candidate of that shape; a refused shape's reason and the best any strategy reached in the
report; and ``bench --advice --generated N --truth DIR``'s share of first choices within a point of the best."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from sandbox import commands
from sandbox.experiments import advice_check, distribution, draw_candidates, draws
from sandbox.experiments.advise import Candidate, Ranked
from sandbox.experiments.storage import ResultStore, load_meta
from sandbox.experiments.sweep import sweep_plan, write_meta
from sandbox.experiments.trials import SweepError
from sandbox.model.config import STRATEGY_NAMES
from sandbox.shapes import generator
from tests.experiments.sweeping import parsed, replace_refusal


@pytest.fixture
def refusing(monkeypatch):
    """The model's refusal with the default settings, replaced: it refuses the shapes named in the returned set;
    a candidate's own settings are checked by the same function (a flare builds them, say)."""
    return replace_refusal(monkeypatch, applies=lambda config: config.flare == 0)


def final_row(case, fraction: float, seed: int = 0, steps: int = 100_000) -> dict:
    """A row of ``final.csv`` as the report writes it for a trial of ``case`` (its outline as it ran)."""
    config = case.config
    return {"case": case.label, "seed": str(seed), "final_step": str(steps), "fraction_in_goal": str(fraction),
            "outline_family": config.outline, "shape": config.shape, "notches": config.notches,
            **{name: str(getattr(config, name)) for name in STRATEGY_NAMES}}


def test_the_candidate_cases_are_named_after_shape_and_candidate_and_read_back_as_them(tmp_path, refusing):
    """gen-star-1000, a blob whose centre lies deep inside, runs all eight candidates (the scaled outline
    with none, flare, switch, no corners, switch + no corners, chase; the offset with none and chase); each
    case's rows of final.csv are read by the advice's check as that candidate of that shape."""
    args = parsed("--generated", "2", "--families", "star", "--generator-seed", "1", "--candidates",
                  "--trials", "1", "--steps", "300", "--chase", "2", "--out", str(tmp_path))
    cases, compare, generated = sweep_plan(args)
    star = [c for c in cases if c.config.shape == "gen-star-1000"]
    assert [c.label for c in star] == [
        "gen-star-1000 / scaled", "gen-star-1000 / scaled + flare", "gen-star-1000 / scaled + switch",
        "gen-star-1000 / scaled + no corners", "gen-star-1000 / scaled + switch + no corners",
        "gen-star-1000 / scaled + chase", "gen-star-1000 / offset", "gen-star-1000 / offset + chase"]
    flare = star[1].config
    assert (flare.outline, flare.flare, flare.chase, flare.steps) == ("scaled", 1.75, 0.0, 300)  # --chase 2 is off
    assert np.array_equal(np.asarray(star[0].shape), generator.generate("star", 1000).vertices)

    truth = advice_check.measured(final_row(c, 0.5 + i / 100) for i, c in enumerate(cases))
    assert sorted(truth) == sorted(draw_candidates.split_label(c.label) for c in cases)
    assert truth[("gen-star-1000", "offset + chase")] == [pytest.approx(0.57)]
    assert draw_candidates.split_label("gen-star-1000 / offset + chase") == ("gen-star-1000", "offset + chase")
    assert draw_candidates.split_label("shape=square / offset") is None and draw_candidates.split_label("x") is None

    write_meta(tmp_path, cases, compare, "phototaxis sweep ...", 1, 0, generated)
    meta = load_meta(tmp_path)[draws.META_KEY]
    assert meta["draws"] == [{"count": 2, "families": ["star"], "generator_seed": 1, "candidates": True}]
    record = meta["shapes"][0]
    assert record["default"] == "scaled" and len(record["candidates"]) == 8 and record["refused"] == ""


def test_a_refused_shape_runs_the_candidates_whose_own_settings_build_it(refusing):
    """Refused with the default settings (no flare), the shape still runs its flare candidate, which the model
    builds: what it reaches says whether the refusal was right."""
    refusing.add("gen-star-1000")
    cases, generated = draw_candidates.candidate_cases(draws.Draw(1, ("star",), 1), {}, {})
    assert [c.label for c in cases] == ["gen-star-1000 / scaled + flare"]
    record = generated["shapes"][0]
    assert record["refused"] == "gen-star-1000: too large, say" and record["candidates"] == ["scaled + flare"]


def test_candidates_go_with_a_draw(tmp_path):
    with pytest.raises(SweepError, match="--candidates runs the advice's candidates of a draw: it goes with"):
        sweep_plan(parsed("--cases", "paper", "--candidates", "--out", str(tmp_path)))


def trial(value: float, seed: int = 0) -> dict:
    return {"seed": seed, "outline": "offset", "samples": {"fraction_in_goal": np.array([0.1, value])}}


def test_a_refused_shapes_reason_and_the_best_any_strategy_reached_reach_the_report():
    """Three shapes of a candidates sweep: one built (its value its default's, offset: 0.70; its best offset +
    chase 0.80), one refused that no strategy can run, one refused whose flare candidate built it 0.76 and
    0.78 (0.77 >= 0.75: the refusal was wrong, and the report says so)."""
    records = [
        {"name": "gen-star-0000", "family": "star", "kind": "blob", "refused": "", "default": "offset",
         "candidates": ["offset", "offset + chase"]},
        {"name": "gen-star-0001", "family": "star", "kind": "points", "refused": "too large: use at most 46 boxes",
         "default": "", "candidates": []},
        {"name": "gen-curved-0000", "family": "curved", "kind": "ring", "refused": "its outline is past the arena",
         "default": "", "candidates": ["scaled + flare"]},
    ]
    by_case = {"gen-star-0000 / offset": [trial(0.7)], "gen-star-0000 / offset + chase": [trial(0.8)],
               "gen-curved-0000 / scaled + flare": [trial(0.76), trial(0.78, 1)]}
    results = distribution.shape_results({"shapes": records}, by_case)
    built, unbuildable, wrong = results
    assert (built.value, built.case, built.best) == (0.7, "gen-star-0000 / offset", ("offset + chase", 0.8))
    assert unbuildable.best is None and not unbuildable.values and wrong.best == ("scaled + flare", pytest.approx(0.77))

    text = "\n".join(distribution.section({"shapes": records, "draws": []}, results, None))
    assert ("- `gen-star-0001` (star, points): too large: use at most 46 boxes. No strategy's settings build it: "
            "none of the advice's candidates ran.") in text
    assert ("- `gen-curved-0000` (curved, ring): its outline is past the arena. The best any strategy reached: "
            "scaled + flare 0.770 (1 of 1 candidates run)") in text
    assert ("The refusal rule against the candidates: 2 of 3 shapes refused (66.7 %); refused although some "
            "strategy builds them 0.75 or more: `gen-curved-0000` (scaled + flare 0.770).") in text
    assert "| star | 2 | 1 | 1 | 0.700 |" in text  # the built star's value: its default candidate's


def test_a_plain_draw_says_nothing_of_candidates():
    records = [{"name": "gen-star-0000", "family": "star", "refused": "too large"}]
    text = "\n".join(distribution.section({"shapes": records, "draws": []},
                                          distribution.shape_results({"shapes": records}, {}), None))
    assert "- `gen-star-0000` (star): too large" in text and "candidates" not in text


def test_the_candidates_sweep_resumes(tmp_path, refusing, monkeypatch):
    """Trials of the candidates already stored are skipped by a second run of the same command: the cases
    and their configurations are the same on every plan."""
    from sandbox.experiments import executors
    from sandbox.experiments.plan import make_trials

    cases, _, _ = sweep_plan(parsed("--generated", "1", "--families", "rectilinear", "--generator-seed", "1",
                                    "--candidates", "--out", str(tmp_path)))
    again, _, _ = sweep_plan(parsed("--generated", "1", "--families", "rectilinear", "--generator-seed", "1",
                                    "--candidates", "--out", str(tmp_path)))
    trials, replanned = make_trials(cases, 2, 0), make_trials(again, 2, 0)
    assert [t.case for t in trials] == [t.case for t in replanned] and len(trials) == 4
    store = ResultStore(tmp_path)
    store.check_writable()
    for t in trials[:3]:  # three finished before the sweep was stopped: their files, the JSON last
        csv_path, json_path = store.paths(t.case, t.seed)
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        csv_path.write_text("case,seed,step\n")
        json_path.write_text(json.dumps({"config": t.config}))
    ran = []

    def fake_trial(config, seed, steps, shape, *rest):
        ran.append((config["outline"], config["chase"], seed))
        return {"seed": seed, "config": config, "samples": []}

    monkeypatch.setattr(executors, "run_sweep_trial", fake_trial)
    monkeypatch.setattr(store, "save", lambda case, result: None)

    class Inline:
        def submit(self, fn, *args):
            import concurrent.futures as cf

            future = cf.Future()
            future.set_result(fn(*args))
            return future

    import contextlib

    outcome = executors.run_trials(replanned, store, lambda: contextlib.nullcontext(Inline()), progress=False)
    assert (outcome.done, outcome.skipped) == (1, 3)
    assert ran == [("offset", 2.0, 1)]  # the last: offset + chase, seed 1


def verdict(status_first: float, best: float, name: str = "gen-star-0000") -> advice_check.Verdict:
    return advice_check.Verdict(name, "offset", status_first, status_first, "offset + chase", best)


def test_the_share_of_first_choices_within_a_point_on_a_draw():
    """Ten shapes advised: eight right (0.80 against 0.805 is within the point), one wrong (0.78 against 0.80),
    one never measured: 8 of 10, 80 %, below the 90 % wanted."""
    verdicts = [verdict(0.80, 0.805, f"gen-star-{i:04d}") for i in range(8)]
    verdicts += [verdict(0.78, 0.80, "gen-curved-0003"), verdict(math.nan, 0.80, "gen-convex-0002")]
    check = advice_check.DrawCheck(verdicts, ["gen-branching-0001"])
    assert check.share_right == pytest.approx(0.8) and not check.passes
    lines = check.summary()
    assert lines[0] == ("First choice within 1 point of the best at 100,000 steps: 8 of 10 shapes advised (80.0 %; "
                        "at least 90 % wanted): FAILS. Wrong: 1, not measured: 1, refused by the model (not advised): 1.")
    assert lines[1] == "Of the 9 shapes whose candidates were all measured: 8 right (88.9 %)."
    assert lines[2] == "wrong: gen-curved-0003: first offset 78.0 %, best offset + chase 80.0 %"
    assert lines[3].startswith("not measured: gen-convex-0002: first offset")
    assert advice_check.DrawCheck(verdicts[:8] + verdicts[:1], []).passes


def test_the_judge_reads_a_candidates_sweep_as_its_truth():
    """The advice's ranking of a generated shape judged against rows of a candidates sweep's final.csv."""
    ranking = [Ranked(Candidate("offset"), [0.8]), Ranked(Candidate("offset", (("chase", 2.0),)), [0.79])]
    truth = {("gen-star-0000", "offset"): [0.78, 0.80], ("gen-star-0000", "offset + chase"): [0.82, 0.82]}
    v = advice_check.judge("gen-star-0000", ranking, truth)
    assert (v.first, v.at_100k, v.best, v.status) == ("offset", pytest.approx(0.79), "offset + chase", "wrong")


def test_bench_advice_on_a_draw_needs_its_truth(tmp_path, capsys):
    assert commands.main(["bench", "--advice", "--generated", "2"]) == 2
    assert "needs --truth DIR" in capsys.readouterr().err
    assert commands.main(["bench", "--advice", "--generated", "2", "--truth", str(tmp_path)]) == 2
    assert f"no {tmp_path}/final.csv: run 'phototaxis report {tmp_path} --no-figures'" in capsys.readouterr().err


@pytest.mark.slow
def test_a_tiny_candidates_sweep_its_report_and_the_advice_judged_on_it(tmp_path, capsys):
    """Two rectilinear shapes of 60 boxes in a 4.5 m construction area, one seed, 1,000 steps: the comb
    (5.1 m long at that area) is refused by the model, in its words, and no candidate builds it; the letter
    runs its eight candidates, and the sweep resumes. Its report's final.csv is the truth ``bench --advice
    --generated`` judges the advice against."""
    out = tmp_path / "candidates"
    small = ["--robots", "30", "--boxes", "60", "--construction-size", "4.5", "--no-progress"]
    sweep = ["sweep", "--generated", "2", "--families", "rectilinear", "--candidates", "--trials", "1", "--steps",
             "1000", "--workers", "2", "--no-figures", "--out", str(out), *small]
    assert commands.main(sweep) == 0
    assert "8 trial(s) run, 0 already done" in capsys.readouterr().err
    assert commands.main(sweep) == 0
    assert "0 trial(s) run, 8 already done" in capsys.readouterr().err
    with (out / "generated.csv").open(newline="") as fh:
        rows = {row["shape"]: row for row in csv.DictReader(fh)}
    assert rows["gen-rectilinear-0000"]["candidates_run"] == "8" and not rows["gen-rectilinear-0000"]["refused"]
    report = (out / "report.md").read_text()
    assert ("- `gen-rectilinear-0001` (rectilinear, comb): at the boxes' total area (60 boxes, 10 m²) the goal is "
            "5.1 x 2.5 m, larger than the 4.5 m construction area") in report
    assert "No strategy's settings build it: none of the advice's candidates ran." in report
    assert "runs only the candidates whose own settings build it" in report

    bench = ["bench", "--advice", "--generated", "2", "--families", "rectilinear", "--truth", str(out),
             "--truth-steps", "1000", "--steps", "500", "--out", str(tmp_path / "advice"), *small]
    code = commands.main(bench)
    printed = capsys.readouterr().out
    assert "| gen-rectilinear-0000 |" in printed and "gen-rectilinear-0001 |" not in printed
    assert "of 1 shapes advised" in printed and "refused by the model (not advised): 1." in printed
    assert code == (0 if ": passes." in printed else 1)
    assert [f.name for f in (tmp_path / "advice").iterdir()] == ["gen-rectilinear-0000.json"]
    assert commands.main(bench) == code and capsys.readouterr().out == printed  # judged again from the kept advice


def test_a_truth_folder_not_yet_reported_is_named_with_the_report_to_run(tmp_path):
    missing = tmp_path / "candidates"
    with pytest.raises(ValueError, match=rf"no {missing}/final.csv: run 'phototaxis report {missing} --no-figures'"):
        advice_check.truth_files([str(missing)])
    (missing / "final.csv").parent.mkdir()
    (missing / "final.csv").write_text("case,seed\n")
    assert advice_check.truth_files([str(missing), str(missing / "final.csv")]) == [str(missing / "final.csv")] * 2


def test_a_shape_is_judged_only_when_the_truth_has_every_candidate_the_advice_ran():
    """A sweep still running has measured offset (0.80) but not offset + chase: the first choice, offset, is
    not known right, since the unmeasured chase may build more. The summary gives the share over the shapes
    judged beside the share over all."""
    ranking = [Ranked(Candidate("offset"), [0.8]), Ranked(Candidate("offset", (("chase", 2.0),)), [0.79])]
    partial = {("gen-star-0000", "offset"): [0.80, 0.80]}
    v = advice_check.judge("gen-star-0000", ranking, partial, every_one=True)
    assert (v.status, v.unmeasured) == ("not measured", ("offset + chase",))
    assert advice_check.judge("gen-star-0000", ranking, partial).status == "right"  # the shapes/ tables' reading
    right = [verdict(0.80, 0.805, f"gen-star-{i:04d}") for i in range(1, 4)]
    lines = advice_check.DrawCheck(right + [v], []).summary()
    assert lines[0].startswith("First choice within 1 point of the best at 100,000 steps: 3 of 4 shapes advised "
                               "(75.0 %; at least 90 % wanted): FAILS.")
    assert lines[1] == "Of the 3 shapes whose candidates were all measured: 3 right (100.0 %)."
    assert lines[2] == ("not measured: gen-star-0000: first offset (no trial at 100,000 steps in the truth of "
                        "offset + chase)")


def timed(shape: str = "gen-star-0000") -> advice_check.Timed:
    ranking = [Ranked(Candidate("offset", (("chase", 2.0),)), [0.81, 0.83], [0.3, 0.4], 12.5),
               Ranked(Candidate("scaled"), [0.74, 0.76], [0.5, 0.7], 4.0)]
    return advice_check.Timed(shape, ranking, "Use offset + chase: 82 % (scaled 75 %)", 30.0, 16.5,
                              [(10.0, 21.0, 20.0), (20.0, None, 10.0)])


def test_a_kept_advice_reads_back_as_it_ran_and_only_with_the_same_settings(tmp_path):
    from sandbox.model.config import Config

    config = Config()
    advice_check.save_timed(tmp_path, timed(), config, 10_000)
    back = advice_check.load_timed(tmp_path, "gen-star-0000", config, 10_000)
    assert back == timed() and back.ranking[0].fraction == pytest.approx(0.82)
    assert advice_check.load_timed(tmp_path, "gen-star-0001", config, 10_000) is None  # never kept
    with pytest.raises(ValueError, match="gen-star-0000.json holds the advice on gen-star-0000 run with other "
                                         "settings; use another --out or delete it"):
        advice_check.load_timed(tmp_path, "gen-star-0000", config, 6_000)
    with pytest.raises(ValueError, match="other settings"):
        advice_check.load_timed(tmp_path, "gen-star-0000", config.replace(robots=100), 10_000)
    (tmp_path / "gen-star-0000.json").write_text('{"settings": {"con')  # torn: run it again
    assert advice_check.load_timed(tmp_path, "gen-star-0000", config, 10_000) is None
    empty = json.loads(json.dumps({"settings": advice_check._settings("gen-star-0000", config, 10_000)}))
    for broken in ({**empty, "ranking": []}, {**empty, "ranking": 5}, {**empty, "ranking": [{"outline": 1}]}):
        (tmp_path / "gen-star-0000.json").write_text(json.dumps({**broken, "verdict": "", "seconds": 1,
                                                                 "cpu_seconds": 1, "estimates": []}))
        assert advice_check.load_timed(tmp_path, "gen-star-0000", config, 10_000) is None


def test_the_advice_on_a_draw_resumes_from_its_folder(tmp_path, monkeypatch, refusing):
    """Three shapes, one refused: the advice runs on two and keeps them; a second call runs none, a third with
    one file gone runs that one again."""
    from sandbox.model.config import Config

    ran = []
    monkeypatch.setattr(advice_check, "timed_advice",
                        lambda shape, config, workers, steps: ran.append(shape) or timed(shape))
    shapes = generator.draw(3, ("star",), 0)
    refusing.add(shapes[1].name)
    call = lambda: advice_check.advise_draw(Config(), shapes, workers=1, steps=1_000, store=tmp_path)  # noqa: E731
    runs, refused = call()
    assert ran == [shapes[0].name, shapes[2].name] and refused == [shapes[1].name]
    assert [r.shape for r in call()[0]] == ran and len(ran) == 2
    (tmp_path / f"{shapes[2].name}.json").unlink()
    call()
    assert ran[2:] == [shapes[2].name]


def test_out_goes_with_the_advice_on_a_draw(capsys):
    assert commands.main(["bench", "--out", "/tmp/x"]) == 2
    assert "--out keeps the advice on a draw" in capsys.readouterr().err


def test_the_advice_on_a_part_of_a_draw_runs_only_its_shapes(tmp_path, monkeypatch, capsys):
    ran = []
    monkeypatch.setattr(advice_check, "timed_advice",
                        lambda shape, config, workers, steps: ran.append(shape) or timed(shape))
    truth = tmp_path / "final.csv"
    truth.write_text("case,seed\n")
    bench = ["bench", "--advice", "--generated", "4", "--families", "convex", "--truth", str(truth)]
    commands.main([*bench, "--part", "2/2", "--no-progress"])
    assert [generator.shape_name("convex", s) for s in (2, 3)] == ran
    assert "of 2 shapes advised" in capsys.readouterr().out
    assert commands.main([*bench, "--part", "3/2"]) == 2
    assert "--part 3/2: K must be 1 to N" in capsys.readouterr().err
    assert commands.main(["bench", "--part", "1/2"]) == 2
    assert "--part splits a draw: bench --advice --generated N --part K/N" in capsys.readouterr().err


def test_an_out_that_cannot_be_a_folder_is_refused_before_any_advice_runs(tmp_path, monkeypatch, capsys):
    ran = []
    monkeypatch.setattr(advice_check, "timed_advice", lambda *a, **k: ran.append(a))
    truth = tmp_path / "final.csv"
    truth.write_text("case,seed\n")
    a_file = tmp_path / "a-file"
    a_file.write_text("")
    assert commands.main(["bench", "--advice", "--generated", "1", "--truth", str(truth), "--out",
                          str(a_file / "advice")]) == 2
    assert f"cannot keep the advice in {a_file / 'advice'}: Not a directory" in capsys.readouterr().err and not ran
