"""The Strategies folder: the paper's seven cases in one control, the outline
the band follows (and why), then a checkbox and an amount per strategy,
generated from their declaration (:data:`sandbox.model.config.STRATEGIES`). Runs on the app's event thread.

Picking a paper case starts it: a new world (the same seed) with the case's
goal and strategies, from step 0, so cases compare from the same start. The
dropdown always shows the case that runs, or ``custom``.

A strategy that does nothing on the outline the band follows (flare, switch
and no corners on the offset outline: :func:`sandbox.model.notes.inert_strategies`)
is greyed out, its checkbox and amount, with a hint and a line under *Band
follows* that say why; it comes back when the outline does. Greyed out, it is
disabled for the server too: the inbox refuses a click on it from any page."""

from __future__ import annotations

from typing import Any, Callable

import viser

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.world.orders import SetOutline, UpdateConfig
from sandbox.app.world.snapshot import Snapshot, running_case
from sandbox.model.config import CASES, STRATEGIES, param
from sandbox.model.notes import inert_note, inert_strategies, strategy_effect_note
from sandbox.shapes import shape_vertices

#: What the Paper case dropdown shows when the goal, the strategies or the outline are not one of the seven.
CUSTOM = "custom"


class StrategiesFolder:
    def __init__(self, gui: Any, runner: Any, use_shape: Callable[[Any, str, Any], None],
                 on_change: Callable[..., None], reset: Callable[..., None]):
        self.gui, self.runner = gui, runner
        self._use_shape, self._on_change, self._reset = use_shape, on_change, reset
        self.controls: dict[str, tuple[Any, Any]] = {}
        self._outline_shown = ""
        #: A case picked and on its way to the simulation: the dropdown keeps showing it meanwhile.
        self._starting: str | None = None
        self._case_shown = ""  # what this panel last set the Paper case dropdown to show
        self._inert_family: str | None = None  # the outline family the strategies were last greyed out for

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Strategies"):
            self._case_shown = self._running(snap)
            self.case = gui.add_dropdown("Paper case", (*CASES, CUSTOM), initial_value=self._case_shown,
                                         hint="Start one of the paper's seven cases from step 0 (same seed). "
                                              "custom: your own goal or strategies")
            self.outline = gui.add_dropdown("Outline", param("outline").choices, initial_value=snap.config.outline,
                                            hint="auto: the paper's scaled outline when the goal's centre lies deep "
                                                 "inside it, else the goal's edge at a distance (offset)")
            self.outline_status = gui.add_markdown(self._outline_text(snap))
            gui.add_markdown("Changes reach the running simulation at the next controller update; no reset.")
            for s in STRATEGIES:
                value = getattr(snap.config, s.name)
                on = gui.add_checkbox(s.label, value > 0, hint=s.tip or s.help)
                amount = gui.add_slider(f"{s.label} amount", s.step, s.high, s.step,
                                        float(value if value > 0 else s.on_value), hint=s.tip or s.help)
                self.controls[s.name] = (on, amount)
                on.on_update(lambda event, n=s.name: self._changed(n, event.client))
                amount.on_update(lambda event, n=s.name: self._changed(n, event.client))
        self._grey_out_inert(snap.family)

        @self.case.on_update
        def _(event: viser.GuiEvent) -> None:
            if event.client is None:
                return  # this panel showing what runs, not a pick
            if self.case.value in CASES:
                self.use_case(self.case.value, event.client)
            else:  # custom is what the dropdown says, not something to pick
                self._case_shown = self.case.value = self._running(self.runner.latest)

        @self.outline.on_update
        def _(event: viser.GuiEvent) -> None:
            if event.client is not None:
                self.use_outline(self.outline.value, event.client)

    def update(self, snap: Snapshot) -> None:
        text = self._outline_text(snap)
        if text != self._outline_shown:
            self.outline_status.content = self._outline_shown = text
        self._grey_out_inert(snap.family)
        # Never over a viewer's pick on its way (as the shape's dropdown): viser sets the value, then runs
        # the callback in a thread of its own, which would read what a refresh put back in between.
        running = self._running(snap)
        if self._starting is None:
            if self.case.value == running:
                self._case_shown = running
            elif self.case.value == self._case_shown:
                self._case_shown = self.case.value = running

    @staticmethod
    def _running(snap: Snapshot) -> str:
        return running_case(snap.shape_name, snap.strategies, snap.family) or CUSTOM

    def _grey_out_inert(self, family: str) -> None:
        """Disable the strategies that do nothing on this outline family (their hint says why), and enable
        the others, once per change of family."""
        if family == self._inert_family:
            return
        self._inert_family = family
        for s in STRATEGIES:
            on, amount = self.controls[s.name]
            why = inert_note(s.name, family)
            on.disabled = amount.disabled = bool(why)
            on.hint = amount.hint = f"Greyed out. {why}" if why else (s.tip or s.help)

    @staticmethod
    def _outline_text(snap: Snapshot) -> str:
        reason = snap.family_reason.split(": ", 1)[-1] if snap.family_reason else ""
        follows = "the goal grown by a distance" if snap.family == "offset" else "the goal scaled"
        text = f"**Band follows:** {follows} ({snap.family}){' - ' + plain(reason) if reason else ''}"
        inert = inert_strategies(snap.family)
        if inert:
            why = [f"{s.label.lower()} ({inert[s.name]})" for s in STRATEGIES if s.name in inert]
            text += f"  \n*Greyed out, as they do nothing with the {snap.family} outline: {_listed(why)}.*"
        return text

    def use(self, outline: str, strategies: dict[str, float], client: Any) -> None:
        """An outline and the strategies' amounts (those not given off), shown and applied."""
        self.outline.value = outline
        self.use_outline(outline, client)
        values = {s.name: float(strategies.get(s.name, 0.0)) for s in STRATEGIES}
        self.runner.ask(UpdateConfig(values), on_error=lambda exc: notify_error(client, "Strategies not used", str(exc)))
        self._show_strategies(values)
        self._on_change(f"outline {outline}, " + ", ".join(f"{k} {v:g}" for k, v in values.items() if v > 0))

    def back_to_defaults(self, client: Any) -> None:
        """The outline back to auto and every strategy off, shown and applied (a new goal starts so)."""
        strategies = {s.name: 0.0 for s in STRATEGIES}
        self.runner.ask(UpdateConfig({"outline": "auto", **strategies}),
                        on_error=lambda exc: notify_error(client, "Strategies not reset", str(exc)))
        self.outline.value = "auto"
        self._show_strategies(strategies)

    def show_settings(self, config: Any) -> None:
        """Show ``config``'s outline and strategies (the settings that stand after a crash went back)."""
        self.outline.value = config.outline  # a value set here, not a pick: nothing is sent
        self._show_strategies({s.name: float(getattr(config, s.name)) for s in STRATEGIES})

    def _show_strategies(self, values: dict[str, float]) -> None:
        self._quiet = True
        try:
            for s in STRATEGIES:
                on, amount = self.controls[s.name]
                on.value = values[s.name] > 0
                if values[s.name] > 0:
                    amount.value = values[s.name]
        finally:
            self._quiet = False

    def use_outline(self, outline: str, client: Any) -> None:
        """Another outline family: the goal is fitted again and its outline starts from its largest size."""

        def done(notes: list[str]) -> None:
            self._on_change(f"outline {outline}")
            if notes:  # one notice for the action
                notify(client, "Outline changed", ". ".join(n[0].upper() + n[1:] for n in notes) + ".", "blue")

        def refused(exc: BaseException) -> None:
            notify_error(client, "Outline not changed", str(exc))

        self.runner.ask(SetOutline(outline), on_done=done, on_error=refused)

    def use_case(self, name: str, client: Any, on_started: Callable[[], None] | None = None) -> None:
        """Start the case: its goal, its strategies (the others off) and the paper's outline, in a new
        world with the same seed, from step 0; then ``on_started()``."""
        case = CASES[name]
        strategies = {s.name: float(case.get(s.name, 0.0)) for s in STRATEGIES}
        self._starting = self._case_shown = self.case.value = name  # shown until it runs (or until it fails)

        def started(_: Any = None) -> None:
            self._starting = None
            self._on_change(f"case {name}", 0)  # the first step of the new world
            if on_started:
                on_started()

        def failed(exc: BaseException) -> None:
            self._starting = None
            notify_error(client, "Case not started", str(exc))

        # In this order, in the simulation's queue: the goal, the paper's outline and the strategies,
        # then the new world (the reset says why if it cannot be built).
        self._use_shape(shape_vertices(case["shape"]), case["shape"], client, quiet=True)
        self.runner.ask(UpdateConfig({"outline": "auto", **strategies}), on_error=failed)
        self._reset(client, on_done=started, on_error=lambda exc: setattr(self, "_starting", None))
        self.outline.value = "auto"
        self._show_strategies(strategies)

    def _changed(self, name: str, client: Any) -> None:
        if getattr(self, "_quiet", False):
            return
        on, amount = self.controls[name]
        value = float(amount.value) if on.value else 0.0

        def failed(exc: BaseException) -> None:
            notify_error(client, "Strategy not changed", str(exc))

        self.runner.ask(UpdateConfig({name: value}), on_error=failed)  # a strategy is live: no reset
        self._on_change(f"{name} {value:g}")
        chase = float(self.controls["chase"][1].value) if self.controls["chase"][0].value else 0.0
        snap = self.runner.latest
        note = strategy_effect_note(name, value, snap.goal_vertices, chase, snap.family)
        if note:  # applied all the same: the goal may change to one it acts on
            notify(client, "No visible effect", note, "yellow")


def _listed(words: list[str]) -> str:
    """'a, b and c'."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"
