"""The parameter folders, generated from the model's declaration
(:func:`sandbox.model.config.params`): the Model folder (the profile and
every value it sets) first, then one folder per group. Values that need a
new world wait for the next reset and are listed until then. Runs on the app's event thread.

One group shows at a time, picked in the *group* dropdown. viser draws
nothing for a hidden folder, but it draws every control of a collapsed
one, and a new page draws the whole panel in one task before it shows
anything: all eight groups (62 controls, 17 of them dropdowns) cost a
first visit about 0.35 s."""

from __future__ import annotations

from typing import Any

import numpy as np
import viser

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.panel.tips import tip
from sandbox.app.world.orders import UpdateConfig
from sandbox.app.world.snapshot import Snapshot
from sandbox.model.config import STRATEGY_NAMES, Config, ConfigError, params

#: Parameters that get their own controls elsewhere (or make no sense live).
NOT_IN_PARAMETER_FOLDERS = {"shape", "steps", *STRATEGY_NAMES}
GROUP_TITLES = {"bodies": "Population and bodies", "robot": "Robot: gains and energy", "lights": "Light grid",
                "controller": "Controller cycle", "arena": "Arena", "run": "Run", "physics": "Physics engine",
                "model": "Model: the authors' program or the paper's text"}
GROUP_ORDER = ("model", "bodies", "robot", "lights", "controller", "arena", "run", "physics")
MODEL_HELP = ("The paper's text and the authors' released program differ in about twenty places; the "
              "program produced the paper's tables. **profile** sets all of the values below at once "
              "(on reset); each can then be changed on its own.")


#: The group shown until another is picked: the population, the setting most often changed.
SHOWN_FIRST = "bodies"


def parameter_groups() -> dict[str, list]:
    """The parameters with controls in this folder, by group, in GROUP_ORDER. Every value a profile
    sets sits with the profile (the model group), so a change of profile shows them together."""
    groups: dict[str, list] = {}
    for p in params():
        if p.name not in NOT_IN_PARAMETER_FOLDERS:
            groups.setdefault("model" if p.profiled else p.group, []).append(p)
    return {group: groups[group] for group in GROUP_ORDER if group in groups}


class ParametersFolder:
    def __init__(self, gui: Any, runner: Any):
        self.gui, self.runner = gui, runner
        self.controls: dict[str, Any] = {}
        self.waiting: list[str] = []  # names waiting for a reset, as the runner last said
        self._quiet = False  # the panel itself is setting the controls (show_settings): nothing to send

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Population and physics", expand_by_default=False):
            self.pending = gui.add_markdown("")
            groups = parameter_groups()
            titles = [GROUP_TITLES[group] for group in groups]
            self.group = gui.add_dropdown("group", titles, initial_value=GROUP_TITLES[SHOWN_FIRST],
                                          hint="Which group of parameters to show; the others keep their values")
            self.group_folders: dict[str, Any] = {}
            for group, members in groups.items():
                title = GROUP_TITLES[group]
                with gui.add_folder(title, visible=group == SHOWN_FIRST) as folder:
                    self.group_folders[title] = folder
                    if group == "model":
                        gui.add_markdown(MODEL_HELP)
                    for p in members:
                        self.controls[p.name] = self._control(p, getattr(snap.config, p.name))

        @self.group.on_update
        def _(event: viser.GuiEvent) -> None:
            self.show_group(self.group.value)

    def show_group(self, title: str) -> None:
        """Show one group's folder and hide the others (on every page: the panel is shared)."""
        if title not in self.group_folders:
            raise ValueError(f"no parameter group {title!r}")
        for name, folder in self.group_folders.items():
            folder.visible = name == title

    def update(self, snap: Snapshot) -> None:
        pass  # the controls are the state; nothing to refresh

    def reset_done(self, client: Any) -> None:
        if self.waiting:
            notify(client, "Reset", "Applied: " + ", ".join(self.waiting), "green")
        self.waiting = []
        self.pending.content = ""

    def _control(self, p: Any, value: Any) -> Any:
        gui = self.gui
        label = _label(p)
        hint = tip(p.name, p.rebuild)
        if p.choices:
            handle = gui.add_dropdown(label, tuple(p.choices), initial_value=value, hint=hint)
        elif p.type is int:
            handle = gui.add_number(label, int(value), min=int(p.low) if p.low is not None else None,
                                    max=int(p.high) if p.high is not None else None, step=1, hint=hint)
        else:
            handle = gui.add_number(label, float(value), min=p.low, max=p.high, step=_step_for(float(value)),
                                    hint=hint)

        @handle.on_update
        def _(event: viser.GuiEvent) -> None:
            self._changed(p.name, handle, event.client)

        return handle

    def show_settings(self, config: Config) -> None:
        """Every control shows ``config``'s value, nothing waits for a reset: the settings that stand
        after the simulation went back to the last that ran (sandbox.app.world.standing)."""
        self._quiet = True
        try:
            for name, handle in self.controls.items():
                handle.value = getattr(config, name)
        finally:
            self._quiet = False
        self.waiting = []
        self.pending.content = ""

    def _changed(self, name: str, handle: Any, client: Any) -> None:
        if self._quiet:
            return
        value = handle.value

        def done(result: tuple[list[str], Config]) -> None:
            self.waiting, settings = result
            if name == "profile":
                self._show_profile_values(settings)
            if self.waiting:
                self.pending.content = ("**Applies on reset:** " + plain(", ".join(self.waiting)) +
                                        " (press *Reset* in Run)")
            if name in self.waiting:
                notify(client, "Applies on reset", f"{name} = {value} takes effect when you press Reset.", "yellow")

        def failed(exc: BaseException) -> None:
            notify_error(client, f"{name} not changed", str(exc))
            # Put the control back to the value in force.
            handle.value = getattr(self.runner.latest.config, name)

        # The server decides before the simulation hears of it: settings whose world would not fit the
        # memory budget (sandbox.model.budget), or that are refused for any other reason, go no further.
        # The simulation checks again (it knows the changes waiting for a reset that no snapshot shows yet).
        try:
            self.runner.latest.config.replace(**{name: value})
        except ConfigError as exc:
            failed(exc)
            return
        self.runner.ask(UpdateConfig({name: value}), on_done=done, on_error=failed)

    def _show_profile_values(self, settings: Config) -> None:
        """After a change of profile, show the values it set (they apply on reset)."""

        for p in params():
            handle = self.controls.get(p.name)
            if p.profiled and handle is not None and handle.value != getattr(settings, p.name):
                handle.value = getattr(settings, p.name)


def _step_for(value: float) -> float:
    if value == 0:
        return 0.01
    magnitude = 10 ** np.floor(np.log10(abs(value)))
    return float(magnitude / 100)


def _label(p: Any) -> str:
    """The control's name with its unit, e.g. ``update every (steps)``; a
    name that already says its unit (``hold steps``) does not repeat it."""
    name = p.name.replace("_", " ")
    if not p.unit or name.endswith(p.unit):
        return name
    return f"{name} ({p.unit})"
