"""Open a design file in the page (issue 56, item 7): the world starts from the design's goal, settings
and seed, lit by its recorded light program, as ``serve --design`` starts it. Runs on the app's event
thread; the uploaded file is read in a worker thread, which posts what it read back.

A design is data, like a polygon file: it replays recorded light patterns, no code, so it is read in the
server by the model's bounded, checked loader (:func:`sandbox.model.design.load_bytes`: sizes checked
before anything is unpacked, docs/design-files.md) within the upload's 1 MB (sandbox.app.web.inbox). It
changes the world, so only a page that may control opens one: the button is a control, which the gate
refuses to a page that only watches. A damaged file, or a goal this server cannot build, is one line on
the page that sent it; the running world goes on untouched.
"""

from __future__ import annotations

import logging
import threading
from typing import Any, Callable

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.world.orders import PlayDesign
from sandbox.model.design import DesignError, load_bytes
from sandbox.model.goal import fit_goal
from sandbox.shapes import ShapeError

#: The title of a refused design: viser's own notice beside it says the file arrived, which it did.
REFUSED = "File received, design not opened"

log = logging.getLogger("sandbox.app.panel.opening")


def read_design(name: str, content: bytes) -> tuple[Any, str]:
    """(the design, '') or (None, why not in one line): the file checked, and its goal fitted as the
    simulation will fit it (a goal it cannot build is refused here, as ``serve --design`` refuses it)."""
    try:
        design = load_bytes(content, name)
    except DesignError as exc:
        return None, str(exc)
    except Exception as exc:  # noqa: BLE001 - whatever happened, the page hears of it and the run goes on
        log.exception("design %r could not be read", name)
        return None, f"{name}: could not be read ({type(exc).__name__})"
    try:
        fit_goal(design.config, design.shape)
    except ShapeError as exc:
        return None, f"{name}: its goal: {exc}"
    return design, ""


def opened_words(name: str, design: Any) -> str:
    """What the notice says of a design opened."""
    return (f"{name}: its goal ({design.config.shape}), settings and seed {design.seed}, from step 0, lit by its "
            f"recorded light program ({len(design.steps):,} light patterns over {design.steps_run:,} steps; "
            "past them the last stays lit). Light program hands the floor back to the paper's controller.")


class DesignOpener:
    """Opens uploaded design files. ``ended_comparison()``: compare mode ended (a design opens one world);
    ``opened(design, name, client)``: the panel shows the design's settings once its world runs."""

    def __init__(self, runner: Any, comparison: Any, *, events: Any, opened: Callable[[Any, str, Any], None],
                 ended_comparison: Callable[[], None] = lambda: None):
        self.runner, self.comparison, self._events = runner, comparison, events
        self._opened, self._ended_comparison = opened, ended_comparison

    def take_upload(self, name: str, content: bytes, client: Any) -> None:
        """An uploaded design file (its name already cleaned): read aside, then opened or refused on the
        event thread; nothing waits for it meanwhile."""

        def read() -> None:
            self._events.post(self._take_read, name, read_design(name, content), client)

        threading.Thread(target=read, name="design-reader", daemon=True).start()

    def _take_read(self, name: str, read: tuple[Any, str], client: Any) -> None:
        design, problem = read
        if problem:
            notify_error(client, REFUSED, problem)
            return
        if self.comparison.runner is not None:  # one world, as serve --design (which refuses --compare)
            self.comparison.end()
            self._ended_comparison()

        def played(program: str) -> None:
            self._opened(design, name, client)
            notify(client, "Design opened", opened_words(name, design), "green")

        self.runner.ask(PlayDesign(design), on_done=played,
                        on_error=lambda exc: notify_error(client, REFUSED, f"{name}: {exc}"))
