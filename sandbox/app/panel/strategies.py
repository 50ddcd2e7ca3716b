"""The Strategies folder: a checkbox and an amount per strategy, generated
from their declaration (:data:`sandbox.model.config.STRATEGIES`)."""

from __future__ import annotations

import functools
from typing import Any

from sandbox.app.panel.common import notify_error
from sandbox.app.snapshot import Snapshot
from sandbox.model.config import STRATEGIES
from sandbox.model.simulation import Simulation


class StrategiesFolder:
    def __init__(self, gui: Any, runner: Any):
        self.gui, self.runner = gui, runner
        self.controls: dict[str, tuple[Any, Any]] = {}

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Strategies"):
            gui.add_markdown("Changes reach the running simulation at the next controller update; no reset.")
            for s in STRATEGIES:
                value = getattr(snap.config, s.name)
                on = gui.add_checkbox(s.label, value > 0, hint=s.help)
                amount = gui.add_slider(f"{s.label} amount", s.step, s.high, s.step,
                                        float(value if value > 0 else s.on_value), hint=s.help)
                self.controls[s.name] = (on, amount)
                on.on_update(lambda event, n=s.name: self._changed(n, event.client))
                amount.on_update(lambda event, n=s.name: self._changed(n, event.client))

    def update(self, snap: Snapshot) -> None:
        pass  # the controls are the state; nothing to refresh

    def _changed(self, name: str, client: Any) -> None:
        on, amount = self.controls[name]
        value = float(amount.value) if on.value else 0.0

        def failed(exc: BaseException) -> None:
            notify_error(client, "Strategy not changed", str(exc))

        self.runner.post(functools.partial(Simulation.set_strategies, **{name: value}), on_error=failed)
