"""Compare mode (issue 25, item 1): a second world beside the running one.
Runs on the app's event thread; a frame, on its runner's thread, only posts to it.

The two worlds start from the same seed, so the same robots and boxes, and
differ only in what the user picked (strategies, goal, outline, profile or
light program). Each runs in its own simulation process, so both cores
work; :class:`Lockstep` holds them on the same step (see its docstring).
The compared world is drawn to the right of the running one (or below it,
for a page taller than wide), in the same scene (so a recording holds
both), with its own caption and share in the goal, and the difference
between the two between them; the Metrics charts carry its curves too.

- :func:`partner_config` makes the compared world's settings from the running
  world's and a paper case's name;
- :class:`Lockstep` is what play, pause, step, reset, speed and Cancel act on, on the app's event thread;
- :class:`~sandbox.app.view.partner.Comparison` (in the view) starts and stops the compared world and
  draws it.
"""

from __future__ import annotations

from concurrent.futures import Future
from pathlib import Path
from typing import Any, Callable

from sandbox.app.world.orders import (Build, CancelBuild, Hold, Reset, RunTo, SetPlaying, SetSpeed, ShowEvery,
                                      SkipAhead, StepOnce)
from sandbox.app.world.runner import FASTEST, FASTEST_CHUNK
from sandbox.app.world.snapshot import Snapshot, case_name, running_case
from sandbox.model.config import CASES, STRATEGIES, Config, ConfigError, read_config_values

#: What the second world may be: a paper case, or the star with the closed loop (Learn's *Show me*
#: for chase; not one of the paper's cases).
COMPARE_CASES: dict[str, dict[str, Any]] = {**CASES, "star + chase": dict(shape="star", chase=2.0)}
#: The choice that compares the running world with itself under the paper's controller: the player's
#: lamp (Be the light, a challenge) or a light program against the paper.
SAME = "the same, with the paper's lights"


def partner_config(base: Config, choice: str) -> Config:
    """The compared world's settings: ``base`` with a case's goal and strategies (every other strategy
    off) and the outline the goal calls for, as picking a paper case does; or ``base`` itself for
    :data:`SAME`."""
    if choice == SAME:
        return base
    if choice not in COMPARE_CASES:
        raise ConfigError(f"cannot compare with {choice!r}: one of {', '.join(COMPARE_CASES)}, or {SAME!r}")
    return base.replace(**{**{s.name: 0.0 for s in STRATEGIES}, "outline": "auto", **COMPARE_CASES[choice]})


def side_config(spec: str, base: Config) -> Config:
    """One side of ``serve --compare``: a paper case's name, or a TOML or JSON file of values over
    ``base``."""
    if spec in COMPARE_CASES:
        return partner_config(base, spec)
    if not Path(spec).is_file():
        raise ConfigError(f"--compare takes two case names ({', '.join(COMPARE_CASES)}) or config files; "
                          f"{spec!r} is neither")
    return base.replace(**read_config_values(spec))


def side_name(snap: Snapshot) -> str:
    """A world's short name for a chart's legend: the paper's case, else its goal and strategies."""
    name = running_case(snap.shape_name, snap.strategies, snap.family) or case_name(snap.shape_name,
                                                                                   snap.strategies)
    return name if len(name) <= 28 else name[:27] + "…"


#: How many frames one world may step ahead of the slower (0.2 s of the page's time at 30 frames a
#: second). A world that reaches the target waits until the other's next frame has reached this process
#: and, on the app's event queue, raised it: a round trip through both processes and the queue, which on
#: a busy machine (the browser drawing in software takes a core of two) outlasts two frames. Six instead
#: of two: 23.6x per world against 22.5x at the default speed, star against star-switch (3 runs each,
#: alternating, one browser).
LEAD_FRAMES = 6


class Lockstep:
    """What play, pause, step, reset and speed act on: the running world and, in compare mode, the
    compared one too, held on the same step.

    Playing, both worlds may step up to a target step (:class:`~sandbox.app.world.orders.Hold`)
    :data:`LEAD_FRAMES` frames ahead of the slower one; each frame of either raises it. So neither runs
    more than that ahead of the other, and the slower sets the pace. Pausing stops raising the target and
    brings both to it (:class:`~sandbox.app.world.orders.RunTo`): paused, the two are on the same step; a
    Step moves both by the same steps; a reset holds both at step 0 until both new worlds are built.

    Runs on the app's event thread (``events``, :mod:`sandbox.app.web.events`), and owns its state
    there: the worlds' frames come on their runners' threads and only post the raise of the target to
    the queue; the runners' answers come through the runners' ``deliver``, the same queue. No lock."""

    def __init__(self, main: Any, events: Any):
        self.main = main
        self.partner: Any = None
        self._events = events
        self._target = 0
        #: Each world's snapshot at every this many frames (sandbox.app.web.pacing.frames_per_snapshot).
        self.shown_every = 1
        #: World keys of the worlds being replaced by a reset: their frames do not raise the target.
        self._stale: dict[int, int] = {}
        #: The builds asked through here that Cancel may stop: (world, build id, its future).
        self._builds: list[tuple[Any, int, Future]] = []
        main.subscribe(self._frame_came)

    def _frame_came(self, snap: Any) -> None:
        """A frame of either world (on its runner's thread): raise the target on the event thread (only
        the newest of these waits there)."""
        self._events.post_latest(self, self._advance)

    # ------------------------------------------------------------ pairing
    def pair(self, partner: Any) -> None:
        """Hold ``partner`` (a new world at step 0, paused) in step with the running world, which it
        restarts from step 0 too (``reset`` afterwards)."""
        self.partner = partner
        partner.submit(SetSpeed(self.main.steps_per_frame))
        partner.submit(ShowEvery(self.shown_every))
        partner.subscribe(self._frame_came)

    def unpair(self) -> Any:
        """The running world goes on alone; returns the partner (to be stopped)."""
        partner, self.partner = self.partner, None
        self._stale.clear()
        self._builds = [build for build in self._builds if build[0] is not partner]
        self.main.submit(Hold(None))
        return partner

    @property
    def sides(self) -> tuple:
        return (self.main,) if self.partner is None else (self.main, self.partner)

    # ------------------------------------------------------------ controls
    @property
    def playing(self) -> bool:
        return self.main.playing

    @property
    def target(self) -> int:
        """The step both worlds may reach; paused, the step both stop on."""
        return self._target

    def set_playing(self, playing: bool) -> None:
        if self.partner is None:
            self.main.submit(SetPlaying(playing))
            return
        for side in self.sides:
            side.submit(SetPlaying(playing))
        if not playing:  # both to the step either may have reached
            for side in self.sides:
                side.ask(RunTo(self._target))
        else:
            self._advance()

    def step_once(self, n: int = 1) -> None:
        if self.partner is None:
            self.main.ask(StepOnce(int(n)))
            return
        self._target += int(n)
        for side in self.sides:
            side.ask(RunTo(self._target))

    def set_speed(self, steps_per_frame: int) -> None:
        for side in self.sides:
            side.submit(SetSpeed(int(steps_per_frame)))

    def show_every(self, frames: int) -> None:
        """A snapshot of each world at every ``frames``-th frame only (the pages draw no more); sent to
        the worlds when it changes."""
        if frames == self.shown_every:
            return
        self.shown_every = frames
        for side in self.sides:
            side.submit(ShowEvery(frames))

    def cancel(self) -> None:
        """Stop the builds asked through here that are not over (the Cancel button): a new world being
        built, a run to the end (both worlds'). Each cancel names its build: one that ended meanwhile
        stays ended, and no later build is touched."""
        self._builds = [build for build in self._builds if not build[2].done()]
        for side, build, _ in self._builds:
            side.submit(CancelBuild(build))

    def _build(self, side: Any, command: Build, on_done: Callable[[Any], None] | None,
               on_error: Callable[[BaseException], None] | None, cancellable: bool = True) -> None:
        """Ask ``side`` for ``command``; a cancellable one is what :meth:`cancel` stops."""
        future = side.ask(command, on_done, on_error)
        if cancellable:
            self._builds = [build for build in self._builds if not build[2].done()]
            self._builds.append((side, command.build, future))

    def skip_ahead(self, step: int, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> None:
        """Both worlds to ``step`` without frames (*Run to the end*); ``on_done`` hears the running world's
        (step reached, cancelled) once both are there. A cancel stops both, maybe a few steps apart:
        both then go on to the farther one's step."""
        command = SkipAhead(int(step))
        partner = self.partner
        if partner is None:
            self._build(self.main, command, on_done, on_error)
            return
        self._target = int(step)
        for side in self.sides:
            side.submit(Hold(self._target))
        answers: dict[int, Any] = {}

        def arrived(side: Any, result: Any) -> None:
            answers[id(side)] = result
            if len(answers) < 2:
                return
            reached = max(r.step for r in answers.values())  # a cancel may stop them apart: on to the farther
            self._target = reached
            for s in self.sides:
                s.submit(Hold(reached))
                if not self.main.playing:
                    s.ask(RunTo(reached))
            self._advance()
            if on_done:
                on_done(answers[id(self.main)])

        for side in (self.main, partner):  # one build on both: one cancel stops both
            self._build(side, command, lambda result, side=side: arrived(side, result), on_error)

    def reset(self, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> None:
        """Both worlds again (``seed`` None: each its own seed, the same one): the running world first,
        then, once it is built, the compared one, both held at step 0 meanwhile. ``on_done`` hears the
        running world's result once both are built. If the running world's reset is refused or
        cancelled, the compared world is left as it was and both go on from where they were
        (``on_error`` hears why). Cancel stops the running world's build only: once it is built, the
        compared one follows it."""
        partner = self.partner
        if partner is None:
            self._build(self.main, Reset(seed), on_done, on_error)
            return
        self._target = 0
        for side in self.sides:
            side.submit(Hold(0))
            self._stale[id(side)] = side.latest.world_key

        def main_built(result: Any) -> None:
            self._build(partner, Reset(seed), lambda _: both_built(result), failed, cancellable=False)

        def both_built(result: Any) -> None:
            self._advance()
            if on_done:
                on_done(result)

        def main_refused(exc: BaseException) -> None:
            # Neither world changed: on from their steps (held where they were).
            self._stale.clear()
            self._target = max(side.latest.step for side in self.sides)
            if self.main.playing:
                # Held at the farther world's step, not at the 0 of the refused reset: _advance raises
                # the holds only above the target, and the worlds' last frames may lie further apart
                # than its lead (then both stayed held at 0, and stopped).
                for side in self.sides:
                    side.submit(Hold(self._target))
                self._advance()
            else:
                for side in self.sides:
                    side.ask(RunTo(self._target))
            failed(exc)

        def failed(exc: BaseException) -> None:
            if on_error:
                on_error(exc)

        self._build(self.main, Reset(seed), main_built, main_refused)

    # ------------------------------------------------------------ pacing
    def _lead(self) -> int:
        """How far ahead of the slower world the target lies: :data:`LEAD_FRAMES` frames' steps."""
        spf = self.main.steps_per_frame
        if spf < FASTEST:
            return LEAD_FRAMES * spf
        return max(2 * FASTEST_CHUNK, int(LEAD_FRAMES * self.main.steps_per_second() / max(self.main.fps, 1.0)))

    def _advance(self) -> None:
        """A frame came: playing, raise the target to a lead ahead of the slower world."""
        partner = self.partner
        if partner is None or not self.main.playing:
            return
        snaps = (self.main.latest, partner.latest)
        for side, snap in zip(self.sides, snaps):
            if self._stale.get(id(side)) == snap.world_key:
                return  # its new world is still being built
            self._stale.pop(id(side), None)
        target = min(snap.step for snap in snaps) + self._lead()
        if target > self._target:
            self._target = target
            for side in self.sides:
                side.submit(Hold(target))
