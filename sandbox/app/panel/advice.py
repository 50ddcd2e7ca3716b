"""The *Which strategy builds my shape?* folder: the running goal's candidate
outlines and strategies tried in short trials beside the live simulation
(:mod:`sandbox.experiments.advise`), ranked, with one click to use the best.
Runs on the app's event thread; the trials run in a pool started by a worker, whose answers are posted back.

The trials run in worker processes at a lower priority, one a core, and while
they run the folder compares the live simulation's speed with its speed before:
when it falls below :data:`SLOWED` of it, the folder says so.

Runs on the app's event thread; the trials' thread only posts to it (its
progress, its end) and hears one thing back: the cancel event.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

import viser

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.world.snapshot import Snapshot
from sandbox.experiments import advise as advice

#: Below this share of its speed before the advice, the page says the advice slows the simulation.
SLOWED = 0.8


class AdviceFolder:
    def __init__(self, gui: Any, runner: Any, use: Callable[[str, dict, Any], None], *, events: Any,
                 run_to_the_end: Callable[[Any], None] = lambda client: None, seeds: int = advice.SEEDS,
                 steps: int = advice.STEPS):
        """``events``: the app's event queue (:mod:`sandbox.app.web.events`; the trials run in a thread of
        their own and report there); ``run_to_the_end(client)``: a new world (same seed) run to the end,
        the result explained (the Run folder's)."""
        self.gui, self.runner = gui, runner
        self._post = events.post
        self._use = use
        self.run_to_the_end = run_to_the_end
        self.seeds, self.steps = seeds, steps
        self.results: list[advice.Ranked] = []
        self.default: advice.Candidate | None = None  # what the goal gets without advice, for the verdict
        self._cancel = threading.Event()  # set here, read by the trials' thread: how it hears Cancel
        self._thread: threading.Thread | None = None
        self._busy = False
        self._speed_before = 0.0
        self._progress = (0, 0)
        self._left: tuple[float | None, float] = (None, 0.0)  # the seconds left, and when they were (monotonic)
        self._shown = ""

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Which strategy builds my shape?", expand_by_default=False):
            gui.add_markdown(f"Short trials ({self.seeds} seeds x {self.steps:,} steps) of every outline and "
                             "strategy that can build the current goal, beside the live simulation.")
            self.start = gui.add_button("Try them all", icon=viser.Icon.TEST_PIPE,
                                        hint="Run the trials in the background and rank the strategies")
            self.cancel = gui.add_button("Cancel", icon=viser.Icon.X, visible=False)
            self.bar = gui.add_progress_bar(0.0, visible=False)
            self.status = gui.add_markdown("")
            self.use_best = gui.add_button("Use the best", icon=viser.Icon.CHECK, disabled=True,
                                           hint="Give the running goal the first-ranked outline and strategies")
            self.best_to_the_end = gui.add_button(
                "Use the best and run to the end", icon=viser.Icon.PLAYER_SKIP_FORWARD, disabled=True,
                hint="The first-ranked outline and strategies in a new world (the same seed), run to the end "
                     "without drawing (Run folder), then the result explained")

        @self.start.on_click
        def _(event: viser.GuiEvent) -> None:
            self.begin(event.client)

        @self.cancel.on_click
        def _(event: viser.GuiEvent) -> None:
            self._cancel.set()

        @self.use_best.on_click
        def _(event: viser.GuiEvent) -> None:
            self.apply_best(event.client)

        @self.best_to_the_end.on_click
        def _(event: viser.GuiEvent) -> None:
            if self.apply_best(event.client):
                self.run_to_the_end(event.client)

    # ------------------------------------------------------------- running
    @property
    def running(self) -> bool:
        return self._busy

    def begin(self, client: Any) -> None:
        """Start the trials of the running goal (refused while some run)."""
        if self.running:
            notify_error(client, "Advice already running", "Wait for it, or cancel it first.")
            return
        snap = self.runner.latest
        config, vertices = snap.world_config.replace(shape=snap.shape_name), snap.goal_vertices
        self._cancel.clear()
        self._speed_before = snap.steps_per_second
        self._progress, self._left = (0, 0), (None, time.monotonic())
        self.results, self.use_best.disabled, self.best_to_the_end.disabled = [], True, True
        self.start.disabled, self.cancel.visible, self.bar.visible, self.bar.value = True, True, True, 0.0
        self._busy = True
        self._thread = threading.Thread(target=self._run, args=(config, vertices, client), name="phototaxis-advice",
                                        daemon=True)
        self._thread.start()

    def _run(self, config: Any, vertices: Any, client: Any) -> None:
        """The trials, in a thread of their own; what they change, they change on the event thread."""
        try:
            default = advice.default_candidate(config, vertices)
            results = advice.advise(config, vertices, seeds=self.seeds, steps=self.steps,
                                    workers=advice.default_workers(),
                                    progress=self._progress_heard, cancel=self._cancel)
        except advice.Cancelled:
            self._post(self._ended, [], client, ("Advice cancelled", "The trials were stopped.", "blue"))
        except Exception as exc:  # noqa: BLE001 - a goal the advice refuses, a worker that died: say so
            self._post(self._ended, [], client, ("Advice failed", str(exc), "red"))
        else:
            self._post(self._ended, results, client, ("Advice ready", advice.verdict(results, default), "green"),
                       default)

    def _ended(self, results: list, client: Any, notice: tuple[str, str, str],
               default: advice.Candidate | None = None) -> None:
        self.results, self.default = results, default
        title, body, colour = notice
        if colour == "red":
            notify_error(client, title, body)
        else:
            notify(client, title, body, colour)
        self._busy = False
        self.start.disabled, self.cancel.visible, self.bar.visible = False, False, False
        self.use_best.disabled = self.best_to_the_end.disabled = not self.results
        self._show()

    def _progress_heard(self, done: int, total: int, seconds_left: float | None) -> None:
        """In the trials' thread: to the event thread, with the moment the time left was reckoned."""
        self._post(self._heard, done, total, seconds_left, time.monotonic())

    def _heard(self, done: int, total: int, seconds_left: float | None = None, at: float | None = None) -> None:
        self._progress, self._left = (done, total), (seconds_left, time.monotonic() if at is None else at)
        self.bar.value = 100.0 * done / max(total, 1)

    def apply_best(self, client: Any) -> bool:
        """The first-ranked outline and strategies, on the running goal (False: no advice yet)."""
        if not self.results:
            notify_error(client, "No advice yet", "Press Try them all first.")
            return False
        best = self.results[0].candidate
        self._use(best.outline, best.every_strategy, client)
        return True

    # ------------------------------------------------------------ read-outs
    def update(self, snap: Snapshot) -> None:
        self._show(snap)

    def _show(self, snap: Snapshot | None = None) -> None:
        text = self._text(snap)
        if text != self._shown:
            self.status.content = self._shown = text

    def _text(self, snap: Snapshot | None = None) -> str:
        if self.running:
            done, total = self._progress
            seconds, at = self._left  # counted down from the last finished trial's estimate
            left = advice.in_words(None if seconds is None else max(seconds - (time.monotonic() - at), 0.0))
            line = f"Running: {done} of {total or '...'} trials done, {left}."
            speed = (snap or self.runner.latest).steps_per_second
            if self._speed_before > 0 and speed < SLOWED * self._speed_before:
                line += (f" **The trials slow the live simulation to {100 * speed / self._speed_before:.0f} % of "
                         f"its speed** (Cancel to give it back).")
            return line
        if self.results:
            return f"**{advice.verdict(self.results, self.default)}**\n\n{advice.table(self.results, self.steps)}"
        return ""

    def stop(self) -> list[threading.Thread]:
        """Stop trials still running (the app is stopping, on the event thread). Returns their thread,
        if it still runs, for the app to wait for (not here: it posts to this thread as it ends)."""
        self._cancel.set()
        return [self._thread] if self._thread is not None and self._thread.is_alive() else []
