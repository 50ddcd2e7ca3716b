"""The Be the light folder: a student, not the controller, decides which
lights are on (issue 25, item 2). Runs on the app's event thread.

*Be the light* hands the floor to a lamp, a disc of lights that moves to
wherever a controlling page clicks the floor; its radius is a slider. *A
click* can instead paint lights on or erase them, like a brush, keeping the
others (:mod:`sandbox.model.lamp`). The
robots follow, charge and drain as always, and the goal and metrics show as
always. *Give the light back* (or the Light program folder's *Back to the
paper's controller*) returns the floor to the paper's controller, keeping
the world. The lamp is one, like the world: any controlling page moves it;
a watching page's clicks are refused by the server like its other clicks.
"""

from __future__ import annotations

from typing import Any

import viser

from sandbox.app.panel.common import notify_error
from sandbox.app.world.orders import SetLamp
from sandbox.app.world.snapshot import LAMP_PROGRAM, Snapshot
from sandbox.model.lamp import DEFAULT_RADIUS, ERASE, LAMP, LARGEST_RADIUS, PAINT, SMALLEST_RADIUS

HELP = ("Press *Be the light*, then click the floor: the lights there come on. Robots that see them "
        "drive in and charge. Move the lamp a little at a time to lead them.")
#: What a click on the floor does, as the page says it.
CLICKS = {"moves the lamp": LAMP, "paints lights on": PAINT, "erases lights": ERASE}


class LampFolder:
    def __init__(self, gui: Any, runner: Any, on_change: Any):
        self.gui, self.runner, self._on_change = gui, runner, on_change
        #: Where the last click put the lamp (a resize keeps it there).
        self._centre: tuple[float, float] | None = None

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Be the light", expand_by_default=False):
            gui.add_markdown(HELP)
            self.toggle = gui.add_button("Be the light", icon=viser.Icon.BULB,
                                         hint="The lights are yours: click the floor to move the lamp (the "
                                              "world stays as it is)")
            self.radius = gui.add_slider("Lamp radius (m)", SMALLEST_RADIUS, LARGEST_RADIUS, 0.5, DEFAULT_RADIUS,
                                         hint="How far from where you click the lights come on (or go off)")
            self.click_does = gui.add_dropdown("A click", tuple(CLICKS), initial_value="moves the lamp",
                                               hint="Move the lamp (only its lights on), or paint lights on and "
                                                    "erase them like a brush, keeping the others")

        @self.toggle.on_click
        def _(event: viser.GuiEvent) -> None:
            if self.on:
                self._set(None, event.client)
            else:  # on at the middle of the floor until the first click
                centre = self.runner.latest.world_config.centre
                self._set((centre, centre), event.client)

        @self.radius.on_update
        def _(event: viser.GuiEvent) -> None:
            if self.on and self._centre is not None and self._mode == LAMP:  # the lamp resized where it is
                self._set(self._centre, event.client)

    @property
    def on(self) -> bool:
        return self.runner.latest.program == LAMP_PROGRAM

    def click(self, point: tuple[float, float], client: Any) -> bool:
        """A click on the floor: moves the lamp there while the student is the light (True), else False."""
        if not self.on:
            return False
        self._set((float(point[0]), float(point[1])), client)
        return True

    @property
    def _mode(self) -> str:
        return CLICKS.get(self.click_does.value, LAMP)

    def _set(self, centre: tuple[float, float] | None, client: Any) -> None:
        self._centre = centre
        was_on = self.on
        mode = LAMP if centre is not None and not was_on else self._mode  # switched on: the lamp, lit

        def done(program: str) -> None:
            on = program == LAMP_PROGRAM
            self._sync(on)
            if on != was_on:  # a dot on the charts where the lamp came or went, not at every move
                self._on_change("be the light" if on else "the paper's controller")

        self.runner.ask(SetLamp(centre, float(self.radius.value), mode),
                        on_done=done, on_error=lambda exc: notify_error(client, "Lamp not used", str(exc)))

    def update(self, snap: Snapshot) -> None:
        self._sync(snap.program == LAMP_PROGRAM)

    def _sync(self, on: bool) -> None:
        label = "Give the light back" if on else "Be the light"
        if self.toggle.label != label:
            self.toggle.label = label
            self.toggle.icon = viser.Icon.BULB_OFF if on else viser.Icon.BULB
