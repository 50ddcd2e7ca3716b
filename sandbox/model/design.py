"""A design: a goal and the light program that built it, in one file a real light field can play.

A :class:`Design` holds the goal (as given, and as fitted on the floor), every setting, the seed,
the steps run and the light program that ran: the pattern at the start and every change, each with
the step it started. :class:`PatternRecorder` keeps them while a simulation runs (the simulation
tells it each change: it costs nothing between changes); :class:`Replay` is a light program that
plays them back at their steps, so the same seed and settings rebuild the same world bit for bit
without the controller that first lit it. :func:`save` and :func:`load` write and read the one file
format, a NumPy ``.npz`` archive (docs/design-files.md): a JSON ``header``, ``steps`` and
``patterns``. :func:`load` checks everything: a damaged, truncated, foreign or inconsistent file is
a :class:`DesignError` in one line.
"""

from __future__ import annotations

import io
import json
import math
import os
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.model.config import Config, ConfigError
from sandbox.model.programs import LightProgram, ProgramError

#: What the header's ``format`` says: a file without it is not a design.
FORMAT = "phototaxis-design"
#: The format's version: a reader refuses versions it does not know.
VERSION = 1
#: The arrays of a design file, besides which it holds nothing.
ARRAYS = ("header", "steps", "patterns")
#: Other files a design file may be taken for, by their first bytes (to say what it is instead).
_MAGIC = {b"\x89PNG": "a PNG image", b"\xff\xd8\xff": "a JPEG image", b"GIF8": "a GIF image",
          b"%PDF": "a PDF document", b"\x93NUMPY": "a single NumPy array (.npy)", b"\x1f\x8b": "a gzip file"}


class DesignError(ValueError):
    """A design that cannot be read or made: the message says why, in one line."""


@dataclass(frozen=True, eq=False)
class Design:
    """A goal, the settings and seed, and the light program that ran on them."""

    config: Config
    #: The goal's polygon as it was given (any position and size: the simulation fits it), None for the circle.
    shape: np.ndarray | None
    #: World steps the run took.
    steps_run: int
    #: (k,) the step each pattern started at: non-decreasing, the first 0.
    steps: np.ndarray
    #: (k, rows, cols): uint8 0 / 1 when every light was only off or at intensity 1, else float64 intensities.
    patterns: np.ndarray
    #: What lit the floor when it was recorded (the paper's controller, chase, a user's program).
    controller: str = ""
    #: The goal fitted on the floor, in metres: ``vertices`` (None for the circle), ``centre``, ``radius``.
    goal: dict = field(default_factory=dict)
    #: The run's end: ``fraction_in_goal``, ``mean_outside_distance``, ``state_digest``.
    result: dict = field(default_factory=dict)

    @property
    def seed(self) -> int:
        return self.config.seed

    def header(self) -> dict:
        """The file's JSON header (docs/design-files.md)."""
        cfg = self.config
        return {
            "format": FORMAT,
            "version": VERSION,
            "seed": cfg.seed,
            "steps_run": int(self.steps_run),
            "controller": self.controller,
            "light_field": light_field(cfg),
            "goal": {"name": cfg.shape, "given": _listed(self.shape), **self.goal},
            "result": self.result,
            "config": cfg.to_dict(),
        }


def light_field(config: Config) -> dict:
    """What a real light field needs to play the patterns: the grid, where it lies, the step's length."""
    n, pitch = config.lights_per_side, config.light_pitch
    return {"rows": n, "cols": n, "pitch_m": pitch, "height_m": config.light_height,
            "first_light_centre_m": [pitch / 2.0, pitch / 2.0], "rows_along": "x", "cols_along": "y",
            "on_intensity": config.light_intensity, "step_seconds": config.dt}


def _number(value: float) -> float | None:
    """A result for JSON: None where it is not a number (the stray distance with no box outside)."""
    return None if math.isnan(value) else float(value)


def _listed(vertices: np.ndarray | None) -> list | None:
    return None if vertices is None else np.asarray(vertices, dtype=float).tolist()


# ------------------------------------------------------------------ recording
class PatternRecorder:
    """The light program a simulation runs, kept as it runs: the pattern at the start and every change.

    ``PatternRecorder().attach(sim)`` before the first step; the simulation then calls :meth:`change`
    at each change of its lit pattern, and :meth:`start` when a reset builds a new world. A change
    costs a comparison and 512 bytes (a 64 x 64 on / off pattern, packed bits) or a copy (other
    intensities); nothing is done between changes."""

    def __init__(self, most: int | None = None) -> None:
        """``most``: keep at most this many patterns (a live world runs for hours); past it the recorder
        stops, and :meth:`design` says so."""
        self.most = most
        self.full = False
        self._steps: list[int] = []
        self._kept: list[tuple[bool, np.ndarray]] = []  # (on / off only?, packed bits or the intensities)
        self._shape: tuple[int, int] = (0, 0)

    def attach(self, sim: Any) -> "PatternRecorder":
        sim.pattern_recorder = self
        self.start(sim.steps_done, sim.lights.intensities)
        return self

    def start(self, step: int, pattern: np.ndarray) -> None:
        """A light program starts here (a new world): forget what came before."""
        self._steps, self._kept, self._shape = [], [], tuple(pattern.shape)
        self.full = False
        self.change(step, pattern)

    def change(self, step: int, pattern: np.ndarray) -> None:
        """The lit pattern became ``pattern`` at ``step`` (before that world step is computed)."""
        if self.most is not None and len(self._steps) >= self.most:
            self.full = True
            return
        on_off = bool(((pattern == 0) | (pattern == 1)).all())
        self._steps.append(int(step))
        self._kept.append((on_off, np.packbits(pattern != 0) if on_off else np.array(pattern, dtype=np.float64)))

    def __len__(self) -> int:
        return len(self._steps)

    def patterns(self) -> tuple[np.ndarray, np.ndarray]:
        """The steps (k,) and the patterns (k, rows, cols), uint8 if every light was only off or at 1."""
        rows, cols = self._shape
        size = rows * cols
        if all(on_off for on_off, _ in self._kept):
            patterns = np.stack([np.unpackbits(bits, count=size) for _, bits in self._kept])
        else:
            patterns = np.stack([np.unpackbits(kept, count=size).astype(np.float64) if on_off else kept.reshape(-1)
                                 for on_off, kept in self._kept])
        return np.array(self._steps, dtype=np.int64), patterns.reshape(-1, rows, cols)

    def design(self, sim: Any, controller: str = "") -> Design:
        """The design of ``sim`` as it stands: its goal, settings, seed, steps and this light program."""
        if self.full:
            raise DesignError(f"this world's light program has more than {self.most:,} patterns, more than a design "
                              "keeps from a live world: reset it, and download the design sooner")
        if not self._steps or self._steps[0] != 0:
            start = self._steps[0] if self._steps else "nowhere"
            raise DesignError(f"the light program was recorded from step {start}, not from the world's start: "
                              "a design replays from its seed, so reset the world and record it whole")
        steps, patterns = self.patterns()
        sample = sim.measure()
        goal = sim.goal
        return Design(config=sim.config, shape=None if sim.shape_vertices is None else np.array(sim.shape_vertices),
                      steps_run=sim.steps_done, steps=steps, patterns=patterns, controller=controller,
                      goal={"vertices": _listed(goal.vertices), "centre": np.asarray(goal.centre, float).tolist(),
                            "radius": goal.radius},
                      result={"fraction_in_goal": _number(sample.fraction_in_goal),
                              "mean_outside_distance": _number(sample.mean_outside_distance),
                              "state_digest": sim.state_digest()})


# -------------------------------------------------------------------- replay
class Replay(LightProgram):
    """A light program that plays a design's patterns, each from the step it started. It looks at
    nothing: the same seed and settings then rebuild the recorded run bit for bit, closed loops
    (chase) included, since what they saw is in the patterns they lit.

    Two changes at one step (a live change in the page, then the program's update) play as the last."""

    every = 1  # asked every step: a pattern may start at any step

    def __init__(self, design: Design):
        self.design = design
        self._steps = [int(s) for s in design.steps]  # Python ints: compared every step
        self._next = 1

    def reset(self, config: Config, goal: Any) -> np.ndarray:
        super().reset(config, goal)
        expected = self.design.patterns.shape[1:]
        if (config.lights_per_side,) * 2 != expected:
            raise ProgramError(f"this design's light grid is {expected[0]} x {expected[1]}; the world's is "
                               f"{config.lights_per_side} x {config.lights_per_side}")
        self._next = 1
        return self.design.patterns[0]

    def update(self, observation: Any) -> np.ndarray | None:
        steps, before = self._steps, self._next
        while self._next < len(steps) and steps[self._next] <= observation.step:
            self._next += 1
        return self.design.patterns[self._next - 1] if self._next > before else None


# ----------------------------------------------------------------- the file
def file_bytes(design: Design) -> bytes:
    """The design file's bytes (a NumPy .npz archive, compressed): what :func:`save` writes."""
    buffer = io.BytesIO()
    np.savez_compressed(buffer, header=np.array(json.dumps(design.header(), allow_nan=False)),
                        steps=np.asarray(design.steps, dtype=np.int64), patterns=design.patterns)
    return buffer.getvalue()


def save(design: Design, path: str | os.PathLike) -> None:
    """Write the design to ``path`` (a NumPy .npz archive, compressed), whole or not at all."""
    path = Path(path)
    part = path.with_name(path.name + ".part")
    try:
        part.write_bytes(file_bytes(design))
        os.replace(part, path)
    except OSError as exc:
        part.unlink(missing_ok=True)
        raise DesignError(f"cannot write design file {path}: {exc.strerror or exc}") from None


def load(path: str | os.PathLike) -> Design:
    """The design in ``path``, checked; a :class:`DesignError` in one line if it is not one."""
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise DesignError(f"cannot read design file {path}: {exc.strerror or exc}") from None
    arrays = _arrays(raw, path)
    try:
        return _design(arrays, path)
    except DesignError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever else a crafted file trips: still one line
        raise DesignError(f"{path}: not a valid design file ({type(exc).__name__}: {_first_line(exc)})") from None


def _arrays(raw: bytes, path: Any) -> dict[str, np.ndarray]:
    """The archive's arrays, read whole (no pickles); a DesignError for anything that is not one."""
    if not raw.startswith(b"PK"):
        what = next((kind for magic, kind in _MAGIC.items() if raw.startswith(magic)),
                    "empty" if not raw else "not a NumPy .npz archive")
        raise DesignError(f"{path} is not a design file: it is {what}")
    try:
        with np.load(io.BytesIO(raw), allow_pickle=False) as archive:
            if "header" not in archive.files:
                held = ", ".join(archive.files[:5]) or "nothing"
                raise DesignError(f"{path} is not a design file: a NumPy archive without a header (it holds {held})")
            return {name: archive[name] for name in archive.files}
    except DesignError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, ValueError, OSError, KeyError) as exc:
        raise DesignError(f"{path} is damaged (cut short or altered?): {_first_line(exc)}") from None


def _design(arrays: dict[str, np.ndarray], path: Any) -> Design:
    header = _header(arrays["header"], path)
    missing = [name for name in ARRAYS if name not in arrays]
    if missing:
        raise DesignError(f"{path} is damaged: it has no {' or '.join(repr(m) for m in missing)} array")
    try:
        config = Config().replace(**_field(header, "config", dict, path))
    except ConfigError as exc:
        raise DesignError(f"{path}: its settings are refused: {exc}") from None
    steps_run = _field(header, "steps_run", int, path)
    if _field(header, "seed", int, path) != config.seed:
        raise DesignError(f"{path} is inconsistent: its seed {header['seed']} is not its settings' {config.seed}")
    _check_light_field(_field(header, "light_field", dict, path), config, path)
    steps = _steps(arrays["steps"], steps_run, path)
    patterns = _patterns(arrays["patterns"], len(steps), config.lights_per_side, path)
    goal = _field(header, "goal", dict, path)
    return Design(config=config, shape=_vertices(goal.get("given"), path), steps_run=steps_run, steps=steps,
                  patterns=patterns, controller=str(header.get("controller", "")),
                  goal={k: v for k, v in goal.items() if k not in ("name", "given")},
                  result=header.get("result") if isinstance(header.get("result"), dict) else {})


def _header(array: np.ndarray, path: Any) -> dict:
    if array.dtype.kind != "U" or array.shape != ():
        raise DesignError(f"{path} is not a design file: its header is not one JSON text")
    try:
        header = json.loads(str(array))
    except json.JSONDecodeError as exc:
        raise DesignError(f"{path} is damaged: its header is not valid JSON ({exc.msg} at {exc.pos})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise DesignError(f"{path} is not a design file: its header does not say format {FORMAT!r}")
    version = header.get("version")
    if version != VERSION:
        raise DesignError(f"{path} is a design of format version {version!r}; this program reads version {VERSION}")
    return header


def _field(header: dict, name: str, kind: type, path: Any) -> Any:
    value = header.get(name)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise DesignError(f"{path} is damaged: its header's {name!r} is {type(value).__name__}, not {kind.__name__}")
    return value


def _check_light_field(grid: dict, config: Config, path: Any) -> None:
    expected = light_field(config)
    wrong = [key for key in ("rows", "cols", "pitch_m", "step_seconds") if grid.get(key) != expected[key]]
    if wrong:
        raise DesignError(f"{path} is inconsistent: its light field's {', '.join(wrong)} disagree with its settings")


def _steps(steps: np.ndarray, steps_run: int, path: Any) -> np.ndarray:
    if steps.ndim != 1 or steps.dtype.kind not in "iu" or len(steps) == 0:
        raise DesignError(f"{path} is damaged: 'steps' must be a list of whole steps, not {steps.dtype} {steps.shape}")
    if steps[0] != 0 or (np.diff(steps) < 0).any() or steps[-1] > steps_run:
        raise DesignError(f"{path} is inconsistent: the patterns' steps must start at 0 and never go back, "
                          f"within the {steps_run} steps run")
    return steps.astype(np.int64)


def _patterns(patterns: np.ndarray, count: int, n: int, path: Any) -> np.ndarray:
    if patterns.shape != (count, n, n):
        raise DesignError(f"{path} is inconsistent: 'patterns' is {patterns.shape}; {count} steps on a "
                          f"{n} x {n} grid need ({count}, {n}, {n})")
    if patterns.dtype == np.uint8:
        if (patterns > 1).any():
            raise DesignError(f"{path} is damaged: on / off patterns hold values other than 0 and 1")
        return patterns
    if patterns.dtype != np.float64 or not np.isfinite(patterns).all() or (patterns < 0).any():
        raise DesignError(f"{path} is damaged: 'patterns' must be uint8 0 / 1 or float64 intensities, finite "
                          f"and not negative")
    return patterns


def _vertices(given: Any, path: Any) -> np.ndarray | None:
    if given is None:
        return None
    vertices = np.asarray(given, dtype=float)
    if vertices.ndim != 2 or vertices.shape[1] != 2 or len(vertices) < 3 or not np.isfinite(vertices).all():
        raise DesignError(f"{path} is damaged: its goal is not a polygon of at least 3 (x, y) points")
    return vertices


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__

