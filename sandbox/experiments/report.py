"""Turn a sweep's stored trials into tables, figures and ``report.md``.

Everything here reads only the files under the sweep's folder, so
``phototaxis report DIR`` rebuilds the same report at any time, also from
a sweep that is still running or was interrupted.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import datetime as _dt
from pathlib import Path
from typing import Any

from sandbox.cli import UserError
from sandbox.experiments import distribution, reference, stats, versus
from sandbox.experiments.storage import ResultStore, load_meta
from sandbox.experiments.trials import METRICS, SweepError
from sandbox.model.config import Config, params
from sandbox.model.metrics import SAMPLE_FIELDS, SampleWriter, plain

FIGURES_DIR = "figures"


def group(results: list[dict], meta: dict) -> dict[str, list[dict]]:
    """Trials by case, in the sweep's case order, each list by seed."""
    order = [c["label"] for c in meta.get("cases", [])]
    by_case: dict[str, list[dict]] = {c: [] for c in order}
    for r in results:
        by_case.setdefault(r["case"], []).append(r)
    return {c: sorted(ts, key=lambda t: t["seed"]) for c, ts in by_case.items() if ts}


def build_report(out: str | Path, dest: str | Path | None = None, against: str | Path | None = None,
                 against_label: str = "the other set", figures: bool = True) -> Path:
    """Write tables, figures (unless ``figures`` is False: they take most of a report's time) and
    report.md for the sweep in ``out`` into ``dest`` (default ``out``), with the same cases of the
    report folder ``against`` beside them if given."""
    out = Path(out)
    dest = Path(dest) if dest is not None else out
    store = ResultStore(out)
    if not store.trials_dir.is_dir():
        raise SweepError(f"{out} holds no sweep results (no {store.trials_dir.name}/ folder); "
                         f"run 'phototaxis sweep --out {out}' first")
    meta = load_meta(out)
    by_case = group(store.load(), meta)
    if not by_case:
        raise SweepError(f"{out} holds no finished trials yet")
    try:
        (dest / FIGURES_DIR if figures else dest).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SweepError(f"cannot write the report to {dest}: {exc.strerror or exc}") from None

    generated = meta.get("generated")
    shapes = distribution.shape_results(generated, by_case) if generated else None
    pairs = stats.default_pairs(list(by_case), [tuple(p) for p in meta.get("compare", [])])
    tables = {m: stats.summaries(by_case, m) for m in METRICS}
    first = {m: stats.summaries(by_case, m, when="first-cycle") for m in METRICS}
    last = stats.summaries(by_case, "fraction_in_goal", when="last-cycle")
    tests = {m: stats.ks_tests(by_case, pairs, m) for m in METRICS}

    _write_results_csv(by_case, dest / "results.csv")
    _write_final_csv(by_case, dest / "final.csv")
    _write_rows(dest / "summary.csv", [dataclasses.asdict(r) for m in METRICS for r in tables[m]])
    _write_rows(dest / "ks_tests.csv", [dataclasses.asdict(r) for m in METRICS for r in tests[m]])
    figs = _draw_figures(by_case, dest / FIGURES_DIR, shapes) if figures else {}

    text = _markdown(meta, by_case, tables, first, last, tests, figs, dest, store.load_failures())
    if shapes is not None:
        distribution.write_csv(shapes, dest / "generated.csv")
        worst = figs.get("worst")
        lines = distribution.section(generated, shapes, worst and Path(worst).relative_to(dest).as_posix())
        head, sep, tail = text.partition("\n## Table II.")
        text = head + "\n".join(lines) + "\n" + sep + tail
    if against is not None:
        lines, rows = versus.versus_section(by_case, against, against_label)
        _write_rows(dest / "versus.csv", rows)
        head, sep, tail = text.partition("\n## Table II.")
        text = head + "\n".join(lines) + "\n" + sep + tail
    report = dest / "report.md"
    report.write_text(text, encoding="utf-8")
    return report


def _draw_figures(by_case: dict[str, list[dict]], folder: Path,
                  shapes: list[distribution.ShapeResult] | None = None) -> dict[str, Path]:
    """The metrics over time (a line per case) and every case's final layout; for a draw of generated
    shapes, a line per family and the layouts of the worst shapes only (a hundred would not be read)."""
    from sandbox.experiments import figures  # matplotlib: only when a report is drawn, not on every command

    if shapes is not None:
        families = distribution.by_family(shapes, by_case)
        figs = {m: figures.plot_metric(families, m, folder / m) for m in METRICS}
        figs["worst"] = distribution.draw_worst(shapes, by_case, folder / "worst_layouts")
        return figs
    figs = {m: figures.plot_metric(by_case, m, folder / m) for m in METRICS}
    figs["layouts"] = figures.plot_layouts(by_case, folder / "final_layouts")
    return figs


# ---------------------------------------------------------------- files


def _write_rows(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as fh:
        if not rows:
            return
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _write_results_csv(by_case: dict[str, list[dict]], path: Path) -> None:
    with path.open("w", newline="") as fh:
        writer = SampleWriter(fh, leading=("case", "seed"))
        for case, trials in by_case.items():
            for t in trials:
                s = t["samples"]
                for i in range(len(s["step"])):
                    writer.write({c: s[c][i] for c in SAMPLE_FIELDS}, case=case, seed=t["seed"])


def _write_final_csv(by_case: dict[str, list[dict]], path: Path) -> None:
    names = [p.name for p in params()]
    with path.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["case", "seed", "final_step", *METRICS, "boxes_escaped", "seconds", "cpu_seconds", "host",
                         "controller", "senses", "light_energy", "outline_family", "outline_reason", *names])
        for case, trials in by_case.items():
            for t in trials:
                s = t["samples"]
                writer.writerow([case, t["seed"], int(s["step"][-1]), *(plain(s[m][-1]) for m in METRICS),
                                 int(s["boxes_escaped"][-1]), t.get("seconds", ""), t.get("cpu_seconds", ""),
                                 t.get("host", ""), t.get("controller", ""), "+".join(t.get("senses", ())),
                                 t.get("light_energy", ""), t.get("outline", ""), t.get("outline_reason", ""),
                                 *(t["config"].get(n, "") for n in names)])


# ------------------------------------------------------------- markdown


def _md_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _summary_table(rows: list[stats.Summary], digits: int) -> str:
    return _md_table(["case", "trials", "mean", "median", "std. dev.", "std. error", "min", "max"],
                     [[f"`{r.case}`", str(r.n), *(stats.fmt(v, digits) for v in
                                                  (r.mean, r.median, r.std, r.sem, r.low, r.high))] for r in rows])


def _ks_table(rows: list[stats.KSTest], digits: int) -> str:
    if not rows:
        return "_No case pairs to compare._"
    return _md_table(["case A", "case B", "n A", "n B", "mean A", "mean B", "KS statistic D", "p-value"],
                     [[f"`{r.a}`", f"`{r.b}`", str(r.n_a), str(r.n_b), stats.fmt(r.mean_a, digits),
                       stats.fmt(r.mean_b, digits), stats.fmt(r.statistic, 3), stats.fmt_p(r.pvalue)] for r in rows])


def _overrides_text(overrides: dict) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in overrides.items()) or "(base values)"


def _against_reference_section(by_case: dict[str, list[dict]], tables: dict) -> list[str]:
    """The paper's cases side by side with the paper's tables and the authors' program."""
    cases = [c for c in by_case if c in reference.PAPER]
    if not cases:
        return []
    ours = {m: {r.case: r for r in tables[m]} for m in METRICS}
    out = ["", "## Against the paper and the authors' program", "",
           f"The paper's Tables II and III; the authors' released program, measured by this project "
           f"(seeds {reference.PROGRAM_SEEDS}, mean ± standard error); and this sweep (mean ± standard error). "
           f"*Within* says whether this sweep's mean is within {reference.FRACTION_TOLERANCE * 100:g} points "
           f"(fraction) or {reference.DISTANCE_TOLERANCE:g} m (distance) of the program's.", ""]
    for i, (metric, title, tolerance, digits) in enumerate((
            ("fraction_in_goal", "Fraction of boxes in the goal", reference.FRACTION_TOLERANCE, 3),
            ("mean_outside_distance", "Mean distance of the boxes outside the goal (m)",
             reference.DISTANCE_TOLERANCE, 2))):
        rows = []
        for c in cases:
            mine, (prog, prog_se) = ours[metric][c], reference.PROGRAM[c][i]
            rows.append([f"`{c}`", stats.fmt(reference.PAPER[c][i], digits),
                         f"{stats.fmt(prog, digits)} ± {stats.fmt(prog_se, digits)}",
                         f"{stats.fmt(mine.mean, digits)} ± {stats.fmt(mine.sem, digits)}",
                         f"{mine.mean - prog:+.{digits}f}", "yes" if abs(mine.mean - prog) <= tolerance else "**no**"])
        out += [f"**{title}**", "", _md_table(["case", "paper", "program", "here", "here − program", "within"], rows),
                ""]
    means = {c: (ours["fraction_in_goal"][c].mean, ours["mean_outside_distance"][c].mean) for c in cases}
    program = {c: (reference.PROGRAM[c][0][0], reference.PROGRAM[c][1][0]) for c in reference.PROGRAM}
    paper = dict(reference.PAPER)
    rows = []
    for f in reference.FINDINGS:
        if not all(c in means for c in f.needs):
            continue
        value = f.measure(means)
        rows.append([f.text, f.shown.format(f.measure(paper)), f.shown.format(f.measure(program)),
                     f.shown.format(value), "yes" if f.holds(value) else "**no**"])
    if rows:
        out += ["**The paper's findings**", "", _md_table(["finding", "paper", "program", "here", "holds"], rows), ""]
    dips = [[f"`{c}`", f"{_largest_dip(by_case[c]):.3f}", f"{reference.PROGRAM_DIPS[c]:.3f}",
             "yes" if _largest_dip(by_case[c]) <= reference.DIP_TOLERANCE else "**no**"] for c in cases]
    out += ["**Dips.** The largest drop of the case's mean fraction-in-goal series (Figure 4) below its best "
            f"value so far, here and in the program; a faithful model has none above "
            f"{reference.DIP_TOLERANCE * 100:g} points.", "",
            _md_table(["case", "largest dip here", "program", f"at most {reference.DIP_TOLERANCE:g}"], dips)]
    return out


def _largest_dip(trials: list[dict]) -> float:
    """Largest drop of the mean fraction-in-goal series (over trials, sample by sample) below its running best."""
    n = min(len(t["samples"]["fraction_in_goal"]) for t in trials)
    mean = [sum(float(t["samples"]["fraction_in_goal"][i]) for t in trials) / len(trials) for i in range(n)]
    best, dip = float("-inf"), 0.0
    for value in mean:
        best = max(best, value)
        dip = max(dip, best - value)
    return dip


def _first_cycle_section(first: dict) -> list[str]:
    if not any(r.n for r in first["fraction_in_goal"]):
        return ["", "_No trial ran long enough to finish a compression cycle, so there is no after-one-cycle table._"]
    return ["", "### After the first compression cycle", "",
            "Both metrics at the first sample taken after each trial completed its first full "
            "contract–hold–dilate cycle (trials too short for a cycle are left out).", "",
            _md_table(["case", "trials", "fraction in goal (mean ± s.d.)", "distance outside, m (mean ± s.d.)"],
                      [[f"`{a.case}`", str(a.n), f"{stats.fmt(a.mean)} ± {stats.fmt(a.std)}",
                        f"{stats.fmt(b.mean)} ± {stats.fmt(b.std)}"]
                       for a, b in zip(first["fraction_in_goal"], first["mean_outside_distance"])])]


def _last_cycle_section(final: list, last: list) -> list[str]:
    """The fraction at the final step beside its mean over each trial's last whole cycle."""
    if not any(r.n for r in last):
        return []
    rows = [[f"`{f.case}`", f"{stats.fmt(f.mean)} ± {stats.fmt(f.sem)}",
             f"{stats.fmt(c.mean)} ± {stats.fmt(c.sem)}" if c.n else "no whole cycle", str(c.n)]
            for f, c in zip(final, last)]
    return ["", "### Over the last whole cycle", "",
            "The fraction in the goal at the final step beside its mean over the samples of each trial's last "
            "whole contract–hold–dilate cycle (mean ± standard error over trials). An open loop runs the same "
            "schedule in every seed, so its final step falls at the same phase of a cycle in every trial: where "
            "the fraction swings within a cycle, the cycle's mean is the fairer figure.", "",
            _md_table(["case", "final step", "last whole cycle", "trials with one"], rows)]


def _escape_lines(by_case: dict[str, list[dict]]) -> list[str]:
    """Every sample that found a box centre beyond the construction wall's inner face (should be none)."""
    hits = []
    for case, trials in by_case.items():
        for t in trials:
            s = t["samples"]
            for step, n in zip(s["step"], s["boxes_escaped"]):
                if n > 0:
                    hits.append(f"`{case}` seed {t['seed']} step {int(step)}: {int(n)}")
    samples = sum(len(t["samples"]["step"]) for ts in by_case.values() for t in ts)
    if not hits:
        return [f"- boxes outside the construction wall: none in any of the {samples} samples"]
    return [f"- **boxes outside the construction wall** in {len(hits)} of {samples} samples "
            f"(a box centre past the wall's inner face): {'; '.join(hits[:10])}"
            + (" ..." if len(hits) > 10 else "")]


def _markdown(meta, by_case, tables, first, last, tests, figs, dest: Path, failures: list[dict]) -> str:
    trials = [t for ts in by_case.values() for t in ts]
    steps = sorted({int(t["steps"]) for t in trials})
    seeds = sorted({int(t["seed"]) for t in trials})
    wall = sum(float(t.get("seconds", 0)) for t in trials)
    cpu = sum(float(t.get("cpu_seconds", t.get("seconds", 0))) for t in trials)
    hosts = sorted({t.get("host", "?") for t in trials})
    defaults = Config().to_dict()
    first_cfg = trials[0]["config"]
    varying = {k for t in trials for k, v in t["config"].items() if v != first_cfg.get(k)} | {"seed"}
    base_changes = {k: v for k, v in first_cfg.items() if v != defaults.get(k) and k not in varying and k != "steps"}
    rel = lambda p: Path(p).relative_to(dest).as_posix()  # noqa: E731

    out = ["# Sweep report", ""]
    out.append(f"Generated {_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC by `phototaxis report` "
               f"from the trial files of the sweep.")
    if meta.get("command"):
        out += ["", "Command:", "", "```", meta["command"], "```"]
    out += ["", f"- **{len(trials)} trials** in {len(by_case)} cases "
                f"({', '.join(f'{c}: {len(ts)}' for c, ts in by_case.items())})",
            f"- steps per trial: {', '.join(map(str, steps))}; seeds {seeds[0]}–{seeds[-1]} "
            f"(each case uses the same seeds)",
            f"- compute: {cpu / 3600:.2f} CPU-hours, {cpu / len(trials):.0f} CPU-s per trial "
            f"({wall / len(trials):.0f} s wall-clock) on average, on {len(hosts)} host(s)",
            f"- base parameters changed from the defaults: {_overrides_text(base_changes)}",
            *_escape_lines(by_case)]
    if meta.get("cases"):
        out += ["", "Cases:", ""]
        out += [f"- `{c['label']}`: {_overrides_text(c.get('overrides', {}))}" for c in meta["cases"]
                if c["label"] in by_case]
    if failures:
        out += ["", f"**{len(failures)} trial(s) failed twice and are missing from the statistics:**", ""]
        out += [f"- `{f['case']}` seed {f['seed']}: {f['error']}" for f in failures]

    out += ["", "## Table II. Fraction of boxes in the goal at the final step", "",
            "Higher is better; 1.0 is a perfect tiling. Standard deviation with ddof = 1; standard error = s.d. / √n.",
            "", _summary_table(tables["fraction_in_goal"], 3),
            "", "## Table III. Mean distance of boxes outside the goal at the final step (m)", "",
            "Lower is better; 0 when every box is inside.", "",
            _summary_table(tables["mean_outside_distance"], 3),
            *_against_reference_section(by_case, tables),
            *_first_cycle_section(first),
            *_last_cycle_section(tables["fraction_in_goal"], last),
            "", "## Table IV. Two-sample Kolmogorov–Smirnov tests: fraction in goal at the final step", "",
            "`scipy.stats.ks_2samp`, two-sided. A small p-value says the two cases' distributions differ.", "",
            _ks_table(tests["fraction_in_goal"], 3),
            "", "## Table V. Two-sample Kolmogorov–Smirnov tests: mean distance outside the goal", "",
            _ks_table(tests["mean_outside_distance"], 3),
            *(_figures_section(figs, rel) if figs else
              ["", "Figures not drawn (`--no-figures`): `phototaxis report` without it draws them."]),
            "", "## Files", "",
            "- `summary.csv`: Tables II and III; `ks_tests.csv`: Tables IV and V"
            + ("; `generated.csv`: the generated shapes, one row each" if meta.get("generated") else ""),
            "- `results.csv`: every sample of every trial; `final.csv`: one row per trial with its final "
            "metrics, its controller, what it sensed, its light energy and full configuration",
            "- `trials/<case>/seed-<seed>.csv|json` (in the sweep folder): the raw per-trial records", ""]
    return "\n".join(out)


def _figures_section(figs: dict, rel) -> list[str]:
    """The one figure report.md shows, the final layouts (compact: the repository keeps it of every committed
    evaluation), and where the others are; links only to what is shown, so a committed report links to
    nothing that is not committed. A draw of generated shapes shows its worst shapes' layouts in its own
    section instead, and its metrics a line per family."""
    if "layouts" not in figs:
        return ["", "## Figures", "",
                f"The fraction of boxes in the goal over time and the mean distance of the boxes outside it, mean "
                f"± 1 s.d. over the trials of each family of generated shapes, are `{rel(figs['fraction_in_goal'])}` "
                f"and `{rel(figs['mean_outside_distance'])}`; every figure is also an SVG beside its PNG."]
    return ["", "## Figures 6 and 7. Final box layouts", "",
            "For each case, the trial whose final fraction in goal is nearest the case's median. Green boxes "
            "are in the goal (black outline), orange ones outside; the dashed square is the construction area.",
            "", f"![final layouts]({rel(figs['layouts'])})", "",
            f"Figure 4, the fraction of boxes in the goal over time, and Figure 5, the mean distance of the boxes "
            f"outside it (mean ± 1 s.d. band per case), are `{rel(figs['fraction_in_goal'])}` and "
            f"`{rel(figs['mean_outside_distance'])}`; every figure is also an SVG beside its PNG."]


# ------------------------------------------------------------------ CLI


def report_command(args: argparse.Namespace) -> int:
    try:
        report = build_report(args.dir, args.out, args.against, args.against_label, figures=not args.no_figures)
    except SweepError as exc:
        raise UserError(str(exc)) from None
    print(report)
    return 0


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "report", help="rebuild tables, figures and report.md from a sweep's stored results",
        description="Read DIR/trials (written by 'phototaxis sweep') and write report.md, summary.csv, "
        "ks_tests.csv, results.csv, final.csv and figures/ into DIR, or into --out.")
    p.add_argument("dir", metavar="DIR", help="the folder a sweep wrote (its --out)")
    p.add_argument("--out", metavar="DEST", default=None,
                   help="write the report here instead (e.g. static/paper), without the raw trial files")
    p.add_argument("--against", metavar="FOLDER", default=None,
                   help="set the same cases of another report folder (its final.csv) beside these, with KS "
                        "tests and light energy, e.g. --against static/paper")
    p.add_argument("--against-label", default="open loop", metavar="TEXT",
                   help="what to call that other set in the tables [default: open loop]")
    p.add_argument("--no-figures", action="store_true",
                   help="tables, CSV files and report.md only: a few seconds faster, e.g. to look at a sweep "
                        "that is still running")
    p.set_defaults(func=report_command)
    return p
