"""What the app can ask of a simulation runner: one frozen dataclass per command, with what it does.
Made on any thread; carried out on the runner's thread (the simulation thread, or the child's loop).

A command is written once, here: its fields, and :meth:`Command.carry_out`, what it does to the
world when the runner that owns the world (:class:`~sandbox.app.world.runner.Runner`) carries it out.
Whoever wants it done submits it (:meth:`SimulationRunner.submit
<sandbox.app.world.contract.SimulationRunner.submit>`) and gets a :class:`concurrent.futures.Future`
of its answer; the process runner (:class:`~sandbox.app.world.child.ProcessRunner`) sends the same
object to its child process, whose Runner carries it out. A new command is one class here.

There are two kinds:

- a command proper runs in the simulation thread between steps (it touches the world); its future
  holds what ``carry_out`` returned, or what it raised;
- a :class:`Control` acts at once, on the thread that submits it, and does not touch the world (play,
  speed, hold, cancel a build): the simulation loop reads what it set at its next frame. Its future is
  done at once. Most controls are a :class:`Setting`: they set a field of the runner's
  :class:`Controls`, of which the process runner keeps a copy (what the app reads back, and what a
  restarted child gets). Only settings write the controls: the loop reads them.

A :class:`Build` (a new world, a run to the end) may take long: it reports its progress, and a
:class:`CancelBuild` that names its :attr:`Build.build` stops it, whether it came while the build ran
or while it waited its turn; a cancel of a build that is over does nothing.

``carry_out`` runs on the simulation thread (a control's on the submitting thread) and uses only what
:class:`World` lists: what the Runner offers its commands (its section "for the commands").
"""

from __future__ import annotations

import itertools
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, NamedTuple, Protocol

from sandbox.app.world.snapshot import DESIGN_PROGRAM, LAMP_PROGRAM, PAPER_PROGRAM

#: The goal a build announces when it builds around the running goal (see ``Runner.on_build``).
SAME_GOAL = "the running goal"


class RunnerStopped(RuntimeError):
    """The runner was stopped before it could carry out a command."""


class BuildCancelled(Exception):
    """Building a new world was stopped by the user."""


class World(Protocol):
    """What a command may use of the runner that carries it out (:class:`~sandbox.app.world.runner.Runner`,
    its section "for the commands"), on the simulation thread."""

    sim: Any  #: the Simulation
    controls: "Controls"
    pending: dict  #: changes waiting for a reset
    program_name: str
    shape_name: str
    program_time_limit: float
    chart_every: int
    recorder: Any  #: the running world's PatternRecorder

    @property
    def settings(self) -> Any: ...  # the running Config with the changes waiting for a reset
    @property
    def world_key(self) -> int: ...
    def announcing(self, config: Any, goal: Any, seed: int | None) -> AbstractContextManager[None]: ...
    def under_way(self, build: int) -> AbstractContextManager[Callable[[float], None]]: ...
    def cancelled(self, build: int) -> bool: ...
    def stop_if_cancelled(self, build: int) -> None: ...
    def cancel(self, build: int) -> None: ...
    def report_progress(self, fraction: float | None) -> None: ...
    def new_world(self) -> int: ...
    def new_goal(self) -> None: ...
    def ran_ahead(self) -> None: ...
    def step(self, n: int | None = None) -> None: ...
    def record_series(self, force: bool = False) -> None: ...
    def snapshot(self) -> None: ...
    def wake(self) -> None: ...
    def start(self) -> Any: ...
    def lift_halt(self) -> None: ...


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

    def carry_out(self, runner: World) -> Any:
        """Do it to ``runner``'s world; what it returns is the answer."""
        raise NotImplementedError(f"{type(self).__name__} says nothing of what it does")


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

    def carry_out(self, runner: World) -> None:
        self.settle(runner.controls)
        if self.wakes:
            runner.wake()


_build_ids = itertools.count(1)


def _next_build() -> int:
    return next(_build_ids)


@dataclass(frozen=True)
class Build(Command):
    """A command that may take long, reports its progress and may be cancelled: a :class:`CancelBuild`
    that names :attr:`build` stops it. Made in the app's process, so the ids of one runner's builds
    differ."""

    #: Which build this is (the :class:`CancelBuild` that stops it names it).
    build: int = field(default_factory=_next_build, kw_only=True)


# ------------------------------------------------------------------ commands
@dataclass(frozen=True)
class Apply(Command):
    """``function(sim)``: any function of the simulation (for a process runner, a picklable one: a
    module-level function or a ``functools.partial`` of one)."""

    function: Callable[[Any], Any]

    def carry_out(self, runner: World) -> Any:
        return self.function(runner.sim)


@dataclass(frozen=True)
class Reset(Build):
    """Build the world again with the changes waiting for a reset; ``seed`` None keeps the seed. Answers
    the new world's key (its frames' ``world_key``: a frame of an older world may still come after the
    answer, from a reset asked for earlier). Cancelled, it raises :class:`BuildCancelled` and the old
    world goes on."""

    seed: int | None = None

    def carry_out(self, runner: World) -> int:
        settings = runner.settings
        seed = settings.seed if self.seed is None else int(self.seed)
        with runner.under_way(self.build) as progress:
            runner.stop_if_cancelled(self.build)  # a cancel that came while it waited its turn counts
            with runner.announcing(settings, SAME_GOAL, seed):
                runner.sim.reset(self.seed, config=settings, progress=progress)
        runner.pending = {}
        return runner.new_world()


@dataclass(frozen=True, eq=False)
class SetShape(Command):
    """Change the goal (vertices as drawn, or None for the circle); answers the notes about its fit."""

    vertices: Any
    name: str

    def carry_out(self, runner: World) -> list[str]:
        sim = runner.sim
        with runner.announcing(sim.config, self.vertices, sim.seed):
            notes = sim.set_shape(self.vertices, name=self.name)
        runner.shape_name = self.name
        runner.new_goal()
        return notes


@dataclass(frozen=True)
class SetOutline(Command):
    """Choose the outline family; answers the notes about the goal."""

    outline: str

    def carry_out(self, runner: World) -> list[str]:
        sim = runner.sim
        with runner.announcing(sim.config.replace(outline=self.outline), SAME_GOAL, sim.seed):
            notes = sim.set_outline(self.outline)
        runner.new_goal()  # an offset goal may have moved
        return notes


@dataclass(frozen=True)
class UpdateConfig(Command):
    """Change parameters (the strategies too): the live ones at once, the others at the next reset.
    Answers (names waiting for a reset, the settings with them)."""

    changes: dict = field(default_factory=dict)

    def carry_out(self, runner: World) -> tuple[list[str], Any]:
        changes = self.changes
        deferred = runner.sim.update_config(**changes)
        # Checked together with what is already waiting (a profile change resets the values it bundles).
        settings = runner.sim.config.replace(**{**runner.pending, **{k: changes[k] for k in deferred}})
        runner.pending = {k: getattr(settings, k) for k in {*runner.pending, *deferred}}
        return sorted(runner.pending), settings


@dataclass(frozen=True)
class SetProgram(Command):
    """Light the floor with a program ``path.py:Class`` (None: the paper's controller), keeping the world;
    answers its name. One that cannot be loaded or started is refused and the running one stays."""

    spec: str | None

    def carry_out(self, runner: World) -> str:
        from sandbox.model.programs import load_program

        spec = self.spec
        runner.sim.use_program(load_program(spec, time_limit=runner.program_time_limit) if spec else None)
        runner.program_name = spec or PAPER_PROGRAM
        return runner.program_name


@dataclass(frozen=True)
class SetLamp(Command):
    """Be the light: move the lamp to ``centre`` (the lights within ``radius`` metres on, the others
    off), or paint or erase there (``mode``: see :mod:`sandbox.model.lamp`), keeping the world; None
    hands the lights back to the paper's controller. Answers the name of what lights the floor."""

    centre: tuple[float, float] | None
    radius: float | None = None
    mode: str = "lamp"

    def carry_out(self, runner: World) -> str:
        from sandbox.model.lamp import Lamp

        sim = runner.sim
        lamp = sim.user_program if isinstance(sim.user_program, Lamp) else None
        if self.centre is None:
            if lamp is not None:
                sim.use_program(None)
                runner.program_name = PAPER_PROGRAM
            return runner.program_name
        if lamp is None:
            lamp = Lamp()
            sim.use_program(lamp)
            runner.program_name = LAMP_PROGRAM
        lamp.aim(*self.centre, self.radius, self.mode)
        return runner.program_name


@dataclass(frozen=True)
class WorldSpec(Command):
    """Answers (config, seed, goal vertices as given or None): what builds the running world again
    elsewhere (a challenge's reference run)."""

    def carry_out(self, runner: World) -> tuple:
        sim = runner.sim
        shape = None if sim.shape_vertices is None else sim.shape_vertices.copy()
        return sim.config, sim.seed, shape


@dataclass(frozen=True)
class StepOnce(Command):
    """Advance ``n`` steps now (paused)."""

    n: int = 1

    def carry_out(self, runner: World) -> None:
        runner.step(int(self.n))


@dataclass(frozen=True)
class RunTo(Command):
    """Step until the world is at ``step`` (nothing if it is there or past): two paused worlds in compare
    mode end on the same step."""

    step: int

    def carry_out(self, runner: World) -> None:
        if runner.sim.steps_done < self.step:
            runner.step(self.step - runner.sim.steps_done)


#: Steps between two progress reports of a skip ahead: 0.2-0.5 s of stepping; each report costs a message.
SKIP_CHUNK = 2000


@dataclass(frozen=True)
class SkipAhead(Build):
    """Run to ``step`` without frames, as fast as the world steps headless (*Run to the end*), telling
    the progress listeners how far it got; a :class:`CancelBuild` stops it where it is. Answers an
    :class:`Arrival`."""

    step: int

    def carry_out(self, runner: World) -> "Arrival":
        """Step in chunks of :data:`SKIP_CHUNK` with no snapshot between them (the chart's samples are
        kept), telling the progress listeners after each; stop early when cancelled (a cancel that came
        while it waited its turn counts: the page's Cancel shows from the moment it is asked)."""
        sim = runner.sim
        start, target = sim.steps_done, int(self.step)
        cancelled = False
        # The state it starts from, shown while it runs: after a reset taken in the same turn (Use and run to
        # the end), the pages would otherwise show the old world until the end.
        runner.snapshot()
        with runner.under_way(self.build):
            while sim.steps_done < target:
                if runner.cancelled(self.build):
                    cancelled = True
                    break
                chunk_end = min(sim.steps_done + SKIP_CHUNK, target)
                while sim.steps_done < chunk_end:  # the chart's samples as a live run takes them
                    runner.step(min(runner.chart_every, chunk_end - sim.steps_done))
                    runner.record_series()
                runner.report_progress((sim.steps_done - start) / max(target - start, 1))
        runner.record_series(force=True)
        runner.ran_ahead()
        return Arrival(sim.steps_done, cancelled, runner.world_key)


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

    def carry_out(self, runner: World) -> Any:
        return runner.recorder.design(runner.sim, controller=runner.program_name)


@dataclass(frozen=True)
class PlayDesign(Command):
    """A new world from the design's settings, goal and seed, lit by its recorded light program
    (``serve --design``); answers the name of what lights the floor."""

    design: Any

    def carry_out(self, runner: World) -> str:
        from sandbox.model.design import Replay

        design, sim = self.design, runner.sim
        with runner.announcing(design.config, design.shape, design.seed):
            sim.set_shape(design.shape, name=design.config.shape)
            sim.use_program(Replay(design))
            runner.pending = {}
            sim.reset(design.seed, config=design.config)
        runner.shape_name = design.config.shape
        runner.program_name = DESIGN_PROGRAM
        runner.new_world()
        return runner.program_name


# ------------------------------------------------------------------ controls
@dataclass(frozen=True)
class Start(Control):
    """Start the simulation loop (a process runner's child waits for it)."""

    def carry_out(self, runner: World) -> None:
        runner.start()


@dataclass(frozen=True)
class CancelBuild(Control):
    """Stop the :class:`Build` ``build``: a world being built by a reset (the old world goes on), or a
    skip ahead (the world stays where it got to). Nothing if that build is over."""

    build: int

    def carry_out(self, runner: World) -> None:
        runner.cancel(self.build)


@dataclass(frozen=True)
class SetPlaying(Setting):
    playing: bool

    def settle(self, controls: Controls) -> None:
        controls.playing = bool(self.playing)

    def carry_out(self, runner: World) -> None:
        Setting.carry_out(self, runner)
        runner.lift_halt()  # after: whoever owns play has heard of a frame that failed, and decided


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
