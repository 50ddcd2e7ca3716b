"""The Challenge folder: build the goal by hand, against the paper (issue 25, item 3; issue 41, item 6).

*Start a round* builds a new world from the paper's first seed with the
running goal and settings, lights the lamp where the robots are (the Be the
light folder's clicks move it, paint or erase) and plays :data:`ROUND_STEPS`
world steps. The score is the boxes the player brought into the goal, beyond
those that started there (:class:`~sandbox.model.challenge.Gain`), set at the
end beside the paper's controller's in the same world over the same steps,
computed in a worker process while the live world waits (honest: same
configuration, seed, goal, steps and definition). After :data:`HINT_SECONDS`
without a box brought in, a one-line hint says what to try. The page keeps
each player's best score of the session, by name.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import viser

from sandbox.app.panel.common import notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.world.snapshot import LAMP_PROGRAM, Snapshot
from sandbox.model.challenge import ROUND_SEED, ROUND_STEPS, Gain, lamp_start, paper_gain
from sandbox.processes import simulation_context

#: At most this many letters of a player's name are kept.
NAME_LENGTH = 24
#: Seconds of a round without a box brought into the goal before the hint shows.
HINT_SECONDS = 10.0
#: What to try when nothing happens: one line.
HINT = ("Hint: light the robots where they are, then move the lamp a little at a time towards the goal: "
        "they follow the light and push the boxes ahead of them.")


@dataclass
class Round:
    """One round: who plays, in which world (its key, once built), and how it ended."""

    player: str
    steps: int
    #: The key of the round's world, once built: the round starts on its first frame. Only that key
    #: will do: a reset asked for before the round's (a compared world being paired) may publish its
    #: world after the round's reset answered, and a round begun on it was abandoned at the next frame.
    built: int | None = None
    #: The world the round began on (the lamp lit, playing).
    world: int | None = None
    #: Boxes in the goal when the round began, and the most the player has had in it since.
    started: int | None = None
    most: int | None = None
    score: Gain | None = None
    at_step: int | None = None
    paper: Gain | None = None


def describe(gain: Gain) -> str:
    """A gain as the page says it: '12 boxes brought in (22 % of the 54 outside at the start)'."""
    outside = gain.boxes - gain.started
    noun = "box" if abs(gain.brought) == 1 else "boxes"
    return f"{gain.brought} {noun} brought in ({100 * gain.share:.0f} % of the {outside} outside at the start)"


class ChallengeFolder:
    def __init__(self, gui: Any, runner: Any, lockstep: Any, lamp: Any, on_change: Callable[[str], None],
                 post: Callable[..., None] = lambda fn, *args: fn(*args), after: Callable[..., Any] | None = None):
        """The round's reset, play and pause act on ``lockstep``: in compare mode the second world (the
        paper's lights, say) plays the round beside the player's. ``post(fn, *args)`` runs on the app's
        event thread: the paper's reference run reports there. ``after(seconds, fn, *args)`` (the event
        queue's timers) shows the hint; without it there is none."""
        self.gui, self.runner, self.lockstep, self.lamp, self._on_change = gui, runner, lockstep, lamp, on_change
        self._post, self._after = post, after
        #: World steps a round lasts, and seconds without progress before the hint (tests shorten both).
        self.round_steps = ROUND_STEPS
        self.hint_seconds = HINT_SECONDS
        self.round: Round | None = None
        #: Each player's best score of the session (boxes brought in, as a share of those outside), by name.
        self.best: dict[str, float] = {}
        self._lock = threading.RLock()
        self._stopped = False
        self._pool: Any = None  # the reference run's process pool (multiprocessing's: it can be terminated)
        self._hint_timer: Any = None

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Challenge", expand_by_default=False):
            gui.add_markdown(f"Build the goal by hand: a round of {self.round_steps:,} steps from the paper's "
                             "seed, with the lamp of *Be the light*. You score the boxes you bring into the goal "
                             "(beyond those that start there), beside the paper's controller in the same world.")
            self.name = gui.add_text("Your name", "player", hint="Your best score of the session is kept under it")
            self.start_button = gui.add_button("Start a round", icon=viser.Icon.FLAG)
            self.status = gui.add_markdown("")
            self.hint = gui.add_markdown("")
            self.scores = gui.add_markdown("")
        self.start_button.on_click(lambda event: self.start(self.name.value, event.client))

    # ------------------------------------------------------------ a round
    def start(self, name: str, client: Any) -> None:
        """A new world from the paper's seed; once built, the lamp lit where the robots are, playing."""
        player = " ".join(str(name).split())[:NAME_LENGTH] or "player"
        self._cancel_hint()
        with self._lock:
            r = self.round = Round(player, int(self.round_steps))
        self.status.content = f"**{plain(player)}**: building the round's world..."
        self.hint.content = ""
        self.lockstep.set_playing(False)

        def built(world_key: int) -> None:
            with self._lock:
                r.built = world_key
            self._begin(r, self.runner.latest)  # its first frame may be here already

        def failed(exc: BaseException) -> None:
            with self._lock:
                if self.round is r:
                    self.round = None
            self.status.content = ""
            notify_error(client, "Round not started", str(exc))

        self.lockstep.reset(ROUND_SEED, on_done=built, on_error=failed)

    def _begin(self, r: Round, snap: Snapshot) -> None:
        """The round's world is built and ``snap`` may be its first frame: count the boxes already in the
        goal, light the lamp on the densest group of robots, and play."""
        with self._lock:
            if self.round is not r or r.world is not None or snap.world_key != r.built:
                return
            r.world = snap.world_key
            r.started = r.most = int(np.count_nonzero(snap.box_in_goal))
        radius = float(self.lamp.radius.value)
        centre = lamp_start(snap.robot_positions, radius)

        def lit(_: Any) -> None:
            self.lockstep.set_playing(True)
            self._on_change(f"round: {r.player}")
            self._arm_hint(r)

        self.runner.set_lamp(centre, radius, "lamp", on_done=lit,
                             on_error=lambda exc: self._abandon(r, f"the lamp could not be lit: {exc}"))

    def update(self, snap: Snapshot) -> None:
        with self._lock:
            r = self.round
            if r is None or r.score is not None:
                return
            if r.world is None:
                self._begin(r, snap)
                return
            if snap.world_key != r.world:
                self._abandon(r, "a new world")
                return
            if snap.program != LAMP_PROGRAM:
                if snap.step > 0:  # (at step 0 the lamp is being lit)
                    self._abandon(r, "the lights went back to a controller")
                return
            now = int(np.count_nonzero(snap.box_in_goal))
            if now > r.most:  # progress: the hint goes, and waits again
                r.most = now
                self.hint.content = ""
                self._arm_hint(r)
            if snap.step < r.steps:
                self.status.content = (f"**{plain(r.player)}**: step {snap.step:,} of {r.steps:,}, "
                                       f"{describe(Gain(r.started, now, len(snap.box_in_goal)))}")
                return
            r.score, r.at_step = Gain(r.started, now, len(snap.box_in_goal)), int(snap.step)
        self._cancel_hint()
        self.hint.content = ""
        self.lockstep.set_playing(False)
        self.status.content = (f"**{plain(r.player)}**: {describe(r.score)} after {r.at_step:,} steps. "
                               "The paper's controller is playing the same world...")
        self.runner.world_spec(on_done=lambda spec: self._score_the_paper(r, spec),
                               on_error=lambda exc: self._show(r, problem=f"no reference: {exc}"))

    def _abandon(self, r: Round, why: str) -> None:
        with self._lock:
            if self.round is not r:
                return
            self.round = None
        self._cancel_hint()
        self.hint.content = ""
        self.status.content = f"**{plain(r.player)}**: round abandoned ({plain(why)})."

    # ------------------------------------------------------------ the hint
    def _arm_hint(self, r: Round) -> None:
        """The hint shows after :attr:`hint_seconds` unless a box is brought in first (or the round ends)."""
        self._cancel_hint()
        if self._after is not None:
            self._hint_timer = self._after(self.hint_seconds, self._show_hint, r)

    def _cancel_hint(self) -> None:
        if self._hint_timer is not None:
            self._hint_timer.cancel()
            self._hint_timer = None

    def _show_hint(self, r: Round) -> None:
        with self._lock:
            if self.round is not r or r.score is not None:
                return
        self._hint_timer = None
        # In the folder, under the round's status, not as a notice: a notice covers the floor (on a phone,
        # the page's shortcut opened the drawer at this folder).
        self.hint.content = HINT

    # ------------------------------------------------------------ the score
    def _score_the_paper(self, r: Round, spec: tuple) -> None:
        config, seed, shape = spec

        def run() -> None:  # in a thread of its own: the result goes back to the event thread
            pool = simulation_context().Pool(1)
            self._pool = pool
            try:
                result = pool.apply_async(paper_gain, (config, seed, r.at_step, shape))
                while not result.ready() and not self._stopped:  # a terminated pool never answers
                    result.wait(0.5)
                if self._stopped:
                    raise RuntimeError("the app stopped")
                paper = result.get()
            except Exception as exc:  # a worker that could not run, or the app stopping: the round counts
                self._post(self._show, r, None, f"no reference: {exc}")
                return
            finally:
                pool.terminate()
                self._pool = None
            self._post(self._show, r, paper)

        threading.Thread(target=run, daemon=True, name="challenge-reference").start()

    def stop(self) -> None:
        """The app is stopping: a reference run still going ends now, not when it finishes."""
        self._stopped = True
        self._cancel_hint()
        pool = self._pool
        if pool is not None:
            pool.terminate()

    def _show(self, r: Round, paper: Gain | None = None, problem: str = "") -> None:
        """The round's end: its score beside the paper's (or why there is none), and the best scores."""
        with self._lock:
            self.best[r.player] = max(self.best.get(r.player, -1.0), r.score.share)
            r.paper = paper
            ranked = sorted(self.best.items(), key=lambda item: -item[1])
        against = (f"the paper's controller: **{describe(r.paper)}** in the same world and steps"
                   if r.paper is not None else plain(problem))
        verdict = "" if r.paper is None else (" You beat it!" if r.score.brought > r.paper.brought else "")
        self.status.content = f"**{plain(r.player)}**: **{describe(r.score)}**; {against}.{verdict}"
        self.scores.content = ("| player | best: boxes brought in, of those outside |\n|---|---|\n"
                               + "".join(f"| {plain(name)} | {100 * share:.0f} % |\n" for name, share in ranked))
