"""The Challenge folder: build the goal by hand, against the paper (issue 25, item 3).

*Start a round* builds a new world from the paper's first seed with the
running goal and settings, gives the lights to the lamp (the Be the light
folder's clicks move it, paint or erase) and plays :data:`ROUND_STEPS`
world steps. At the end the player's share of boxes in the goal is set
beside the paper's controller's in the same world after the same steps,
computed in a worker process while the live world waits (honest: same
configuration, seed, goal and steps). The page keeps each player's best
share of the session, by name.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable

import viser

from sandbox.app.panel.common import notify_error
from sandbox.app.snapshot import LAMP_PROGRAM, Snapshot
from sandbox.model.challenge import ROUND_SEED, ROUND_STEPS, paper_share
from sandbox.processes import simulation_context

#: At most this many letters of a player's name are kept.
NAME_LENGTH = 24


@dataclass
class Round:
    """One round: who plays, from which world (its key, once built), and how it ended."""

    player: str
    steps: int
    old_world: int
    world: int | None = None
    score: float | None = None
    at_step: int | None = None
    paper: float | None = None


class ChallengeFolder:
    def __init__(self, gui: Any, runner: Any, lockstep: Any, lamp: Any, on_change: Callable[[str], None],
                 post: Callable[..., None] = lambda fn, *args: fn(*args)):
        """The round's reset, play and pause act on ``lockstep``: in compare mode the second world (the
        paper's lights, say) plays the round beside the player's. ``post(fn, *args)`` runs on the app's
        event thread: the paper's reference run reports there."""
        self.gui, self.runner, self.lockstep, self.lamp, self._on_change = gui, runner, lockstep, lamp, on_change
        self._post = post
        #: World steps a round lasts (tests shorten it).
        self.round_steps = ROUND_STEPS
        self.round: Round | None = None
        #: Each player's best share of the session, by name.
        self.best: dict[str, float] = {}
        self._lock = threading.RLock()
        self._stopped = False
        self._pool: Any = None  # the reference run's process pool (multiprocessing's: it can be terminated)

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Challenge", expand_by_default=False):
            gui.add_markdown(f"Build the goal by hand: a round of {self.round_steps:,} steps from the paper's "
                             "seed, with the lamp of *Be the light*, then your share of boxes in the goal beside "
                             "the paper's controller's in the same world.")
            self.name = gui.add_text("Your name", "player", hint="Your best score of the session is kept under it")
            self.start_button = gui.add_button("Start a round", icon=viser.Icon.FLAG)
            self.status = gui.add_markdown("")
            self.scores = gui.add_markdown("")
        self.start_button.on_click(lambda event: self.start(self.name.value, event.client))

    # ------------------------------------------------------------ a round
    def start(self, name: str, client: Any) -> None:
        """A new world from the paper's seed, the lamp lit at its middle, playing."""
        player = " ".join(str(name).split())[:NAME_LENGTH] or "player"
        with self._lock:
            self.round = Round(player, int(self.round_steps), self.runner.latest.world_key)
        self.status.content = f"**{player}**: building the round's world..."
        self.lockstep.set_playing(False)

        def built(_: Any) -> None:
            centre = self.runner.latest.world_config.centre
            self.runner.set_lamp((centre, centre), float(self.lamp.radius.value), "lamp")
            self.lockstep.set_playing(True)
            self._on_change(f"round: {player}")

        def failed(exc: BaseException) -> None:
            with self._lock:
                self.round = None
            self.status.content = ""
            notify_error(client, "Round not started", str(exc))

        self.lockstep.reset(ROUND_SEED, on_done=built, on_error=failed)

    def update(self, snap: Snapshot) -> None:
        with self._lock:
            r = self.round
            if r is None or r.score is not None:
                return
            if r.world is None:
                if snap.world_key == r.old_world or snap.program != LAMP_PROGRAM:
                    return  # the round's world is not running yet
                r.world = snap.world_key
            if snap.world_key != r.world or snap.program != LAMP_PROGRAM:
                self.round = None
                self.status.content = (f"**{r.player}**: round abandoned (a new world, or the lights went back "
                                       "to a controller).")
                return
            if snap.sample.step < r.steps:
                self.status.content = (f"**{r.player}**: step {snap.step:,} of {r.steps:,}, "
                                       f"{100 * snap.sample.fraction_in_goal:.1f} % in the goal")
                return
            r.score, r.at_step = float(snap.sample.fraction_in_goal), int(snap.sample.step)
        self.lockstep.set_playing(False)
        self.status.content = (f"**{r.player}**: {100 * r.score:.1f} % in the goal after {r.at_step:,} steps. "
                               "The paper's controller is playing the same world...")
        self.runner.world_spec(on_done=lambda spec: self._score_the_paper(r, spec),
                               on_error=lambda exc: self._show(r, problem=f"no reference: {exc}"))

    def _score_the_paper(self, r: Round, spec: tuple) -> None:
        config, seed, shape = spec

        def run() -> None:  # in a thread of its own: the result goes back to the event thread
            pool = simulation_context().Pool(1)
            self._pool = pool
            try:
                result = pool.apply_async(paper_share, (config, seed, r.at_step, shape))
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
        pool = self._pool
        if pool is not None:
            pool.terminate()

    def _show(self, r: Round, paper: float | None = None, problem: str = "") -> None:
        """The round's end: its score beside the paper's (or why there is none), and the best scores."""
        with self._lock:
            self.best[r.player] = max(self.best.get(r.player, 0.0), r.score)
            r.paper = paper
            ranked = sorted(self.best.items(), key=lambda item: -item[1])
        against = (f"the paper's controller: **{100 * r.paper:.1f} %** in the same world and steps"
                   if r.paper is not None else problem)
        verdict = "" if r.paper is None else (" You beat it!" if r.score > r.paper else "")
        self.status.content = f"**{r.player}**: **{100 * r.score:.1f} %** in the goal; {against}.{verdict}"
        self.scores.content = ("| player | best share |\n|---|---|\n"
                               + "".join(f"| {name} | {100 * share:.1f} % |\n" for name, share in ranked))
