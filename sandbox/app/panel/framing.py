"""How each viewer frames the floor: the construction area, the whole arena,
or the presenter layout (issue 24, item 5).

The presenter layout is for a projector: this viewer's panel collapses to
its bar, and its camera frames the construction area with the legend drawn
on the floor beside it (the panel, and its legend, being out of the way).
Each viewer chooses for itself, like its
camera; ``serve --classroom`` starts every page in it. A portrait view (a
phone) has no room beside the construction area: there the presenter layout
frames the construction area alone, with the legend in the panel.
"""

from __future__ import annotations

import threading
from typing import Any

from sandbox.app.legend import legend_picture
from sandbox.app.scene import PHONE_ASPECT, add_floor_legend, aim_camera, frame_arena, presenter_camera

CONSTRUCTION = "Construction area"
WHOLE_ARENA = "Whole arena"
PRESENTER = "Presenter"
#: The View buttons: each frames the clicking page's own camera.
VIEWS = (CONSTRUCTION, WHOLE_ARENA, PRESENTER)


class Framing:
    """Each viewer's view (one of :data:`VIEWS`), and what the presenter layout adds to its page."""

    def __init__(self, runner: Any, default: str = WHOLE_ARENA):
        if default not in VIEWS:
            raise ValueError(f"unknown view {default!r}: one of {', '.join(VIEWS)}")
        self.runner, self.default = runner, default
        #: Compare mode: how far right of the running world the second one lies (m), framed with it.
        self.beside: float | None = None
        self._views: dict[int, str] = {}
        self._legends: dict[int, Any] = {}
        self._lock = threading.RLock()
        picture = legend_picture()
        self._legend_aspect = picture.shape[0] / picture.shape[1]

    def of(self, client_id: int) -> str:
        with self._lock:
            return self._views.get(client_id, self.default)

    def choose(self, client: Any, view: str) -> None:
        """This viewer frames the floor as ``view`` from now on; its page is laid out for it."""
        if client is None or view not in VIEWS:
            return
        with self._lock:
            was = self.of(client.client_id)
            self._views[client.client_id] = view
            if view == PRESENTER and was != PRESENTER:
                client.gui.main_panel.minimize()
            elif view != PRESENTER and was == PRESENTER:
                client.gui.main_panel.expand()
        self.apply(client)

    def toggle_presenter(self, client: Any) -> None:
        """The presenter layout, or back from it to the construction area (the P key)."""
        if client is not None:
            self.choose(client, CONSTRUCTION if self.of(client.client_id) == PRESENTER else PRESENTER)

    def apply(self, client: Any) -> None:
        """Frame this viewer's camera for its view and window; the presenter's legend on its floor.

        All of it under the lock, from reading the view to moving the camera: the server's fit thread
        applies a page's view as its window reports its shape, and a View button chosen meanwhile
        must not be framed first and then overwritten by the view the fit read before it (seen on a
        loaded machine: the whole arena chosen, the presenter's camera left)."""
        config = self.runner.latest.world_config
        aspect = float(getattr(client.camera, "aspect", 0.0) or 1.4)
        with self._lock:
            view = self.of(client.client_id)
            presenter = view == PRESENTER and aspect >= PHONE_ASPECT
            self._show_legend(client, config, presenter)
            if not presenter:
                frame_arena(client, config, whole=view == WHOLE_ARENA, beside=self.beside)
                return
            aim_camera(client, *presenter_camera(config, aspect, self._legend_aspect, beside=self.beside))

    def arrive(self, client: Any) -> None:
        """A page that connected: the default view's layout (its camera is framed as it reports its shape)."""
        if self.of(client.client_id) == PRESENTER:
            client.gui.main_panel.minimize()

    def forget(self, client_id: int) -> None:
        with self._lock:
            self._views.pop(client_id, None)
            self._legends.pop(client_id, None)

    def _show_legend(self, client: Any, config: Any, shown: bool) -> None:
        """The legend on this viewer's floor (placed for the world's construction area), or none."""
        place = (config.centre, config.construction_size)
        legend, placed_for = self._legends.get(client.client_id, (None, None))
        if legend is not None and (not shown or placed_for != place):
            legend.remove()
            del self._legends[client.client_id]
            legend = None
        if shown and legend is None:
            self._legends[client.client_id] = (add_floor_legend(client.scene, config, presenter=True), place)
