"""What the sandbox is measured against, for the paper's seven cases.

- ``PAPER``: the paper's Tables II and III (final fraction of boxes in the
  goal, mean distance of the boxes outside it in metres).
- ``PROGRAM``: the authors' released program (github AdamBignell/push, HEAD,
  built -O2, headless), run by this project in the paper's configuration:
  4 seeds (1-4) x 100,000 steps per case; mean and standard error of the
  final values. These are measurements, not the program's code.
- ``FINDINGS``: the paper's qualitative findings as numbers a run of the
  seven cases must meet (the fidelity issue's thresholds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

#: case -> (fraction in goal, distance outside in m), the paper's Tables II / III.
PAPER = {
    "circle": (0.822, 0.39),
    "square": (0.795, 0.52),
    "square-flare": (0.790, 1.54),
    "square-flare-switch": (0.819, 0.54),
    "star": (0.683, 1.80),
    "star-switch": (0.761, 0.61),
    "star-switch-nocorners": (0.756, 0.50),
}

#: case -> ((fraction mean, s.e.), (distance mean, s.e.)) of the authors' program, 4 seeds.
PROGRAM = {
    "circle": ((0.7975, 0.0049), (0.3521, 0.0076)),
    "square": ((0.7895, 0.0045), (0.4748, 0.0129)),
    "square-flare": ((0.7700, 0.0057), (1.0079, 0.0699)),
    "square-flare-switch": ((0.7990, 0.0026), (0.4266, 0.0082)),
    "star": ((0.7265, 0.0039), (1.1000, 0.0260)),
    "star-switch": ((0.7735, 0.0095), (0.4073, 0.0224)),
    "star-switch-nocorners": ((0.7660, 0.0045), (0.5203, 0.0247)),
}
PROGRAM_SEEDS = "1-4"

#: case -> largest drop of the program's mean fraction-in-goal series below its running best (4 seeds).
PROGRAM_DIPS = {
    "circle": 0.0245,
    "square": 0.0135,
    "square-flare": 0.0115,
    "square-flare-switch": 0.0190,
    "star": 0.0110,
    "star-switch": 0.0135,
    "star-switch-nocorners": 0.0245,
}

#: The program's circle case over its first contraction: step -> mean fraction in goal over its
#: 4 seeds (series.csv). At 4000 the band has not reached the boxes yet (their scattered start);
#: by 6000 it has swept them in. A short run of the model is checked against it (test_fidelity).
PROGRAM_CIRCLE_FIRST_CONTRACTION = {4000: 0.3165, 5000: 0.541, 6000: 0.740}

#: How close to the program a faithful model's case means must be.
FRACTION_TOLERANCE = 0.025
DISTANCE_TOLERANCE = 0.25  # m
#: Largest drop of a case's mean fraction-in-goal series below its running best.
DIP_TOLERANCE = 0.03


@dataclass(frozen=True)
class Finding:
    text: str
    needs: tuple[str, ...]  # cases it compares
    #: value from {case: (fraction mean, distance mean)}; and whether it holds
    measure: Callable[[dict], float]
    holds: Callable[[float], bool]
    shown: str  # how the value reads, e.g. "{:+.3f}"


FINDINGS = (
    Finding("switch lifts the star by at least 3 points", ("star", "star-switch"),
            lambda m: m["star-switch"][0] - m["star"][0], lambda v: v >= 0.03, "{:+.3f}"),
    Finding("switch at least halves the star's stray distance", ("star", "star-switch"),
            lambda m: m["star-switch"][1] / m["star"][1], lambda v: v <= 0.5, "x{:.2f}"),
    Finding("flare pushes the square's stray boxes out at least 1.8x", ("square", "square-flare"),
            lambda m: m["square-flare"][1] / m["square"][1], lambda v: v >= 1.8, "x{:.2f}"),
    Finding("adding switch to flare brings them back to at most 0.6x", ("square-flare", "square-flare-switch"),
            lambda m: m["square-flare-switch"][1] / m["square-flare"][1], lambda v: v <= 0.6, "x{:.2f}"),
)
