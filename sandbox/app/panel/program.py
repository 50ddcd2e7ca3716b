"""The Light program folder: hand the lights to a program of your own (a
``path.py:ClassName`` on the server's machine) and back, without a restart. Runs on the app's event thread.

A program that cannot be loaded is refused with one line and the running one
stays; one that fails while running (an exception, a pattern of the wrong
shape) hands the lights back to the paper's controller and every viewer is
told why. Loading runs a Python file on the server, so the server decides
who may: a page opened on the server's own machine, or any controlling page
with ``serve --allow-programs`` (:mod:`sandbox.app.web.access`). The controls are
the same on every page (viser's panel is shared), so a page that may not is
told why when it asks. Going back to the paper's controller is always
allowed to a controlling page.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import viser

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.world.orders import SetProgram
from sandbox.app.world.snapshot import Snapshot


#: What a page that may not load programs is told (the rule: sandbox.app.web.access.Access.local_page).
REFUSED = ("Loading light programs is not allowed from this page: only a page opened on the server's own "
           "machine may load them (not through a proxy, unless the server was started with --trust-proxy), "
           "or any page with the token if the server was started with --allow-programs.")


class ProgramFolder:
    def __init__(self, gui: Any, runner: Any, server: Any, *, allowed: bool, on_change: Any, may_load: Any = None):
        self.gui, self.runner, self.server = gui, runner, server
        #: Every controlling page may load a program (served to this machine alone, or --allow-programs);
        #: otherwise only some may (a page on this machine), and the folder says so.
        self.allowed, self._on_change = allowed, on_change
        #: may_load(client): whether that page may load a program (the server's gate decides, per page).
        self._may_load = may_load or (lambda client: allowed)
        #: How many failures of light programs the running simulation has counted, as announced. A
        #: restarted simulation process counts from nothing again: its first failure must be told too.
        self._errors_seen = 0
        self._shown: str | None = None
        on_crash = getattr(runner, "on_crash", None)  # a runner in a process of its own
        if on_crash is not None:
            on_crash(lambda why: self._count_afresh())

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Light program", expand_by_default=False):
            self.status = gui.add_markdown(self._status(snap))
            self.path = gui.add_text("Program", _example_spec(),
                                     hint="path/to/module.py:ClassName on the server's machine: a class with "
                                          "update(observation) returning one intensity per light")
            self.use = gui.add_button("Use this program", icon=viser.Icon.PLAYER_PLAY)
            self.back = gui.add_button("Back to the paper's controller", icon=viser.Icon.ARROW_BACK_UP)
            if not self.allowed:
                gui.add_markdown("*Shared beyond this machine: only a page opened on the server's own machine "
                                 "loads programs (start with* `serve --allow-programs` *to let every page with "
                                 "the token).*")

        @self.use.on_click
        def _(event: viser.GuiEvent) -> None:
            self.load(self.path.value.strip(), event.client)

        @self.back.on_click
        def _(event: viser.GuiEvent) -> None:
            self.load(None, event.client)

    def load(self, spec: str | None, client: Any) -> None:
        if spec is not None and not self._may_load(client):
            # Checked here, whatever the page shows: a program is a Python file run on this machine.
            notify_error(client, "Program not used", REFUSED)
            return
        if spec is not None:
            path, sep, name = spec.rpartition(":")
            if not sep or not path.endswith(".py") or not name:
                notify_error(client, "Program not used", f"{spec!r}: give path/to/module.py:ClassName")
                return

        def done(name: str) -> None:
            notify(client, "Light program", f"The lights follow {name} now.", "green")
            self._on_change(f"program {name}")

        def failed(exc: BaseException) -> None:
            notify_error(client, "Program not used", f"{exc} (the lights stay as they were)")

        self.runner.ask(SetProgram(spec), on_done=done, on_error=failed)

    def update(self, snap: Snapshot) -> None:
        text = self._status(snap)
        if text != self._shown:
            self.status.content = self._shown = text
        error = snap.program_error
        if (error[0] if error else 0) < self._errors_seen:  # fewer than seen: a new process counts afresh
            self._count_afresh()
        if error and error[0] > self._errors_seen:
            self._errors_seen = error[0]
            for client in self.server.get_clients().values():
                notify_error(client, "Light program stopped",
                             f"{error[1]}; the paper's controller lights the floor again.")

    def _count_afresh(self) -> None:
        """The simulation process was restarted: the next failure it counts is news."""
        self._errors_seen = 0

    @staticmethod
    def _status(snap: Snapshot) -> str:
        return f"**Lights:** {plain(snap.program)}"


def _example_spec() -> str:
    """The example program of a source checkout, as a path that works from where the server runs."""
    example = Path(__file__).resolve().parents[3] / "examples" / "shrinking_ring.py"
    try:
        shown = example.relative_to(Path.cwd())
    except ValueError:
        shown = example
    return f"{shown.as_posix()}:ShrinkingRing"
