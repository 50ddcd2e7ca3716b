"""What the app can ask of a simulation runner: one frozen dataclass per command.

A command is data. The runner in this process (:class:`~sandbox.app.world.runner.Runner`) carries every
command out in one place, ``Runner.handle``; the process runner
(:class:`~sandbox.app.world.child.ProcessRunner`) sends the command as it is to its child process, whose
Runner handles it, and the answer comes back. Whoever submits a command gets a
:class:`concurrent.futures.Future` of its answer (:meth:`SimulationRunner.submit
<sandbox.app.world.contract.SimulationRunner.submit>`); a new command is one class here and one handler in
the Runner.

There are two kinds:

- a command proper runs in the simulation thread between steps (it touches the world); its future
  holds what it returned, or what it raised;
- a :class:`Control` acts at once, on the thread that submits it, and does not touch the world (play,
  speed, hold, cancel a build): the simulation loop reads what it set at its next frame. Its future is
  done at once. Most controls are a :class:`Setting`: they set a field of the runner's
  :class:`Controls`, of which the process runner keeps a copy (what the app reads back, and what a
  restarted child gets).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, NamedTuple


class RunnerStopped(RuntimeError):
    """The runner was stopped before it could carry out a command."""


@dataclass
class Controls:
    """What the controls set: read by the simulation loop at each frame, and by the app."""

    playing: bool = True
    steps_per_frame: int = 10
    #: The robots the viewers follow: the snapshots carry their photocells (``Snapshot.followed``).
    followed: tuple[int, ...] = ()
    #: Whether snapshots carry the luminosity field (costly: only for the heat map).
    want_field: bool = False
    #: Playing, the world steps no further than this step (None: no limit); compare mode holds two worlds
    #: in lockstep with it (sandbox.app.world.lockstep).
    hold_at: int | None = None
    #: A snapshot every this many frames (1: every frame): no page draws more (sandbox.app.web.pacing).
    show_every: int = 1

    def settings(self) -> list["Setting"]:
        """The settings that bring a fresh runner's controls to these (a restarted child's)."""
        return [SetPlaying(self.playing), SetSpeed(self.steps_per_frame), Follow(self.followed),
                WantField(self.want_field), Hold(self.hold_at), ShowEvery(self.show_every)]


@dataclass(frozen=True)
class Command:
    """Runs in the simulation thread between steps; its future gets what it returns or raises."""

    #: Whether it acts at once on the submitting thread (a :class:`Control`) rather than between steps.
    at_once: ClassVar[bool] = False


@dataclass(frozen=True)
class Control(Command):
    """Acts at once, without the world; its future is done when it has acted (or been sent)."""

    at_once: ClassVar[bool] = True


@dataclass(frozen=True)
class Setting(Control):
    """A control that sets a field of :class:`Controls`."""

    #: Whether the simulation loop should run now rather than at its next frame.
    wakes: ClassVar[bool] = True

    def settle(self, controls: Controls) -> None:
        raise NotImplementedError


# ------------------------------------------------------------------ commands
@dataclass(frozen=True)
class Apply(Command):
    """``function(sim)``: any function of the simulation (for a process runner, a picklable one: a
    module-level function or a ``functools.partial`` of one)."""

    function: Callable[[Any], Any]


@dataclass(frozen=True)
class Reset(Command):
    """Build the world again with the changes waiting for a reset; ``seed`` None keeps the seed."""

    seed: int | None = None


@dataclass(frozen=True, eq=False)
class SetShape(Command):
    """Change the goal (vertices as drawn, or None for the circle); answers the notes about its fit."""

    vertices: Any
    name: str


@dataclass(frozen=True)
class SetOutline(Command):
    """Choose the outline family; answers the notes about the goal."""

    outline: str


@dataclass(frozen=True)
class UpdateConfig(Command):
    """Change parameters: the live ones at once, the others at the next reset. Answers (names waiting
    for a reset, the settings with them)."""

    changes: dict = field(default_factory=dict)


@dataclass(frozen=True)
class SetProgram(Command):
    """Light the floor with a program ``path.py:Class`` (None: the paper's controller); answers its name."""

    spec: str | None


@dataclass(frozen=True)
class SetLamp(Command):
    """Be the light: move the lamp to ``centre``, or paint or erase there (``mode``); None hands the
    lights back. Answers the name of what lights the floor."""

    centre: tuple[float, float] | None
    radius: float | None = None
    mode: str = "lamp"


@dataclass(frozen=True)
class WorldSpec(Command):
    """Answers (config, seed, goal vertices as given or None): what builds the running world again."""


@dataclass(frozen=True)
class StepOnce(Command):
    """Advance ``n`` steps now (paused)."""

    n: int = 1


@dataclass(frozen=True)
class RunTo(Command):
    """Step until the world is at ``step`` (nothing if it is there or past)."""

    step: int


@dataclass(frozen=True)
class SkipAhead(Command):
    """Run to ``step`` without frames, as fast as the world steps headless (*Run to the end*), telling
    the progress listeners how far it got; a :class:`CancelBuild` stops it where it is. Answers an
    :class:`Arrival`."""

    step: int


class Arrival(NamedTuple):
    """Where a :class:`SkipAhead` got to: the step reached, whether it was cancelled, and in which world
    (its frames' ``world_key``). The world is named because the answer can come before any frame of it:
    a reset then a run to the end publish no frame between them."""

    step: int
    cancelled: bool
    world_key: int


@dataclass(frozen=True)
class DesignOf(Command):
    """Answers the running world's design (sandbox.model.design): its goal, settings, seed and the
    light program it has run so far, every pattern with the step it started."""


@dataclass(frozen=True)
class PlayDesign(Command):
    """A new world from the design's settings, goal and seed, lit by its recorded light program."""

    design: Any


# ------------------------------------------------------------------ controls
@dataclass(frozen=True)
class Start(Control):
    """Start the simulation loop (a process runner's child waits for it)."""


@dataclass(frozen=True)
class CancelBuild(Control):
    """Stop a world being built by a reset (the old world goes on), or a skip ahead (the world stays
    where it got to)."""


@dataclass(frozen=True)
class SetPlaying(Setting):
    playing: bool

    def settle(self, controls: Controls) -> None:
        controls.playing = bool(self.playing)


@dataclass(frozen=True)
class SetSpeed(Setting):
    steps_per_frame: int
    wakes: ClassVar[bool] = False

    def settle(self, controls: Controls) -> None:
        controls.steps_per_frame = max(1, int(self.steps_per_frame))


@dataclass(frozen=True)
class Follow(Setting):
    """Carry these robots' photocells, commands and charge in the snapshots (the inspectors' robots)."""

    robots: tuple[int, ...]

    def settle(self, controls: Controls) -> None:
        controls.followed = tuple(sorted({int(i) for i in self.robots}))


@dataclass(frozen=True)
class WantField(Setting):
    on: bool

    def settle(self, controls: Controls) -> None:
        controls.want_field = bool(self.on)


@dataclass(frozen=True)
class ShowEvery(Setting):
    """Take a snapshot at every ``frames``-th frame only; the world steps on the same schedule. The
    pages decide it: when every one draws fewer frames than are sent, the rest are not worth taking
    (sandbox.app.web.pacing.frames_per_snapshot)."""

    frames: int
    wakes: ClassVar[bool] = False

    def settle(self, controls: Controls) -> None:
        controls.show_every = max(1, int(self.frames))


@dataclass(frozen=True)
class Hold(Setting):
    """Playing, step no further than ``step`` (None: no limit). Taken at the next frame: waking the
    loop would run a frame early, and compare mode moves the limit at every frame."""

    step: int | None
    wakes: ClassVar[bool] = False

    def settle(self, controls: Controls) -> None:
        controls.hold_at = None if self.step is None else int(self.step)
