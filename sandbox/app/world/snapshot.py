"""A snapshot: everything a picture of the simulation needs, copied between
steps so that the page (or a recording) can keep it while the simulation
goes on. Runners make them; the scene, the panel and the GIF / MP4 frames
read them. Made on the simulation thread, immutable, read on any thread."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from sandbox.model.config import Config
from sandbox.model.metrics import Sample


#: What lights the floor, as snapshots name it: the paper's controller, a person's lamp (the Be the light
#: folder), a design's recorded light program (serve --design), or else a light program's path:Class.
PAPER_PROGRAM = "the paper's controller"
LAMP_PROGRAM = "a lamp you move (Be the light)"
DESIGN_PROGRAM = "the design's recorded light program"


@dataclasses.dataclass(frozen=True)
class RobotView:
    """What the inspector shows about one robot."""

    index: int
    position: np.ndarray
    heading: float
    sensors: np.ndarray  # the four photocells (robots.PHOTOCELLS order) at the last refresh
    sensor_points: np.ndarray  # (4, 2)
    command: np.ndarray  # held (v, w)
    applied: np.ndarray  # (v, w) actually applied (0 when out of charge)
    charge: float


@dataclasses.dataclass(frozen=True)
class Snapshot:
    """A consistent copy of everything the page draws, taken between steps."""

    frame: int
    step: int
    time: float
    phase: str
    cycle: int
    seed: int
    shape_name: str
    world_config: Config  # what the running world was built with
    config: Config  # the current settings (may hold values pending a reset)
    robot_positions: np.ndarray
    robot_headings: np.ndarray
    robot_charges: np.ndarray
    box_positions: np.ndarray
    box_angles: np.ndarray
    box_in_goal: np.ndarray
    lights_key: tuple  # changes whenever the light pattern (or the world) changes
    intensities: np.ndarray
    field: np.ndarray | None  # sensed luminosity on a display grid, float32 [ix, iy]; only when asked for
    outline: np.ndarray
    goal_key: int  # changes whenever the goal changes
    goal_outline: np.ndarray
    goal_vertices: np.ndarray | None  # the fitted polygon (None for the circle)
    sample: Sample
    strategies: dict  # flare, switch, no_corners as the controller applies them now
    playing: bool
    steps_per_frame: int
    steps_per_second: float
    #: The robots some viewer follows, in the order of ``Runner.followed`` (each viewer follows its own).
    followed: tuple[RobotView, ...]
    #: What lights the floor: "the paper's controller" or a light program's path:Class.
    program: str = PAPER_PROGRAM
    #: (count, message) of the last light program that failed while running (the paper's took over).
    program_error: tuple[int, str] | None = None
    #: Changes with every new world (a reset): charts never join two worlds' samples.
    world_key: int = 0
    #: The outline family the band follows ('scaled' or 'offset') and why.
    family: str = "scaled"
    family_reason: str = ""
    #: The goal's sides beside which alone the band is lit now ('' the whole band; sandbox/model/gather.py).
    gathering: str = ""

    def robot(self, index: int | None) -> RobotView | None:
        """The followed robot ``index``, or None (not followed, or not in this world)."""
        return next((r for r in self.followed if r.index == index), None)


def case_name(shape: str, strategies: dict) -> str:
    """The goal and its strategies in words: the paper's case name when they
    are one of its seven cases, else e.g. ``heart + flare 1.5`` (a shape file by its name alone:
    ``K.txt``)."""
    from sandbox.model.config import STRATEGY_NAMES

    active = {name: float(strategies.get(name, 0.0)) for name in STRATEGY_NAMES if strategies.get(name, 0.0) > 0}
    # A shape file by its name alone: its folders pushed a phone's one-line caption off the screen.
    shown = shape.replace("\\", "/").rsplit("/", 1)[-1]
    described = " + ".join([shown, *(f"{k.replace('_', ' ')} {v:g}" for k, v in active.items())])
    name = running_case(shape, strategies)
    if name is None:
        return described
    return name if name == described else f"{name} ({described})"


def running_case(shape: str, strategies: dict, family: str = "scaled") -> str | None:
    """The paper's case that runs: its goal, exactly its strategies (the others off) and the paper's
    scaled outline; None when what runs is not one of the seven."""
    if family != "scaled":
        return None
    return _case_of(shape, tuple(sorted((k, float(v)) for k, v in strategies.items() if v > 0)))


@functools.lru_cache(maxsize=256)
def _case_of(shape: str, active: tuple) -> str | None:
    """:func:`running_case` of the strategies on (``active``: sorted (name, amount) pairs), remembered: the
    panel asks every frame (a class's desks: 30 pages at 10 frames a second)."""
    from sandbox.model.config import CASES, STRATEGY_NAMES

    on = {name: amount for name, amount in active if name in STRATEGY_NAMES}
    for name, case in CASES.items():
        if case["shape"] == shape and on == {k: float(v) for k, v in case.items() if k != "shape"}:
            return name
    return None


def caption(snap: Snapshot) -> str:
    """One line that says what a recorded frame shows: case, strategies and step, and what lights the
    floor: the paper's controller's phase and cycle, or the program (or person) lighting it instead."""
    return (f"{case_name(snap.shape_name, snap.strategies)} | step {snap.step:,} | {_lit_by(snap)}"
            f" | {100 * snap.sample.fraction_in_goal:.0f} % in goal")


def _lit_by(snap: Snapshot) -> str:
    if snap.program == PAPER_PROGRAM:
        # A band that gathers says so in one word: the panel's phase line names the sides, and the caption
        # keeps to one line on a phone.
        return f"{'gathering' if snap.gathering else snap.phase}, cycle {snap.cycle}"
    if snap.program == LAMP_PROGRAM:
        return "lit by your lamp"
    return f"lit by {snap.program.rsplit(':', 1)[-1]}"  # a light program's class
