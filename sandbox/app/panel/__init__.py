"""The control panel: one small class per folder, each with ``build(snap)``
and ``update(snap)``, in the order the page shows them.
Built on the main thread before the event queue opens; runs on the app's event thread after.

Every callback runs on the app's event thread (:mod:`sandbox.app.web.events`),
one at a time, as do the frames' updates. None of them touches the simulation:
they go through the runner (commands, controls). The parameter folders are
generated from the model's declaration.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

import viser

from sandbox.app.panel import learn
from sandbox.app.view import legend
from sandbox.app.view.partner import Comparison
from sandbox.app.panel.advice import AdviceFolder
from sandbox.app.panel.common import PANEL_HZ
from sandbox.app.view.floor import floor_point
from sandbox.app.panel.challenge import ChallengeFolder
from sandbox.app.panel.compare import CompareFolder
from sandbox.app.panel.framing import WHOLE_ARENA, Framing
from sandbox.app.panel.inspector import InspectorFolder
from sandbox.app.panel.lamp import LampFolder
from sandbox.app.panel.metrics import MetricsFolder
from sandbox.app.panel.opening import DesignOpener
from sandbox.app.panel.parameters import ParametersFolder
from sandbox.app.panel.presenter import PresenterScreen
from sandbox.app.panel.program import ProgramFolder
from sandbox.app.panel.recording import RecordFolder
from sandbox.app.panel.result import ResultFolder
from sandbox.app.panel.run import RunFolder
from sandbox.app.panel.shape import ShapeFolder, upload_name
from sandbox.app.panel.strategies import StrategiesFolder
from sandbox.app.world.snapshot import Snapshot


class Panel:
    """Builds the GUI on ``server`` for ``runner`` and keeps its read-outs current.
    ``view`` is the scene (it shows the heat map); the shape being drawn has its own nodes (draw_view)."""

    def __init__(self, server: Any, runner: Any, view: Any, comparison: Comparison, *, events: Any,
                 allow_programs: bool = True, may_load_programs: Any = None, default_view: str = WHOLE_ARENA):
        """``comparison``: compare mode's second world (:mod:`sandbox.app.world.lockstep`); play, pause, step,
        reset and speed act on its :class:`~sandbox.app.world.lockstep.Lockstep`. ``events``: the app's event
        queue (:mod:`sandbox.app.web.events`), the only way in: work done in threads of its own puts its
        results there, and the timers are its. (Tests pass a stand-in that runs each event at once.)

        Each folder gets what it calls at construction; where two folders call each other, the one built
        first gets a function that finds the other when called."""
        gui = server.gui
        self.runner = runner
        self.comparison = comparison
        lockstep = comparison.lockstep
        #: How each viewer frames the floor (its View, the presenter layout), and what the presenter's
        #: screen adds to a page: its title card, its on-screen bar, its Start over offer.
        self.framing = Framing(runner, default_view, on_presenter=lambda client, shown: self.presenter.presenting(
            client, shown))
        self._last_refresh = 0.0
        self.parameters = ParametersFolder(gui, runner)
        self.metrics = MetricsFolder(gui, runner, compared=lambda: comparison.runner)
        self.run = RunFolder(gui, runner, lockstep, show_field=lambda on: view.set_show_field(on, runner.latest),
                             after_reset=self._after_reset, framing=self.framing,
                             after_skip=lambda arrival, client: self.result.explain_at(arrival, client))
        self.shape = ShapeFolder(gui, runner, server.scene, events=events, on_change=self.metrics.mark,
                                 reset=self.run.reset,
                                 back_to_defaults=lambda client: self.strategies.back_to_defaults(client),
                                 run_to_the_end=self._to_the_end)
        self.strategies = StrategiesFolder(gui, runner, use_shape=self.shape.use, on_change=self.metrics.mark,
                                           reset=self.run.reset)
        self.advice = AdviceFolder(gui, runner, use=self.strategies.use, events=events,
                                   run_to_the_end=self._afresh_to_the_end)
        self.program = ProgramFolder(gui, runner, server, allowed=allow_programs, on_change=self.metrics.mark,
                                     may_load=may_load_programs)
        self.lamp = LampFolder(gui, runner, on_change=self.metrics.mark)
        self.challenge = ChallengeFolder(gui, runner, lockstep, self.lamp, on_change=self.metrics.mark, events=events)
        self.compare = CompareFolder(gui, runner, comparison, on_change=self.metrics.mark, events=events)
        self.inspector = InspectorFolder(gui, runner, server, reframe=self.framing.apply)
        self.result = ResultFolder(gui, runner, server.scene, events=events)
        self.record = RecordFolder(gui, server, runner)
        #: Opens a design file uploaded in the Result folder (issue 56, item 7).
        self.opening = DesignOpener(runner, comparison, events=events, opened=self._design_opened,
                                    ended_comparison=lambda: self.metrics.mark("compare: off"))
        self.presenter = PresenterScreen(runner, lockstep, self.run, compared=lambda: comparison.runner, events=events)
        self.folders = (self.run, self.compare, self.shape, self.advice, self.strategies, self.program, self.lamp,
                        self.challenge, self.metrics, self.result, self.inspector, self.record, self.parameters,
                        self.presenter)
        snap = runner.latest
        self._build_legend(gui)
        for folder in self.folders:
            folder.build(snap)
        #: Learn's *Show me* buttons, one per strategy.
        self.show_me_buttons = self._build_learn(gui, self.show_me)
        server.scene.on_click()(self._on_scene_click)
        self.result.open_design.on_upload(lambda event: self.opening.take_upload(
            upload_name(event.file.name or "design.npz"), event.file.content, event.client))

    def update(self, snap: Snapshot, force: bool = False) -> None:
        """Refresh the read-outs (throttled to PANEL_HZ)."""
        now = time.perf_counter()
        if not force and now - self._last_refresh < 1.0 / PANEL_HZ:
            return
        self._last_refresh = now
        for folder in self.folders:
            folder.update(snap)

    def welcome(self, client: Any, controls: bool = True) -> None:
        """A page connected (``controls``: it may control the simulation): its own inspector, title card
        or Start over offer, and layout, and the drawing preview warmed up."""
        self.inspector.attach(client)
        self.presenter.arrive(client, controls)
        self.framing.arrive(client)
        self.shape.draw.warm_up()

    def farewell(self, client_id: int) -> None:
        """A page left: its own inspector and layout go with it."""
        self.inspector.detach(client_id)
        self.framing.forget(client_id)
        self.presenter.forget(client_id)

    def show_settings(self, config: Any) -> None:
        """The controls show ``config``: after a crash, the simulation went back to the last settings that
        ran (sandbox.app.world.standing), and the panel shows the settings that stand."""
        self.parameters.show_settings(config)
        self.strategies.show_settings(config)

    def on_frame_drawn(self) -> None:
        self.record.on_frame_drawn()

    def stop(self) -> list[threading.Thread]:
        """The app is stopping (on the event thread, which owns the workers' folders): the advisor's trials
        and the challenge's reference runs end now. Returns the workers still going, for the app to wait
        for off the event thread (they post to it as they end)."""
        return [*self.advice.stop(), *self.challenge.stop()]

    def _to_the_end(self, client: Any) -> None:
        """Run the world just built (a goal used, the advisor's best) to the Run folder's end step."""
        self.run.skip_ahead(int(self.run.end_step.value), client, new_world=True)

    def _afresh_to_the_end(self, client: Any) -> None:
        """A new world with the same seed (the settings just given), run to the Run folder's end step."""
        self.run.reset(client, on_done=lambda _: self._to_the_end(client))

    def _design_opened(self, design: Any, name: str, client: Any) -> None:
        """A design's world runs: the controls show its settings, the chart marks it, the drawing gives way."""
        self.show_settings(design.config)
        self.inspector.stop()
        self.shape.draw.give_way()
        self.metrics.mark(f"design {name}", 0)  # its first step

    def _after_reset(self, client: Any) -> None:
        self.inspector.stop()
        self.parameters.reset_done(client)
        self.metrics.mark("reset")

    @staticmethod
    def _build_legend(gui: Any) -> None:
        with gui.add_folder("Legend"):
            gui.add_image(legend.legend_picture(), format="png")
            gui.add_markdown("*Show sensed light* (in Run) paints the light the robots sense instead:")
            gui.add_image(legend.colour_bar_picture(), format="png")

    def _on_scene_click(self, event: Any) -> None:
        point = floor_point(event.ray_origin, event.ray_direction)
        if point is None:
            return
        if self.comparison.covers(point):
            return  # on the compared world: the shape, the lamp and the inspector act on the running one
        # The drawing picks its points and edges within a few of the clicking page's pixels: it needs the page.
        if not self.shape.draw.click(point, event.client) and not self.lamp.click(point, event.client):
            self.inspector.click(point, event.client)

    def show_me(self, without: str, with_it: str, client: Any) -> None:
        """Learn's *Show me*: the paper case ``without`` a strategy in this world, and beside it, from the
        same seed, the case ``with_it`` (compare mode)."""
        self.strategies.use_case(without, client, on_started=lambda: self.compare.choose(with_it, client))

    @staticmethod
    def _build_learn(gui: Any, show_me: Callable[[str, str, Any], None]) -> list:
        buttons = []
        with gui.add_folder("Learn", expand_by_default=False):
            gui.add_markdown(learn.INTRO)
            gui.add_image(learn.stored_picture("learn-phototaxis.png"), format="png")
            gui.add_markdown(learn.CYCLE)
            gui.add_image(learn.stored_picture("learn-cycle.png"), format="png")
            gui.add_markdown(learn.STRATEGIES)
            for paragraph, (without, with_it) in learn.STRATEGY_LESSONS:
                gui.add_markdown(paragraph)
                button = gui.add_button(f"Show me: {without} | {with_it}", icon=viser.Icon.COLUMNS,
                                        hint=f"Run {without} here and {with_it} beside it, from the same seed")
                button.on_click(lambda event, a=without, b=with_it: show_me(a, b, event.client))
                buttons.append(button)
            gui.add_markdown(learn.STRATEGIES_MORE)
            gui.add_image(learn.stored_picture("learn-strategies.png"), format="png")
            gui.add_markdown(learn.INSPECT)
        return buttons
