"""Compare mode (issue 25, item 1): a second world beside the running one.

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
- :class:`Lockstep` is what play, pause, step, reset and speed act on;
- :class:`Comparison` starts and stops the compared world and draws it.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any, Callable

from sandbox.app.runner import FASTEST, FASTEST_CHUNK
from sandbox.app.scene import DIFFERENCE_HEIGHT, Z_TOP, SceneView, compare_offset, difference_anchor
from sandbox.app.snapshot import Snapshot, case_name, running_case
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
#: and raised it: a round trip through both processes, which on a busy machine (the browser drawing in
#: software takes a core of two) outlasts two frames. Six instead of two: 23.6x per world against 22.5x
#: at the default speed, star against star-switch (3 runs each, alternating, one browser).
LEAD_FRAMES = 6


class Lockstep:
    """What play, pause, step, reset and speed act on: the running world and, in compare mode, the
    compared one too, held on the same step.

    Playing, both worlds may step up to a target step (:meth:`Runner.hold`) :data:`LEAD_FRAMES`
    frames ahead of the slower one; each frame of either raises it. So neither runs more than that
    ahead of the other, and the slower sets the pace. Pausing stops raising the target and brings both to it
    (:meth:`Runner.run_to`): paused, the two are on the same step; a Step moves both by the same
    steps; a reset holds both at step 0 until both new worlds are built."""

    def __init__(self, main: Any):
        self.main = main
        self.partner: Any = None
        self._target = 0
        #: Each world's snapshot at every this many frames (sandbox.app.pacing.frames_per_snapshot).
        self.shown_every = 1
        #: World keys of the worlds being replaced by a reset: their frames do not raise the target.
        self._stale: dict[int, int] = {}
        self._lock = threading.RLock()
        main.subscribe(lambda snap: self._advance())

    # ------------------------------------------------------------ pairing
    def pair(self, partner: Any) -> None:
        """Hold ``partner`` (a new world at step 0, paused) in step with the running world, which it
        restarts from step 0 too (``reset`` afterwards)."""
        with self._lock:
            self.partner = partner
            partner.set_speed(self.main.steps_per_frame)
            partner.show_every(self.shown_every)
            partner.subscribe(lambda snap: self._advance())

    def unpair(self) -> Any:
        """The running world goes on alone; returns the partner (to be stopped)."""
        with self._lock:
            partner, self.partner = self.partner, None
            self._stale.clear()
            self.main.hold(None)
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
        with self._lock:
            if self.partner is None:
                self.main.set_playing(playing)
                return
            for side in self.sides:
                side.set_playing(playing)
            if not playing:  # both to the step either may have reached
                for side in self.sides:
                    side.run_to(self._target)
            else:
                self._advance()

    def step_once(self, n: int = 1) -> None:
        with self._lock:
            if self.partner is None:
                self.main.step_once(n)
                return
            self._target += int(n)
            for side in self.sides:
                side.run_to(self._target)

    def set_speed(self, steps_per_frame: int) -> None:
        for side in self.sides:
            side.set_speed(steps_per_frame)

    def show_every(self, frames: int) -> None:
        """A snapshot of each world at every ``frames``-th frame only (the pages draw no more); sent to
        the worlds when it changes."""
        with self._lock:
            if frames == self.shown_every:
                return
            self.shown_every = frames
            for side in self.sides:
                side.show_every(frames)

    def skip_ahead(self, step: int, *, on_done: Callable[[Any], None] | None = None,
                   on_error: Callable[[BaseException], None] | None = None) -> None:
        """Both worlds to ``step`` without frames (*Run to the end*); ``on_done`` hears the running world's
        (step reached, cancelled) once both are there. A cancel stops both, maybe a few steps apart:
        both then go on to the farther one's step."""
        with self._lock:
            partner = self.partner
            if partner is None:
                self.main.skip_ahead(step, on_done=on_done, on_error=on_error)
                return
            self._target = int(step)
            for side in self.sides:
                side.hold(self._target)
        answers: dict[int, Any] = {}

        def arrived(side: Any, result: Any) -> None:
            answers[id(side)] = result
            if len(answers) < 2:
                return
            reached = max(r.step for r in answers.values())  # a cancel may stop them apart: on to the farther
            with self._lock:
                self._target = reached
                for s in self.sides:
                    s.hold(reached)
                    if not self.main.playing:
                        s.run_to(reached)
            self._advance()
            if on_done:
                on_done(answers[id(self.main)])

        for side in (self.main, partner):
            side.skip_ahead(step, on_done=lambda result, side=side: arrived(side, result), on_error=on_error)

    def reset(self, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> None:
        """Both worlds again (``seed`` None: each its own seed, the same one): the running world first,
        then, once it is built, the compared one, both held at step 0 meanwhile. ``on_done`` hears the
        running world's result once both are built. If the running world's reset is refused or
        cancelled, the compared world is left as it was and both go on from where they were
        (``on_error`` hears why)."""
        with self._lock:
            partner = self.partner
            if partner is None:
                self.main.reset(seed, on_done=on_done, on_error=on_error)
                return
            self._target = 0
            for side in self.sides:
                side.hold(0)
                self._stale[id(side)] = side.latest.world_key

        def main_built(result: Any) -> None:
            partner.reset(seed, on_done=lambda _: both_built(result), on_error=failed)

        def both_built(result: Any) -> None:
            self._advance()
            if on_done:
                on_done(result)

        def main_refused(exc: BaseException) -> None:
            with self._lock:  # neither world changed: on from their steps (held where they were)
                self._stale.clear()
                self._target = max(side.latest.step for side in self.sides)
                if self.main.playing:
                    # Held at the farther world's step, not at the 0 of the refused reset: _advance raises
                    # the holds only above the target, and the worlds' last frames may lie further apart
                    # than its lead (then both stayed held at 0, and stopped).
                    for side in self.sides:
                        side.hold(self._target)
                    self._advance()
                else:
                    for side in self.sides:
                        side.run_to(self._target)
            failed(exc)

        def failed(exc: BaseException) -> None:
            if on_error:
                on_error(exc)

        self.main.reset(seed, on_done=main_built, on_error=main_refused)

    # ------------------------------------------------------------ pacing
    def _lead(self) -> int:
        """How far ahead of the slower world the target lies: :data:`LEAD_FRAMES` frames' steps."""
        spf = self.main.steps_per_frame
        if spf < FASTEST:
            return LEAD_FRAMES * spf
        return max(2 * FASTEST_CHUNK, int(LEAD_FRAMES * self.main.steps_per_second() / max(self.main.fps, 1.0)))

    def _advance(self) -> None:
        """A frame came: playing, raise the target to a lead ahead of the slower world."""
        with self._lock:
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
                    side.hold(target)


def difference(left: Snapshot, right: Snapshot) -> str:
    """What compare mode shows between the worlds: which one has more boxes in the goal, by how much."""
    ahead = 100 * (right.sample.fraction_in_goal - left.sample.fraction_in_goal)
    if abs(ahead) < 0.05:
        return "level: the same share in goal"
    name = side_name(right if ahead > 0 else left)
    return f"{name} +{abs(ahead):.1f} points"


class Comparison:
    """The compared world: its runner (held in :class:`Lockstep` with the running one), and its nodes
    in the scene, right of the running world's arena or below it (:attr:`offset`).

    ``make_runner(config, shape=..., seed=..., playing=...)`` builds a runner like the app's (a
    process of its own); :meth:`draw` is called as the app draws a frame, on its event thread;
    ``on_layout(offset)`` hears where the second world lies (None: gone), to frame the pages."""

    ROOT = "/compare"

    def __init__(self, server: Any, lockstep: Lockstep, make_runner: Callable[..., Any],
                 on_layout: Callable[[float | None], None],
                 on_crash: Callable[[str], None] = lambda why: None, caption_over_construction: bool = False,
                 events: Any = None):
        """``on_crash(why)`` hears that the compared world's process died (compare mode then ends: a
        restarted world would start again from step 0, far behind the running one);
        ``caption_over_construction``: where its caption sits, as the running world's (a classroom's
        pages frame the construction areas); ``events``: the app's event queue, where the compared
        world is adopted and dropped (None: in the calling thread)."""
        self.caption_over_construction = caption_over_construction
        self.server, self.lockstep, self._make_runner = server, lockstep, make_runner
        self._on_layout, self._on_crash = on_layout, on_crash
        self._events = events
        self.view: Any = None
        self.label: str | None = None
        #: Whether the second world lies below the first (chosen by the page that asked for it).
        self.stacked = False
        self._difference: Any = None  # the label between the worlds
        self._drawn: int | None = None  # the compared world's frame last drawn
        self._starting = threading.Lock()  # one new world's process starting at a time

    @property
    def runner(self) -> Any:
        return self.lockstep.partner

    @property
    def offset(self) -> tuple[float, float]:
        """Where the compared world is drawn (m along the floor from the running one)."""
        return compare_offset(self.lockstep.main.latest.world_config, self.stacked)

    def covers(self, point: tuple[float, float]) -> bool:
        """Whether a floor point lies on the compared world's arena (a click there acts on nothing)."""
        if self.runner is None:
            return False
        size = self.lockstep.main.latest.world_config.arena_size
        (dx, dy), (x, y) = self.offset, point
        return bool(dx - 1.0 <= x <= dx + size + 1.0 and dy - 1.0 <= y <= dy + size + 1.0)

    def _on_events(self, fn: Callable, *args: Any) -> Any:
        """Run ``fn`` on the app's event thread and wait for it (inline when already there)."""
        return fn(*args) if self._events is None else self._events.call(fn, *args, timeout=60.0)

    def begin(self, config: Config, shape: Any, label: str, stacked: bool = False) -> None:
        """Compare with a world of ``config`` and ``shape`` from the running world's seed: both start
        again from step 0, playing if the running one was; ``stacked``: the second world below the
        first (for the asking page's tall view) instead of right of it. Blocks while the new world's
        process starts (a second or two): call it off the event thread (the start happens here, the
        adoption on the event thread)."""
        with self._starting:
            seed = self.lockstep.main.latest.seed
            partner = self._make_runner(config, shape=shape, seed=seed, playing=False)
            try:
                partner.start()
                self._on_events(self._adopt, partner, label, stacked)
            except BaseException:
                partner.stop()
                raise

    def _adopt(self, partner: Any, label: str, stacked: bool = False) -> None:
        """Pair the started ``partner`` with the running world and draw it (on the event thread)."""
        self._end()
        self.stacked = stacked
        playing = self.lockstep.main.playing
        with self.server.atomic():
            view = SceneView(self.server.scene, partner.latest, root=self.ROOT, offset=self.offset,
                             caption_over_construction=self.caption_over_construction)
            view.set_compared(self.offset, partner.latest, second=True)
            x, y = difference_anchor(self.lockstep.main.latest.world_config, self.offset)
            self._difference = self.server.scene.add_label(
                "/compare_difference", difference(self.lockstep.main.latest, partner.latest), position=(x, y, Z_TOP),
                anchor="center-center", font_size_mode="scene", font_scene_height=DIFFERENCE_HEIGHT)
        self.view, self.label, self._drawn = view, label, partner.latest.frame
        if hasattr(partner, "on_crash"):  # a process of its own
            partner.on_crash(lambda why, partner=partner: self._crashed(partner, why))  # on the event queue
        self.lockstep.pair(partner)
        # Both from step 0 (held there while they are built), then playing if the running world was;
        # also if a world could not be rebuilt (its process died, say).
        self.lockstep.reset(None, on_done=lambda _: self.lockstep.set_playing(playing),
                            on_error=lambda _: self.lockstep.set_playing(playing))
        self._on_layout(self.offset)

    def end(self) -> None:
        """The running world goes on alone."""
        if self._end():
            self._on_layout(None)

    def _crashed(self, partner: Any, why: str) -> None:
        if partner is not self.runner:
            return
        self._on_crash(why)
        self.end()

    def _end(self) -> bool:
        partner = self.lockstep.unpair()
        view, self.view, self.label = self.view, None, None
        if view is not None:
            view.remove()
        if self._difference is not None:
            self._difference.remove()
            self._difference = None
        if partner is not None:
            partner.stop()
        return partner is not None

    def draw(self) -> None:
        """Draw the compared world's newest frame, if it has a new one: the app calls this as it draws
        the running world's, in the same batch, so that the page gets both in one picture (viser's
        page asks for a picture per batch: a batch for each world would ask for two)."""
        view, partner = self.view, self.runner
        if view is None or partner is None:
            return
        snap = partner.latest
        if snap.frame != self._drawn:
            self._drawn = snap.frame
            view.update(snap)
            text = difference(self.lockstep.main.latest, snap)
            if self._difference is not None and self._difference.text != text:
                self._difference.text = text
