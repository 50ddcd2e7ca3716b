"""A design: a goal and the light program that built it, in one file a real light field can play.

A :class:`Design` holds the goal (as given, and as fitted on the floor), every setting, the seed,
the steps run and the light program that ran: the pattern at the start and every change, each with
the step it started. :class:`PatternRecorder` keeps them while a simulation runs (the simulation
tells it each change: it costs nothing between changes); :class:`Replay` is a light program that
plays them back at their steps, so the same seed and settings rebuild the same world bit for bit
without the controller that first lit it. :func:`save` and :func:`load` write and read the one file
format, a NumPy ``.npz`` archive (docs/design-files.md): a JSON ``header``, ``steps`` and
``patterns``. :func:`load` checks everything: a damaged, truncated, foreign or inconsistent file is
a :class:`DesignError` in one line, and so is one larger than the bounds below, refused from the
archive's directory and each array's header before anything is unpacked (:mod:`.bounded_npz`).
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import stat
import struct
import zipfile
import zlib
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO, Callable, Iterator

import numpy as np

from sandbox.model import bounded_npz
from sandbox.model.config import Config, ConfigError
from sandbox.model.programs import LightProgram, ProgramError
from sandbox.shapes.validation import MAX_VERTICES

#: What the header's ``format`` says: a file without it is not a design.
FORMAT = "phototaxis-design"
#: The format's version: a reader refuses versions it does not know.
VERSION = 1
#: The arrays of a design file, besides which it holds nothing.
ARRAYS = ("header", "steps", "patterns")

# Bounds on a design, checked before anything is unpacked; :func:`save` and the recorder keep to them
# too, so every design this program writes, it reads (docs/design-files.md#bounds).
_DEFAULT = Config()
#: Light patterns a design holds: ten times the controller updates of a default run (100,000 steps,
#: an update every 100): 10,000. The star with switch and chase holds 942 in a default run.
MAX_PATTERNS = 10 * (_DEFAULT.steps // _DEFAULT.update_every)
#: Bytes its patterns unpack to: that many on / off patterns of the default 64 x 64 grid, 41 MB
#: (1,250 patterns of float64 intensities).
MAX_PATTERN_BYTES = MAX_PATTERNS * _DEFAULT.lights_per_side ** 2
#: Characters of its JSON header: the goal as given and as fitted, each of an upload's most vertices
#: (10,000) at up to 52 characters a vertex, is 1.04 million; the rest is 2,000.
MAX_HEADER_CHARS = 1_500_000
#: Characters of a name shown in the page (the goal's, the settings' shape); an uploaded file's name is cut to it.
MAX_NAME_CHARS = 80
#: Characters of what lit the floor (a light program's file and class): longer is cut when recorded.
MAX_CONTROLLER_CHARS = 1_000
#: Bytes of the file on disk: its largest patterns and header even if nothing compressed, and margin.
MAX_FILE_BYTES = 64_000_000
#: Characters a name may not hold: it is shown on one line.
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")

#: What a design keeps of its run's end (the header's ``result``): ``cycles`` is null when the paper's
#: controller did not light the whole run (a light program's cycles are its own), absent in older files.
RESULT_KEYS = ("fraction_in_goal", "mean_outside_distance", "state_digest", "cycles")
#: Other files a design file may be taken for, by their first bytes (to say what it is instead).
_MAGIC = {b"\x89PNG": "a PNG image", b"\xff\xd8\xff": "a JPEG image", b"GIF8": "a GIF image",
          b"%PDF": "a PDF document", b"\x93NUMPY": "a single NumPy array (.npy)", b"\x1f\x8b": "a gzip file"}


class DesignError(ValueError):
    """A design that cannot be read or made: the message says why, in one line."""


@dataclass(frozen=True, eq=False, repr=False)
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
    #: The run's end: ``fraction_in_goal``, ``mean_outside_distance``, ``state_digest``, ``cycles``.
    result: dict = field(default_factory=dict)

    @property
    def cycles(self) -> int | None:
        """The contract-hold-dilate cycles the run went through, as recorded: None when they were not
        counted (a light program of the user's, a goal changed mid-run) or the file is older than the count.
        A replay cannot count them itself: its patterns have no cycle."""
        cycles = self.result.get("cycles")
        return cycles if isinstance(cycles, int) and not isinstance(cycles, bool) and cycles >= 0 else None

    @property
    def seed(self) -> int:
        return self.config.seed

    def __repr__(self) -> str:
        """A line, not its arrays: an error quoting a command that carries a design stays one line."""
        return (f"Design(shape={self.config.shape[:MAX_NAME_CHARS]!r}, seed={self.seed}, steps_run={self.steps_run}, "
                f"patterns={len(self.patterns)} x {' x '.join(map(str, self.patterns.shape[1:]))})")

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


def _shortened(controller: str) -> str:
    """What lit the floor, as a design keeps it: on one line, cut to :data:`MAX_CONTROLLER_CHARS` (it only
    describes: the patterns replay without it)."""
    text = _CONTROL.sub("?", str(controller))
    return text if len(text) <= MAX_CONTROLLER_CHARS else text[:MAX_CONTROLLER_CHARS - 1] + "…"


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

    def __init__(self, most: int = MAX_PATTERNS) -> None:
        """``most``: keep at most this many patterns (a live world runs for hours), and never more than a
        design holds (:data:`MAX_PATTERNS`, :data:`MAX_PATTERN_BYTES` unpacked: fewer on a larger grid or
        with intensities other than 0 and 1); past it the recorder stops, and :meth:`design` says so."""
        self.most = min(most, MAX_PATTERNS)
        self.full = False
        #: Whether one paper's controller lit the floor since the start, so that its cycle is the run's.
        self.cycles_counted = True
        self._steps: list[int] = []
        self._kept: list[tuple[bool, np.ndarray]] = []  # (on / off only?, packed bits or the intensities)
        self._shape: tuple[int, int] = (0, 0)
        self._dimmed = False  # an intensity other than 0 and 1 so far: the design stores float64

    def attach(self, sim: Any) -> "PatternRecorder":
        sim.pattern_recorder = self
        self.start(sim.steps_done, sim.lights.intensities, paper=sim.user_program is None)
        return self

    def start(self, step: int, pattern: np.ndarray, paper: bool = True) -> None:
        """A light program starts here (a new world): forget what came before. ``paper``: whether the
        paper's controller lights it (its cycles are then counted)."""
        self._steps, self._kept, self._shape = [], [], tuple(pattern.shape)
        self.full = self._dimmed = False
        self.cycles_counted = paper
        self.change(step, pattern)

    def cycles_lost(self) -> None:
        """The controller's cycle no longer covers the whole run: another program took the floor, or a
        new goal brought a new controller, counting from 0, mid-run."""
        self.cycles_counted = False

    def change(self, step: int, pattern: np.ndarray) -> None:
        """The lit pattern became ``pattern`` at ``step`` (before that world step is computed)."""
        if self.full:
            return
        on_off = bool(((pattern == 0) | (pattern == 1)).all())
        if len(self._steps) >= self._room(self._dimmed or not on_off):
            self.full = True
            return
        self._dimmed = self._dimmed or not on_off
        self._steps.append(int(step))
        self._kept.append((on_off, np.packbits(pattern != 0) if on_off else np.array(pattern, dtype=np.float64)))

    def __len__(self) -> int:
        return len(self._steps)

    def _room(self, dimmed: bool) -> int:
        """Patterns a design of this grid holds: at most ``most``, unpacking to :data:`MAX_PATTERN_BYTES`."""
        rows, cols = self._shape
        return min(self.most, MAX_PATTERN_BYTES // max(1, rows * cols * (8 if dimmed else 1)))

    def patterns(self) -> tuple[np.ndarray, np.ndarray]:
        """The steps (k,) and the patterns (k, rows, cols), uint8 if every light was only off or at 1
        (unpacked into one array: at most :data:`MAX_PATTERN_BYTES`)."""
        rows, cols = self._shape
        size = rows * cols
        patterns = np.empty((len(self._kept), size), dtype=np.float64 if self._dimmed else np.uint8)
        for row, (on_off, kept) in zip(patterns, self._kept):
            row[:] = np.unpackbits(kept, count=size) if on_off else kept.reshape(-1)
        return np.array(self._steps, dtype=np.int64), patterns.reshape(-1, rows, cols)

    def design(self, sim: Any, controller: str = "") -> Design:
        """The design of ``sim`` as it stands: its goal, settings, seed, steps and this light program."""
        if self.full:
            rows, cols = self._shape
            raise DesignError(f"this world's light program has more than {len(self):,} patterns of {rows} x {cols} "
                              f"lights, more than a design holds: record a shorter run (a live world: reset it, "
                              f"and download its design sooner)")
        if not self._steps or self._steps[0] != 0:
            start = self._steps[0] if self._steps else "nowhere"
            raise DesignError(f"the light program was recorded from step {start}, not from the world's start: "
                              "a design replays from its seed, so reset the world and record it whole")
        steps, patterns = self.patterns()
        sample = sim.measure()
        goal = sim.goal
        return Design(config=sim.config, shape=None if sim.shape_vertices is None else np.array(sim.shape_vertices),
                      steps_run=sim.steps_done, steps=steps, patterns=patterns, controller=_shortened(controller),
                      goal={"vertices": _listed(goal.vertices), "centre": np.asarray(goal.centre, float).tolist(),
                            "radius": goal.radius},
                      result={"fraction_in_goal": _number(sample.fraction_in_goal),
                              "mean_outside_distance": _number(sample.mean_outside_distance),
                              "state_digest": sim.state_digest(),
                              "cycles": int(sim.cycle) if self.cycles_counted else None})


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
    """The design file's bytes (a NumPy .npz archive, compressed): what :func:`save` writes. A design
    over a bound is a :class:`DesignError`: what this program writes, it reads."""
    header = json.dumps(design.header(), allow_nan=False)
    _check_writable(design, header)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, header=np.array(header), steps=np.asarray(design.steps, dtype=np.int64),
                        patterns=design.patterns)
    return buffer.getvalue()


def save(design: Design, path: str | os.PathLike) -> None:
    """Write the design to ``path`` (a NumPy .npz archive, compressed), whole or not at all."""
    path = Path(path)
    data = file_bytes(design)
    part = path.with_name(path.name + ".part")
    try:
        part.write_bytes(data)
        os.replace(part, path)
    except OSError as exc:
        part.unlink(missing_ok=True)
        raise DesignError(f"cannot write design file {path}: {exc.strerror or exc}") from None


def check_recordable(config: Config) -> None:
    """Refuse, before a run, settings whose design could not be read back: a goal's name too long to
    show (a polygon file's path, as typed)."""
    _check_name(config.shape, "its goal's name (the settings' shape)", "a design of this run", MAX_NAME_CHARS)


def _check_writable(design: Design, header: str) -> None:
    where = "this design"
    _check_name(design.config.shape, "its goal's name (the settings' shape)", where, MAX_NAME_CHARS)
    _check_name(design.controller, "its controller's name", where, MAX_CONTROLLER_CHARS)
    _check_vertex_count(design.shape, "its goal as given", where)
    _check_vertex_count(design.goal.get("vertices"), "its goal as fitted", where)
    if len(header) > MAX_HEADER_CHARS:
        raise DesignError(f"{where} is too large: its header is {len(header):,} characters of JSON; "
                          f"at most {MAX_HEADER_CHARS:,}")
    _check_pattern_count(len(design.patterns), where)
    _check_pattern_bytes(design.patterns.shape, design.patterns.dtype.itemsize, where)


def load(path: str | os.PathLike) -> Design:
    """The design in ``path``, checked; a :class:`DesignError` in one line if it is not one. Nothing is
    unpacked past a bound: the file's size, the archive's directory and each array's header are
    checked before what they describe is read."""
    return _checked(lambda: _opened(path), path)


def load_bytes(content: bytes, name: str) -> Design:
    """The design in ``content``, a file's bytes (a page's upload) named ``name`` in what is said: the
    same checks as :func:`load`, the same one-line :class:`DesignError`, without a file on disk."""
    return _checked(lambda: _in_memory(bytes(content), name), name)


def _checked(open_archive: Callable[[], Any], path: Any) -> Design:
    """The design in the file ``open_archive()`` opens (a context manager of a seekable binary file),
    checked; every failure one line that names ``path``."""
    try:
        with open_archive() as handle, bounded_npz.Archive(handle) as archive:
            return _design(archive, path)
    except DesignError:
        raise
    except bounded_npz.ArchiveTooLarge as exc:
        raise DesignError(f"{path} is too large: {exc}") from None
    except bounded_npz.ArchiveDamaged as exc:
        raise DesignError(f"{path} is damaged: {exc}") from None
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, struct.error) as exc:
        raise DesignError(f"{path} is damaged (cut short or altered?): {_first_line(exc)}") from None
    except Exception as exc:  # noqa: BLE001 - whatever else a crafted file trips: still one line
        raise DesignError(f"{path}: not a valid design file ({type(exc).__name__}: {_first_line(exc)})") from None


@contextmanager
def _opened(path: Any) -> Iterator[BinaryIO]:
    """``path`` opened for reading, once it is known to be a file of at most :data:`MAX_FILE_BYTES`
    (a pipe or a device is never read: /dev/zero never ends) that starts like a zip archive."""
    try:
        _check_file(os.stat(path), path)  # before opening: a pipe's open waits for a writer
        handle = open(path, "rb")  # noqa: SIM115 - closed by the with below
    except OSError as exc:
        raise DesignError(f"cannot read design file {path}: {exc.strerror or exc}") from None
    with handle:
        _check_file(os.fstat(handle.fileno()), path)  # the file opened, not one that replaced it
        _check_start(handle.read(8), path)
        handle.seek(0)
        yield handle


@contextmanager
def _in_memory(content: bytes, name: str) -> Iterator[BinaryIO]:
    """``content`` as a file, once it is known to be at most :data:`MAX_FILE_BYTES` and to start like a
    zip archive (as :func:`_opened` checks a file on disk)."""
    if len(content) > MAX_FILE_BYTES:
        raise DesignError(f"{name} is too large: {_megabytes(len(content))}; a design file is at most "
                          f"{_megabytes(MAX_FILE_BYTES)}")
    _check_start(content[:8], name)
    yield io.BytesIO(content)


def _check_start(start: bytes, path: Any) -> None:
    """A design file starts as a zip archive does; anything else is named (a PNG image, empty...)."""
    if not start.startswith(b"PK"):
        what = next((kind for magic, kind in _MAGIC.items() if start.startswith(magic)),
                    "empty" if not start else "not a NumPy .npz archive")
        raise DesignError(f"{path} is not a design file: it is {what}")


def _check_file(info: os.stat_result, path: Any) -> None:
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else "a pipe" if stat.S_ISFIFO(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode) else "a device")
        raise DesignError(f"cannot read design file {path}: it is {kind}, not a file")
    if info.st_size > MAX_FILE_BYTES:
        raise DesignError(f"{path} is too large: {_megabytes(info.st_size)} on disk; a design file is "
                          f"at most {_megabytes(MAX_FILE_BYTES)}")


def _design(archive: bounded_npz.Archive, path: Any) -> Design:
    _check_members(archive, path)
    described = _described(archive, path)
    steps = _steps(archive, described["steps_run"], path)
    patterns = _patterns(archive, len(steps), described["config"].lights_per_side, path)
    return Design(steps=steps, patterns=patterns, **described)


def _described(archive: bounded_npz.Archive, path: Any) -> dict:
    """What the header says, checked: the Design's fields but its arrays. Only what a design uses is
    kept, so the parsed header (up to :data:`MAX_HEADER_CHARS` of JSON) is gone before the arrays are read."""
    header = _header(archive, path)
    missing = [name for name in ARRAYS if name not in archive.arrays]
    if missing:
        raise DesignError(f"{path} is damaged: it has no {' or '.join(repr(m) for m in missing)} array")
    try:
        config = Config().replace(**_field(header, "config", dict, path))
    except ConfigError as exc:
        raise DesignError(f"{path}: its settings are refused: {exc}") from None
    goal = _field(header, "goal", dict, path)
    controller = header.get("controller", "")
    _check_name(config.shape, "its goal's name (the settings' shape)", path, MAX_NAME_CHARS)
    if "name" in goal:
        _check_name(goal["name"], "its goal's name", path, MAX_NAME_CHARS)
    _check_name(controller, "its controller's name", path, MAX_CONTROLLER_CHARS)
    _check_vertex_count(goal.get("given"), "its goal as given", path)
    _check_vertex_count(goal.get("vertices"), "its goal as fitted", path)
    steps_run = _field(header, "steps_run", int, path)
    if _field(header, "seed", int, path) != config.seed:
        raise DesignError(f"{path} is inconsistent: its seed {header['seed']} is not its settings' {config.seed}")
    _check_light_field(_field(header, "light_field", dict, path), config, path)
    result = header.get("result")
    return dict(config=config, shape=_vertices(goal.get("given"), path), steps_run=steps_run, controller=controller,
                goal=_fitted(goal, path), result=_result(result) if isinstance(result, dict) else {})


def _fitted(goal: dict, path: Any) -> dict:
    """The goal as fitted on the floor, as the header gives it: its vertices (a polygon, or None for the
    circle), centre and radius; nothing else is kept."""
    kept: dict = {}
    if "vertices" in goal:
        kept["vertices"] = _listed(_vertices(goal["vertices"], path))
    centre = goal.get("centre")
    if isinstance(centre, list) and len(centre) == 2 and all(_is_number(c) for c in centre):
        kept["centre"] = [float(c) for c in centre]
    if _is_number(goal.get("radius")):
        kept["radius"] = float(goal["radius"])
    return kept


def _result(result: dict) -> dict:
    """The run's end as the header gives it: its known keys, each a number, null or a short text."""
    def plain(value: Any) -> bool:
        return value is None or _is_number(value) or (isinstance(value, str) and len(value) <= MAX_NAME_CHARS)

    return {key: result[key] for key in RESULT_KEYS if key in result and plain(result[key])}


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_members(archive: bounded_npz.Archive, path: Any) -> None:
    """A header first (else it is some other archive), then nothing but a design's arrays, each once."""
    held = archive.arrays
    if "header" not in held:
        raise DesignError(f"{path} is not a design file: a NumPy archive without a header "
                          f"(it holds {', '.join(held[:5]) or 'nothing'})")
    stranger = next((name for name in archive.members if name[:-4] not in ARRAYS or not name.endswith(".npy")), None)
    if stranger is not None:
        raise DesignError(f"{path} is not a design file: it holds {stranger[:MAX_NAME_CHARS]!r} besides a design's "
                          f"arrays ({', '.join(ARRAYS)})")
    twice = next((name for name in held if held.count(name) > 1), None)
    if twice is not None:
        raise DesignError(f"{path} is damaged: it holds {twice!r} twice")


def _header(archive: bounded_npz.Archive, path: Any) -> dict:
    """The JSON header, refused from its array's header if it is longer than :data:`MAX_HEADER_CHARS`."""
    described = archive.header("header")
    if described.dtype.kind != "U" or described.shape != ():
        raise DesignError(f"{path} is not a design file: its header is not one JSON text")
    chars = described.dtype.itemsize // 4  # numpy's text is four bytes a character
    if chars > MAX_HEADER_CHARS:
        raise DesignError(f"{path} is too large: its header is {chars:,} characters of JSON; "
                          f"at most {MAX_HEADER_CHARS:,}")
    text = str(archive.read("header", MAX_HEADER_CHARS * 4))
    try:
        header = json.loads(text)
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


def _check_name(name: Any, what: str, where: Any, most: int) -> None:
    """A name the page shows: text on one line, at most ``most`` characters."""
    if not isinstance(name, str):
        raise DesignError(f"{where} is damaged: {what} is {type(name).__name__}, not text")
    if len(name) > most:
        raise DesignError(f"{where} is refused: {what} is {len(name):,} characters long; at most {most:,}")
    if _CONTROL.search(name):
        raise DesignError(f"{where} is refused: {what} holds a control character (a line break?); a name is one line")


def _check_vertex_count(vertices: Any, what: str, where: Any) -> None:
    """At most an upload's :data:`MAX_VERTICES`, counted before the list becomes an array."""
    if isinstance(vertices, (list, np.ndarray)) and len(vertices) > MAX_VERTICES:  # else not a polygon: said later
        raise DesignError(f"{where} is too large: {what} has {len(vertices):,} vertices; a goal has at most "
                          f"{MAX_VERTICES:,}")


def _check_pattern_count(count: int, where: Any) -> None:
    if count > MAX_PATTERNS:
        raise DesignError(f"{where} is too large: it holds {count:,} light patterns; a design holds at most "
                          f"{MAX_PATTERNS:,}")


def _check_pattern_bytes(shape: tuple[int, ...], itemsize: int, where: Any) -> None:
    count, rows, cols = shape
    unpacked = count * rows * cols * itemsize
    if unpacked > MAX_PATTERN_BYTES:
        raise DesignError(f"{where} is too large: its {count:,} patterns of {rows:,} x {cols:,} lights unpack to "
                          f"{unpacked:,} bytes; a design's patterns unpack to at most {MAX_PATTERN_BYTES:,} "
                          f"({MAX_PATTERNS:,} on / off patterns of {_DEFAULT.lights_per_side} x "
                          f"{_DEFAULT.lights_per_side} lights)")


def _check_light_field(grid: dict, config: Config, path: Any) -> None:
    expected = light_field(config)
    wrong = [key for key in ("rows", "cols", "pitch_m", "step_seconds") if grid.get(key) != expected[key]]
    if wrong:
        raise DesignError(f"{path} is inconsistent: its light field's {', '.join(wrong)} disagree with its settings")


def _steps(archive: bounded_npz.Archive, steps_run: int, path: Any) -> np.ndarray:
    described = archive.header("steps")
    if len(described.shape) != 1 or described.dtype.kind not in "iu" or described.shape[0] == 0:
        raise DesignError(f"{path} is damaged: 'steps' must be a list of whole steps, not {described.dtype} "
                          f"{described.shape}")
    _check_pattern_count(described.shape[0], path)
    steps = archive.read("steps", MAX_PATTERNS * 8)  # int64 at most
    if steps[0] != 0 or (np.diff(steps) < 0).any() or steps[-1] > steps_run:
        raise DesignError(f"{path} is inconsistent: the patterns' steps must start at 0 and never go back, "
                          f"within the {steps_run} steps run")
    return steps.astype(np.int64)


def _patterns(archive: bounded_npz.Archive, count: int, n: int, path: Any) -> np.ndarray:
    """The patterns, their shape and type checked from their header and their size bounded before they
    are read; their values then checked without a temporary array as large as they are."""
    described = archive.header("patterns")
    if described.shape != (count, n, n):
        raise DesignError(f"{path} is inconsistent: 'patterns' is {described.shape}; {count} steps on a "
                          f"{n} x {n} grid need ({count}, {n}, {n})")
    if described.dtype not in (np.dtype(np.uint8), np.dtype(np.float64)):
        raise DesignError(f"{path} is damaged: 'patterns' must be uint8 0 / 1 or float64 intensities, finite "
                          f"and not negative")
    _check_pattern_bytes(described.shape, described.dtype.itemsize, path)
    patterns = archive.read("patterns", MAX_PATTERN_BYTES)
    if patterns.dtype == np.uint8:
        if patterns.size and patterns.max() > 1:
            raise DesignError(f"{path} is damaged: on / off patterns hold values other than 0 and 1")
        return patterns
    if patterns.size and not (patterns.min() >= 0 and patterns.max() < math.inf):  # a NaN fails both
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


def _megabytes(n: int) -> str:
    return f"{n / 1_000_000:,.1f} MB"


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__

