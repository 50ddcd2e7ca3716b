"""The Compare folder: a second world beside the running one (issue 25, item 1; see
:mod:`sandbox.app.world.lockstep`).
Runs on the app's event thread; the compared world starts in a worker, which posts what it finds.

Runs on the app's event thread. A new world's process starts in a worker (it
blocks for a second or two), which changes nothing here: it posts what
happened back to the event thread."""

from __future__ import annotations

import threading
from typing import Any, Callable

import viser

from sandbox.app.view.partner import Comparison
from sandbox.app.world.lockstep import COMPARE_CASES, SAME, partner_config, side_name
from sandbox.app.panel.common import notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.view.scene import PHONE_ASPECT
from sandbox.app.world.orders import WorldSpec
from sandbox.app.world.snapshot import Snapshot

NOTHING = "nothing"
#: A page narrower than this (width / height) gets the second world below the first, not beside it: a phone
#: or a portrait screen. A 1024 x 768 projector's canvas beside the open panel (0.79) keeps them side by
#: side, which it needs once the panel folds (the layout is chosen when the comparison starts).
TALL = PHONE_ASPECT
#: The Compare with... choices: none, the running world under the paper's lights, a case.
CHOICES = (NOTHING, SAME, *COMPARE_CASES)


class CompareFolder:
    def __init__(self, gui: Any, runner: Any, comparison: Comparison, on_change: Callable[[str], None], *,
                 events: Any):
        """``events``: the app's event queue (:mod:`sandbox.app.web.events`; the worker that starts a world
        reports there)."""
        self.gui, self.runner, self.comparison, self._on_change = gui, runner, comparison, on_change
        self._post = events.post
        # Shared by the compare workers (no state behind it): one change of comparison at a time, so
        # that a choice made while a world starts waits for it, and comes after it.
        self._busy = threading.Lock()
        self._starting = False
        self._quiet = False  # set while the dropdown is set from here, not by a page
        self._shown = NOTHING  # what this panel last set the dropdown to show

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Compare", expand_by_default=False):
            gui.add_markdown("A second world to the right of this one (below it on a page taller than wide), from "
                             "the same seed: the same robots and "
                             "boxes, with the strategies of a paper case (or the same settings under the paper's "
                             "lights, against your lamp or program). Play, pause, step, reset and speed act on "
                             "both; the charts show both.")
            self.choice = gui.add_dropdown("Compare with...", CHOICES, initial_value=NOTHING,
                                           hint="Both worlds start again from step 0 with this world's seed")
            self.status = gui.add_markdown("")

        @self.choice.on_update
        def _(event: viser.GuiEvent) -> None:
            if not self._quiet:
                self.choose(str(self.choice.value), event.client)

    def choose(self, choice: str, client: Any) -> None:
        """Compare with ``choice`` (one of :data:`CHOICES`; :data:`NOTHING` ends the comparison), in
        a thread of its own: a new world's process takes a second or two to start."""
        if choice not in CHOICES:
            return
        self.show(choice)
        self._starting = choice != NOTHING  # until it runs, the dropdown keeps showing it
        threading.Thread(target=self._choose, args=(choice, client, tall(client)), daemon=True,
                         name="compare").start()

    def _choose(self, choice: str, client: Any, stacked: bool) -> None:
        """In a worker (a world's process starting blocks); what it changes, it posts to the app's event
        thread, the page's status line too."""
        with self._busy:
            if choice == NOTHING:
                self._post(self._ended, client)
                return
            self._post(self._say_starting)
            try:
                config, shape = self._partner(choice)
                self.comparison.begin(config, shape, choice, stacked=stacked)
            except Exception as exc:  # a refused goal or a process that would not start: say so
                self._post(self._refused, client, exc)
                return
            self._post(self._began, choice, client)

    def _say_starting(self) -> None:
        self.status.content = "Starting the second world..."

    def _ended(self, client: Any) -> None:
        self._starting = False
        if self.comparison.runner is not None:
            self.comparison.end()
            self._on_change("compare: off")

    def _refused(self, client: Any, exc: Exception) -> None:
        self._starting = False
        notify_error(client, "Cannot compare", str(exc))
        self.show(NOTHING if self.comparison.runner is None else self.comparison.label)

    def _began(self, choice: str, client: Any) -> None:
        # No notice: it covered the right world's caption for seconds (issue 41); the captions, the
        # readouts and this folder's status say what runs.
        self._starting = False
        self._on_change(f"compare: {choice}")

    def show(self, choice: str) -> None:
        """The dropdown shows ``choice`` (without acting on it; a config file's name is not a choice)."""
        if choice not in CHOICES:
            return
        self._shown = choice
        if self.choice.value != choice:
            self._quiet = True
            try:
                self.choice.value = choice
            finally:
                self._quiet = False

    def _partner(self, choice: str) -> tuple[Any, Any]:
        """The compared world's settings and goal: the running world's (its goal as given) under the
        paper's lights, or its settings with a paper case's goal and strategies."""
        config = self.runner.latest.config
        if choice != SAME:
            return partner_config(config, choice), "from-config"
        _, _, vertices = self.runner.call(WorldSpec(), 30.0)  # in the worker: waiting here holds no event
        return config, ("from-config" if vertices is None else vertices)

    def update(self, snap: Snapshot) -> None:
        """The dropdown shows what is compared (nothing, once a comparison ended for any reason), the status
        line both shares."""
        partner = self.comparison.runner
        compared = NOTHING if partner is None else self.comparison.label
        # Never over a page's pick: viser sets the dropdown's value, then runs its callback in a thread
        # of its own; a refresh in between put "nothing" back, the callback read it, and no second world
        # started (seen under two test suites at once). So the dropdown is set only while it still shows
        # what this panel showed. A comparison on its way: the dropdown shows it already.
        if not self._starting:
            if self.choice.value == compared:
                self._shown = compared
            elif self.choice.value == self._shown:
                self.show(compared)
        if partner is None:
            if not self._starting:
                self.status.content = ""
            return
        other = partner.latest
        first, second = ("Top", "Bottom") if self.comparison.stacked else ("Left", "Right")
        self.status.content = (
            f"**{first}** {plain(side_name(snap))}: {100 * snap.sample.fraction_in_goal:.1f} % in the goal, "
            f"step {snap.step:,}  \n**{second}** {plain(side_name(other))}: "
            f"{100 * other.sample.fraction_in_goal:.1f} % in the goal, step {other.step:,}")


def tall(client: Any) -> bool:
    """Whether the page that asks for a comparison is taller than wide: the shared scene has one layout
    for every page, and it follows the page that runs the comparison (the presenter's, which the room
    reads); the other pages frame both worlds as their windows allow."""
    aspect = getattr(getattr(client, "camera", None), "aspect", None)
    return bool(aspect) and float(aspect) < TALL
