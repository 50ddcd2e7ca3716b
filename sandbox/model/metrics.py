"""Measuring success on arrays of box centres, and the samples of it that
runs, sweeps, reports and the app record (one CSV writer and reader for all)."""

from __future__ import annotations

import csv
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import IO, Any, Sequence

import numpy as np

from sandbox.model.goal import Goal


@dataclass(frozen=True)
class Sample:
    """Both success metrics and a few health counts at one step."""

    step: int
    fraction_in_goal: float
    mean_outside_distance: float
    boxes_escaped: int
    charged_robots: int
    cycle: int
    phase: str

    def to_dict(self) -> dict:
        return asdict(self)


#: Column names of a metrics sample, in order (CSV traces, sweeps, the app).
SAMPLE_FIELDS = [f.name for f in fields(Sample)]


class SampleWriter:
    """Writes samples as CSV rows: ``leading`` columns (e.g. case, seed), the
    sample's fields, then ``trailing`` columns (e.g. time); numbers in full
    precision. The one writer of sample files: run traces, sweep trials,
    report tables and the app's download."""

    def __init__(self, handle: IO[str], leading: Sequence[str] = (), trailing: Sequence[str] = ()):
        self.leading, self.trailing = list(leading), list(trailing)
        self._csv = csv.writer(handle)
        self._csv.writerow([*self.leading, *SAMPLE_FIELDS, *self.trailing])

    def write(self, sample: "Sample | dict", **columns: Any) -> None:
        values = sample.to_dict() if isinstance(sample, Sample) else sample
        row = [*(columns[c] for c in self.leading), *(values[c] for c in SAMPLE_FIELDS),
               *(columns[c] for c in self.trailing)]
        self._csv.writerow([plain(v) for v in row])


def plain(value: Any) -> Any:
    """A value as a CSV cell: numpy scalars unwrapped, floats in full precision."""
    if hasattr(value, "item"):  # numpy scalars
        value = value.item()
    return repr(value) if isinstance(value, float) else value


def read_samples(path: Path) -> dict[str, np.ndarray]:
    """A sample file (as :class:`SampleWriter` writes it) as one array per sample field."""
    with Path(path).open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError("no samples")
    out: dict[str, np.ndarray] = {}
    for c in SAMPLE_FIELDS:
        values = [r[c] for r in rows]
        out[c] = np.array(values) if c == "phase" else np.array(values, dtype=float)
    out["step"] = out["step"].astype(int)
    return out


def fraction_in_goal(in_goal: np.ndarray) -> float:
    """Share of boxes whose centre is inside the goal (1.0 when there are no boxes)."""
    return float(in_goal.mean()) if len(in_goal) else 1.0


def mean_outside_distance(box_positions: np.ndarray, goal: Goal, in_goal: np.ndarray) -> float:
    """Mean distance of boxes outside the goal to its nearest point (0 if none are)."""
    outside = box_positions[~in_goal]
    if len(outside) == 0:
        return 0.0
    return float(goal.distance(outside).mean())


def escaped(box_positions: np.ndarray, centre: float, construction_size: float) -> np.ndarray:
    """Boxes whose centre lies outside the construction wall, centred on
    (centre, centre) (must never happen)."""
    return np.any(np.abs(box_positions - centre) > construction_size / 2.0, axis=1)
