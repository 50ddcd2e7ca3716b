"""The Challenge folder: build the goal by hand, against the paper (issue 25, item 3; issue 41, item 6).
Runs on the app's event thread; its reference run starts in a worker, which hands the pool back to the event thread.

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

The round's score and hint are also written on the floor, under the
construction wall, in letters sized in metres (:data:`FLOOR_TEXT_HEIGHT`):
the presenter layout folds the panel, and the room reads the floor.

Runs on the app's event thread, which owns the round and the reference runs'
pools (a worker only starts a pool, which blocks, and hands it over).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import viser

from sandbox.app.panel.common import notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.view.scene import CONSTRUCTION_VIEW, construction_box
from sandbox.app.world.orders import SetLamp, WorldSpec
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
#: The hint as the floor says it: short enough for one line under the construction area.
FLOOR_HINT = "Hint: light the robots, then lead them to the goal"
#: The floor's score and hint: letters this high (m). The presenter layout at 1024 x 768 frames the
#: construction area (16 m) about 480 px high: 30 px a metre, 25 px letters, read from the back of a room.
FLOOR_TEXT_HEIGHT = 0.85


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
    def __init__(self, gui: Any, runner: Any, lockstep: Any, lamp: Any, on_change: Callable[[str], None], *,
                 events: Any, scene: Any = None):
        """The round's reset, play and pause act on ``lockstep``: in compare mode the second world (the
        paper's lights, say) plays the round beside the player's. ``events``: the app's event queue
        (:mod:`sandbox.app.web.events`), where the paper's reference run reports and whose timer shows
        the hint. ``scene``: where the floor's score and hint are written (none: the folder only).
        Everything here runs on its thread."""
        self.gui, self.runner, self.lockstep, self.lamp, self._on_change = gui, runner, lockstep, lamp, on_change
        self._scene, self._floor, self._floor_text = scene, None, ""
        self._events = events
        #: World steps a round lasts, and seconds without progress before the hint (tests shorten both).
        self.round_steps = ROUND_STEPS
        self.hint_seconds = HINT_SECONDS
        self.round: Round | None = None
        #: Each player's best score of the session (boxes brought in, as a share of those outside), by name.
        self.best: dict[str, float] = {}
        self._stopped = False
        #: The reference runs going, each a process pool (multiprocessing's: it can be terminated) with
        #: its round. A worker starts the pool (that blocks) and hands it over here (:meth:`_adopt`).
        self._pools: dict[Any, Round] = {}
        #: The threads starting a pool: the app waits for them as it stops (:meth:`stop`).
        self._starters: list[threading.Thread] = []
        self._hint_timer: Any = None
        #: Who runs the paper's controller for the score: None, a process pool of this folder's own; or
        #: ``reference(spec, steps, on_done(gain), on_error(why))``, on this thread (a class's, shared by its
        #: students: :mod:`sandbox.app.lesson.references`).
        self.reference: Callable[..., None] | None = None

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

    # ------------------------------------------------------------ the floor's words
    def _write_floor(self, text: str) -> None:
        """The round's score (and hint) on the floor under the construction wall, centred; "" hides it."""
        if self._scene is None or text == self._floor_text:
            return
        self._floor_text = text
        if self._floor is None:
            cfg = self.runner.latest.world_config
            below = (cfg.centre, cfg.centre - cfg.construction_size / 2.0 - 0.4, 0.12)  # the caption's height
            self._floor = self._scene.add_label("/challenge", text or " ", position=below, anchor="top-center",
                                                font_size_mode="scene", font_scene_height=FLOOR_TEXT_HEIGHT,
                                                visible=bool(text))
            return
        if text:
            self._floor.text = text
        self._floor.visible = bool(text)

    def _floor_words(self, r: Round, now: int | None = None, step: int | None = None) -> None:
        """What the floor says of round ``r``: its score so far (``now`` boxes in the goal at ``step``) and
        the hint, or its end beside the paper's."""
        if r.score is not None:
            line = f"{r.player}: {r.score.brought} brought in"
            if r.paper is not None:
                line += f"; the paper's controller: {r.paper.brought}"
                line += " - you beat it!" if r.score.brought > r.paper.brought else ""
            self._write_floor(line)
            return
        if now is None or step is None:
            self._write_floor(f"{r.player}: get ready")
            return
        line = f"{r.player}: {now - r.started} brought in, step {step:,} of {r.steps:,}"
        self._write_floor(line + ("\n" + FLOOR_HINT if self.hint.content else ""))

    # ------------------------------------------------------------ a round
    def start(self, name: str, client: Any) -> None:
        """A new world from the paper's seed; once built, the lamp lit where the robots are, playing."""
        player = " ".join(str(name).split())[:NAME_LENGTH] or "player"
        self._cancel_hint()
        r = self.round = Round(player, int(self.round_steps))
        self.status.content = f"**{plain(player)}**: building the round's world..."
        self.hint.content = ""
        self._floor_words(r)
        self.lockstep.set_playing(False)

        def built(world_key: int) -> None:
            r.built = world_key
            self._begin(r, self.runner.latest)  # its first frame may be here already

        def failed(exc: BaseException) -> None:
            if self.round is r:
                self.round = None
            self.status.content = ""
            notify_error(client, "Round not started", str(exc))

        self.lockstep.reset(ROUND_SEED, on_done=built, on_error=failed)

    def _begin(self, r: Round, snap: Snapshot) -> None:
        """The round's world is built and ``snap`` may be its first frame: count the boxes already in the
        goal, light the lamp on the densest group of robots, and play."""
        if self.round is not r or r.world is not None or snap.world_key != r.built:
            return
        r.world = snap.world_key
        r.started = r.most = int(np.count_nonzero(snap.box_in_goal))
        radius = float(self.lamp.radius.value)
        # Its disk on the floor every page frames: the construction view (a phone's, a projector's beside
        # the folded panel's bar), not on the densest group wherever it is.
        view = construction_box(snap.world_config, CONSTRUCTION_VIEW)
        inset = min(radius + snap.world_config.light_pitch, (view[1] - view[0]) / 2.0)  # its lit cells whole
        centre = lamp_start(snap.robot_positions, radius,
                            within=(view[0] + inset, view[1] - inset, view[2] + inset, view[3] - inset))

        def lit(_: Any) -> None:
            self.lockstep.set_playing(True)
            self._on_change(f"round: {r.player}")
            self._arm_hint(r)

        self.runner.ask(SetLamp(centre, radius, "lamp"), on_done=lit,
                        on_error=lambda exc: self._abandon(r, f"the lamp could not be lit: {exc}"))

    def update(self, snap: Snapshot) -> None:
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
            self._floor_words(r, now, snap.step)
            return
        r.score, r.at_step = Gain(r.started, now, len(snap.box_in_goal)), int(snap.step)
        self._cancel_hint()
        self.hint.content = ""
        self.lockstep.set_playing(False)
        self.status.content = (f"**{plain(r.player)}**: {describe(r.score)} after {r.at_step:,} steps. "
                               "The paper's controller is playing the same world...")
        self._floor_words(r)
        self.runner.ask(WorldSpec(), on_done=lambda spec: self._score_the_paper(r, spec),
                        on_error=lambda exc: self._show(r, problem=f"no reference: {exc}"))

    def _abandon(self, r: Round, why: str) -> None:
        if self.round is not r:
            return
        self.round = None
        self._cancel_hint()
        self.hint.content = ""
        self.status.content = f"**{plain(r.player)}**: round abandoned ({plain(why)})."
        self._write_floor("")

    # ------------------------------------------------------------ the hint
    def _arm_hint(self, r: Round) -> None:
        """The hint shows after :attr:`hint_seconds` unless a box is brought in first (or the round ends)."""
        self._cancel_hint()
        self._hint_timer = self._events.after(self.hint_seconds, self._show_hint, r)

    def _cancel_hint(self) -> None:
        if self._hint_timer is not None:
            self._hint_timer.cancel()
            self._hint_timer = None

    def _show_hint(self, r: Round) -> None:
        if self.round is not r or r.score is not None:
            return
        self._hint_timer = None
        # In the folder, under the round's status, not as a notice: a notice covers the floor (on a phone,
        # the page's shortcut opened the drawer at this folder).
        self.hint.content = HINT

    # ------------------------------------------------------------ the score
    def _score_the_paper(self, r: Round, spec: tuple) -> None:
        """The paper's controller in the round's world over its steps, in a process pool of its own.
        Starting a pool blocks (the fork server may still be loading the model), so a worker starts it
        and hands it to this thread, which owns it from then on: it sets the run going, hears its answer
        (the pool's callbacks only post it here) and ends it."""
        if self._stopped:
            return
        if self.reference is not None:
            self.reference(spec, r.at_step, lambda paper: self._shared_scored(r, paper, ""),
                           lambda why: self._shared_scored(r, None, f"no reference: {why}"))
            return
        starter = threading.Thread(target=self._start_pool, args=(r, spec), daemon=True, name="challenge-reference")
        self._starters = [thread for thread in self._starters if thread.is_alive()] + [starter]
        starter.start()

    def _start_pool(self, r: Round, spec: tuple) -> None:
        """In a worker: start the reference run's pool and hand it to the event thread. Until that took
        it, the pool is this worker's: if the app stopped first, the worker ends it."""
        try:
            pool = simulation_context().Pool(1)
        except Exception as exc:  # noqa: BLE001 - no process to run it in: the round counts, without a reference
            self._events.post(self._show, r, None, f"no reference: {exc}")
            return
        if self._events.submit(self._adopt, r, spec, pool).exception() is not None:
            pool.terminate()  # the queue stopped before it ran: nobody else will end it

    def _adopt(self, r: Round, spec: tuple, pool: Any) -> None:
        """The worker's pool, now this thread's: the reference run starts in it (or, the app stopping,
        it ends at once)."""
        if self._stopped:
            pool.terminate()
            self._show(r, None, "no reference: the app stopped")
            return
        self._pools[pool] = r
        config, seed, shape = spec
        post = self._events.post  # the pool's callbacks run on its own thread: they only post
        pool.apply_async(paper_gain, (config, seed, r.at_step, shape),
                         callback=lambda paper: post(self._scored, pool, paper),
                         error_callback=lambda exc: post(self._scored, pool, None, f"no reference: {exc}"))

    def _scored(self, pool: Any, paper: Gain | None, problem: str = "") -> None:
        r = self._pools.pop(pool, None)
        if r is None:
            return  # ended by stop()
        pool.close()  # its one task is done: its process ends by itself, nothing waits for it here
        self._show(r, paper, problem)

    def _shared_scored(self, r: Round, paper: Gain | None, problem: str) -> None:
        if not self._stopped:  # (a folder stopped with its page says nothing more)
            self._show(r, paper, problem)

    def stop(self) -> list[threading.Thread]:
        """The app is stopping (on the event thread): a reference run still going ends now, not when it
        finishes. Returns the workers still starting a pool, for the app to wait for."""
        self._stopped = True
        self._cancel_hint()
        pools, self._pools = self._pools, {}
        for pool, r in pools.items():
            pool.terminate()  # a terminated pool never answers
            self._show(r, None, "no reference: the app stopped")
        return [thread for thread in self._starters if thread.is_alive()]

    def _show(self, r: Round, paper: Gain | None = None, problem: str = "") -> None:
        """The round's end: its score beside the paper's (or why there is none), and the best scores."""
        self.best[r.player] = max(self.best.get(r.player, -1.0), r.score.share)
        r.paper = paper
        ranked = sorted(self.best.items(), key=lambda item: -item[1])
        against = (f"the paper's controller: **{describe(r.paper)}** in the same world and steps"
                   if r.paper is not None else plain(problem))
        verdict = "" if r.paper is None else (" You beat it!" if r.score.brought > r.paper.brought else "")
        self.status.content = f"**{plain(r.player)}**: **{describe(r.score)}**; {against}.{verdict}"
        self._floor_words(r)
        self.scores.content = ("| player | best: boxes brought in, of those outside |\n|---|---|\n"
                               + "".join(f"| {plain(name)} | {100 * share:.0f} % |\n" for name, share in ranked))
