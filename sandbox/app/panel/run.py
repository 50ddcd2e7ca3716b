"""The Run folder: play, step, reset, speed, the heat map switch, and status. Runs on the app's event thread."""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np
import viser

from sandbox.app.world.orders import Arrival, WantField
from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.framing import VIEWS, Framing
from sandbox.app.panel.plain import plain
from sandbox.app.world.runner import FASTEST
from sandbox.app.world.snapshot import Snapshot

#: Where *Run to the end* stops by default: the paper's runs are 100,000 steps.
DEFAULT_END = 100_000
MOST_END = 10_000_000


class RunFolder:
    def __init__(self, gui: Any, runner: Any, lockstep: Any, show_field: Callable[[bool], None],
                 after_reset: Callable[[Any], None], framing: Framing,
                 after_skip: Callable[[Arrival, Any], None] = lambda arrival, client: None):
        """Play, pause, step, reset, speed and *Run to the end* act on ``lockstep`` (the running world and,
        in compare mode, the second one); the rest reads ``runner``. ``after_skip(arrival, client)``: a run
        to the end arrived (the panel explains the result once a frame shows it)."""
        self.gui, self.runner, self.lockstep, self.framing = gui, runner, lockstep, framing
        self._show_field, self._after_reset, self._after_skip = show_field, after_reset, after_skip
        #: A run to the end under way: (its target step, when it started), else None.
        self._skipping: tuple[int, float] | None = None

    def build(self, snap: Snapshot) -> None:
        gui, runner = self.gui, self.runner
        with gui.add_folder("Run"):
            self.play = gui.add_button("Pause" if runner.playing else "Play",
                                       icon=viser.Icon.PLAYER_PAUSE if runner.playing else viser.Icon.PLAYER_PLAY,
                                       hint="Start or stop the simulation")
            self.step_button = gui.add_button("Step", icon=viser.Icon.PLAYER_TRACK_NEXT,
                                              hint="Advance one controller update (100 world steps, 3.3 s of "
                                                   "simulated time by default; pauses first)")
            self.reset_same = gui.add_button("Reset (same seed)", icon=viser.Icon.REFRESH,
                                             hint="Rebuild the world with the same seed: the same run again")
            self.reset_new = gui.add_button("Reset (new seed)", icon=viser.Icon.DICE,
                                            hint="Rebuild the world with a new random seed")
            self.speed = gui.add_slider("Steps per frame", 1, FASTEST, 1, runner.steps_per_frame,
                                        hint=f"Speed: world steps simulated between two pictures; {FASTEST}: as "
                                             "fast as the machine can, the pictures still at the frame rate")
            self.show_field = gui.add_checkbox("Show sensed light", False,
                                               hint="Show the luminosity field the robots sense, as a heat map, "
                                                    "instead of the light grid")
            self.view = gui.add_button_group("View", VIEWS,
                                             hint="Frame your own view on where the boxes are built, the whole "
                                                  "arena, or for a projector: panel folded, legend on the floor "
                                                  "(key p). Other pages keep theirs")
            self.end_step = gui.add_number("Run to step", DEFAULT_END, min=1, max=MOST_END, step=1000,
                                           hint="Where Run to the end stops (100,000: the paper's runs)")
            self.run_to_end = gui.add_button("Run to the end", icon=viser.Icon.PLAYER_SKIP_FORWARD,
                                             hint="Pause, run to that step without drawing, as fast as the "
                                                  "machine steps, then show the result")
            self.status = gui.add_markdown(self._status_text(snap))
            self.cancel = gui.add_button("Cancel building", icon=viser.Icon.X, visible=False,
                                         hint="Stop building the new world (the current one goes on), or stop "
                                              "running to the end where it got to")
        runner.on_progress(self._building)

        @self.cancel.on_click
        def _(event: viser.GuiEvent) -> None:
            self.lockstep.cancel()  # the builds it asked for, each by its id

        self.run_to_end.on_click(lambda event: self.skip_ahead(int(self.end_step.value), event.client))
        self.play.on_click(lambda event: self.toggle_play())
        self.step_button.on_click(lambda event: self.step())
        self.reset_same.on_click(lambda event: self._reset(None, event.client))
        # The same actions from the keyboard (and viser's command palette, Ctrl+K), for a presenter
        # standing at the projector.
        keys = (("space", "Play / pause", lambda event: self.toggle_play()),
                ("S", "Step", lambda event: self.step()),
                ("R", "Reset (same seed)", lambda event: self._reset(None, event.client)),
                ("P", "Presenter layout", lambda event: self.framing.toggle_presenter(event.client)))
        for key, label, action in keys:
            gui.add_command(label, hotkey=key, description=f"key: {key.lower()}").on_trigger(action)

        @self.reset_new.on_click
        def _(event: viser.GuiEvent) -> None:
            self._reset(int(np.random.default_rng().integers(0, 2**31 - 1)), event.client)

        @self.speed.on_update
        def _(event: viser.GuiEvent) -> None:
            self.lockstep.set_speed(int(self.speed.value))

        @self.view.on_click
        def _(event: viser.GuiEvent) -> None:
            self.frame(event.client, self.view.value)

        @self.show_field.on_update
        def _(event: viser.GuiEvent) -> None:
            runner.submit(WantField(bool(self.show_field.value)))  # the next snapshots carry the field
            self._show_field(self.show_field.value)

    def toggle_play(self) -> None:
        self.lockstep.set_playing(not self.lockstep.playing)
        self.sync_play_button()

    def pause(self) -> None:
        self.lockstep.set_playing(False)
        self.sync_play_button()

    def step(self) -> None:
        """One controller update, paused first."""
        self.pause()
        self.lockstep.step_once(self.runner.latest.world_config.update_every)

    def skip_ahead(self, step: int, client: Any, new_world: bool = False) -> None:
        """*Run to the end*: the world (both, in compare mode) to ``step`` without frames, then the result.
        ``new_world``: a world just built, at step 0 (*Use and run to the end*): the latest frame may
        still be the old world's, so its step says nothing about where this one is."""
        if self._skipping is not None:
            notify_error(client, "Already running to the end", "Wait for it, or press Cancel.")
            return
        if not new_world and step <= self.runner.latest.step:
            notify(client, "Already there", f"The world is at step {self.runner.latest.step:,}, past {step:,}.")
            return
        self._skipping = (int(step), time.monotonic())
        self.run_to_end.disabled = True
        # Paused first, as Step is: the floor then stays on the state the Result folder explains (a playing
        # world went on past it, the rings and the text soon about another state).
        self.pause()
        self._building(0.0)

        def arrived(arrival: Arrival) -> None:
            self._skipping = None
            self.run_to_end.disabled = False
            if arrival.cancelled:
                notify(client, "Stopped", f"Stopped at step {arrival.step:,}, as asked.")
            self._after_skip(arrival, client)

        def failed(exc: BaseException) -> None:
            self._skipping = None
            self.run_to_end.disabled = False
            notify_error(client, "Run to the end stopped", str(exc))

        self.lockstep.skip_ahead(step, on_done=arrived, on_error=failed)

    def frame(self, client: Any, view: str) -> None:
        """Lay one page out as ``view`` (the View buttons): its camera, and its panel and legend."""
        self.framing.choose(client, view)

    def _reset(self, seed: int | None, client: Any) -> None:
        self.reset(client, seed)

    def reset(self, client: Any, seed: int | None = None, *, on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException], None] | None = None) -> None:
        """A new world (``seed`` None: the same seed); a refusal or a cancel is told to ``client``."""

        def failed(exc: BaseException) -> None:
            cancelled = type(exc).__name__ == "BuildCancelled"
            (notify if cancelled else notify_error)(client, "Reset cancelled" if cancelled else "Reset refused",
                                                    str(exc))
            if on_error:
                on_error(exc)

        def done(result: Any) -> None:
            self._after_reset(client)
            if on_done:
                on_done(result)

        self.lockstep.reset(seed, on_done=done, on_error=failed)

    def _building(self, fraction: float | None) -> None:
        """Progress of a world being built, or of a run to the end (None: done). Every page sees it."""
        self._build_fraction = fraction
        self.cancel.visible = fraction is not None
        if fraction is None:
            return
        label = "Cancel building" if self._skipping is None else "Cancel the run to the end"
        if self.cancel.label != label:
            self.cancel.label = label
        if self._skipping is None:
            self.status.content = f"**Building the world:** {100 * fraction:.0f} % of the bodies placed"
            return
        target, since = self._skipping
        spent = time.monotonic() - since
        left = f", about {spent * (1 - fraction) / fraction:,.0f} s left" if fraction > 0.02 else ""
        self.status.content = (f"**Running to step {target:,} without drawing:** {100 * fraction:.0f} %{left}. "
                               "The floor shows the result when it gets there.")

    def update(self, snap: Snapshot) -> None:
        if getattr(self, "_build_fraction", None) is not None:
            return  # the status line shows the build
        self.status.content = self._status_text(snap)
        if self.play.label != ("Pause" if snap.playing else "Play"):
            self.sync_play_button()

    def sync_play_button(self) -> None:
        playing = self.runner.playing
        self.play.label = "Pause" if playing else "Play"
        self.play.icon = viser.Icon.PLAYER_PAUSE if playing else viser.Icon.PLAYER_PLAY

    def _status_text(self, snap: Snapshot) -> str:
        cfg, runner = snap.world_config, self.runner
        return (f"**Step** {snap.step:,} &nbsp; **time** {snap.time:,.1f} s  \n"
                f"**Phase** {snap.phase} &nbsp; **cycle** {snap.cycle}  \n"
                f"**Seed** {snap.seed} &nbsp; {cfg.robots} robots, {cfg.boxes} boxes, "
                f"goal *{plain(snap.shape_name)}*  \n"
                + (f"**Speed** {runner.steps_per_second():,.0f} steps/s "
                   f"({runner.steps_per_second() * cfg.dt:,.1f}x real time), "
                   f"{runner.frames_per_second():,.0f} frames/s sent" if snap.playing else "**Paused**"))
