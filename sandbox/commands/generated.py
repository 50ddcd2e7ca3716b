"""What the repository commits that a command generates: the table ``phototaxis regenerate`` runs.

Each row is one committed evaluation (a sweep and its report into ``static/``) or the demo
recordings: its name, what it writes, and the ``phototaxis`` commands that make it, in order, as a
user would type them (``{runs}`` is the folder the sweeps keep their trials in, ``--runs``). The
rows run in this order: an evaluation set ``--against`` another comes after it. The grid files the
sweeps read stay in ``static/`` beside what they made.

Git keeps of a report folder what a reader reads: ``report.md``, its small CSV tables and
``figures/final_layouts.png`` (written compact); ``.gitignore`` leaves out the rest (``results.csv``,
the other figures and the SVGs) and the demo recordings. ``tests/test_repository.py`` checks both.
"""

from __future__ import annotations

from dataclasses import dataclass

from sandbox.model.config import CASES

#: Stands for the --runs folder in the commands below.
RUNS = "{runs}"


@dataclass(frozen=True)
class Generated:
    name: str
    what: str  # one line: what it measures or shows
    out: str  # the report folder it writes, or a glob of the files (recordings)
    commands: tuple[tuple[str, ...], ...]  # phototaxis argv, in order

    @property
    def is_report(self) -> bool:
        return any(argv[0] == "report" for argv in self.commands)


def evaluation(name: str, what: str, out: str, sweep: tuple[str, ...], *, trials: int,
               report: tuple[str, ...] = ()) -> Generated:
    """A sweep into {runs}/NAME (its report left for later) and its report into ``out``."""
    trials_dir = f"{RUNS}/{name}"
    return Generated(name, what, out, (
        ("sweep", *sweep, "--trials", str(trials), "--no-report", "--out", trials_dir),
        ("report", trials_dir, "--out", out, *report)))


def demos() -> Generated:
    """The paper's seven cases as pages that replay in any browser (docs/browser.md)."""
    return Generated("demos", "the paper's seven cases, 6,000 steps each, as standalone HTML replays",
                     "static/demo-*.html",
                     tuple(("record", "--case", case, "--steps", "6000", "--every", "120", "--fps", "10",
                            "--out", f"static/demo-{case}.html") for case in CASES))


TABLE: tuple[Generated, ...] = (
    evaluation("paper", "the paper's seven cases, default profile (README, docs/experiments.md)",
               "static/paper", ("--cases", "paper"), trials=10),
    evaluation("paper-text", "the paper's seven cases under the paper's written model",
               "static/paper-text", ("--cases", "paper", "--profile", "paper-text"), trials=10),
    evaluation("closed-loop", "chase on the paper's seven cases, beside the open loop (docs/closed-loop.md)",
               "static/closed-loop", ("--cases", "paper", "--chase", "2.0"), trials=10,
               report=("--against", "static/paper")),
    evaluation("closed-loop-packed", "chase on a goal already built, beside the scattered start",
               "static/closed-loop/packed-start", ("--cases", "paper", "--box-start", "packed", "--chase", "2.0"),
               trials=10, report=("--against", "static/closed-loop", "--against-label", "chase, scattered start")),
    evaluation("hold", "the star with a hold of 2,500 steps", "static/experiments/hold",
               ("--grid", "static/experiments/hold.toml"), trials=6),
    evaluation("shapes", "every shape in shapes/, scaled and offset outlines (static/shapes/README.md)",
               "static/shapes", ("--grid", "static/shapes/evaluation.toml"), trials=4),
    evaluation("shapes-chase", "every shape in shapes/, offset outline with chase", "static/shapes/chase",
               ("--grid", "static/shapes/evaluation-chase.toml"), trials=4),
    evaluation("shapes-scaled-chase", "five shapes, scaled outline with chase", "static/shapes/scaled-chase",
               ("--grid", "static/shapes/evaluation-scaled-chase.toml"), trials=4),
    evaluation("notched", "notched and thin shapes, the default (docs/design-notches.md)", "static/shapes/notched",
               ("--grid", "static/shapes/notched/evaluation.toml"), trials=4),
    evaluation("notched-plain", "notched and thin shapes, the plain band", "static/shapes/notched/plain",
               ("--grid", "static/shapes/notched/evaluation-plain.toml"), trials=4),
    evaluation("templates", "the drawing templates", "static/shapes/templates",
               ("--grid", "static/shapes/templates/evaluation.toml"), trials=4),
    evaluation("templates-candidates", "the drawing templates with chase, for the advisor's check (bench --advice)",
               "static/shapes/templates/candidates", ("--grid", "static/shapes/templates/evaluation-candidates.toml"),
               trials=2),
    evaluation("generated", "100 generated shapes nobody chose, the fresh draw never tuned on (docs/shapes.md)",
               "static/shapes/generated", ("--generated", "100", "--families", "all", "--generator-seed", "2",
                                           "--steps", "100000"), trials=2),
    evaluation("iterations", "solver iterations 10 against 5", "static/tuning/iterations",
               ("--grid", "static/tuning/iterations.toml"), trials=8),
    evaluation("iterations6", "solver iterations 10 against 6 (docs/performance.md)", "static/tuning/iterations6",
               ("--grid", "static/tuning/iterations6.toml"), trials=8),
    evaluation("sleep", "bodies asleep or not (docs/performance.md)", "static/tuning/sleep",
               ("--grid", "static/tuning/sleep.toml"), trials=16),
    demos(),
)

#: What ``phototaxis bench --advice`` checks the advisor on: every shape in shapes/, the circle and the
#: drawing templates, against the candidates these evaluations ran to 100,000 steps (rows above).
ADVICE_SHAPES = ("circle", "shapes/*.txt", "static/shapes/templates/shapes/*.txt")
ADVICE_EVALUATIONS = ("static/shapes/final.csv", "static/shapes/chase/final.csv",
                      "static/shapes/scaled-chase/final.csv", "static/closed-loop/final.csv",
                      "static/shapes/templates/final.csv", "static/shapes/templates/candidates/final.csv")
