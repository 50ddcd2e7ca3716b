"""How each viewer frames the floor: the construction area, the whole arena,
or the presenter layout (issue 24, item 5). Runs on the app's event thread.

The presenter layout is for a projector: this viewer's panel collapses to
its bar, and its camera frames the construction area with the legend drawn
on the floor beside it (the panel, and its legend, being out of the way).
Each viewer chooses for itself, like its
camera; ``serve --classroom`` starts every page in it. A portrait view (a
phone) has no room beside the construction area: there the presenter layout
frames the construction area alone, with the legend in the panel.

In compare mode every view frames both worlds (issue 41, item 1): the whole
arenas, or both construction areas with their captions, readouts and the
difference between them; the presenter's legend then lies on the floor
between the worlds (or left of them, stacked).

Runs on the app's event thread, which owns every page's view and legend.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from sandbox.app.view.legend import legend_picture
from sandbox.app.world.snapshot import LAMP_PROGRAM
from sandbox.app.view.scene import (PHONE_ASPECT, add_floor_legend, aim_camera, compare_camera, compare_legend_box,
                               frame_arena, presenter_camera)

CONSTRUCTION = "Construction area"
WHOLE_ARENA = "Whole arena"
PRESENTER = "Presenter"
#: The View buttons: each frames the clicking page's own camera.
VIEWS = (CONSTRUCTION, WHOLE_ARENA, PRESENTER)


def lit_by_hand(snap: Any) -> tuple[float, float, float, float] | None:
    """The floor a person's lamp (or brush) lights, its lit cells' extent (left, right, bottom, top), or
    None: a phone's view framed again as its drawer opens or closes frames it too (the drawer opened
    over the lamp: issue 56, item 16)."""
    if getattr(snap, "program", None) != LAMP_PROGRAM or snap.intensities is None or not snap.intensities.any():
        return None
    cells, pitch = np.argwhere(snap.intensities > 0), snap.world_config.light_pitch
    (x0, y0), (x1, y1) = cells.min(axis=0) * pitch, (cells.max(axis=0) + 1) * pitch
    return float(x0), float(x1), float(y0), float(y1)


class Framing:
    """Each viewer's view (one of :data:`VIEWS`), and what the presenter layout adds to its page."""

    def __init__(self, runner: Any, default: str = WHOLE_ARENA,
                 on_presenter: Callable[[Any, bool], None] = lambda client, shown: None):
        """``on_presenter(client, shown)`` hears a page enter (True) or leave the presenter layout (its
        on-screen bar: :mod:`sandbox.app.panel.presenter`)."""
        if default not in VIEWS:
            raise ValueError(f"unknown view {default!r}: one of {', '.join(VIEWS)}")
        self.runner, self.default, self.on_presenter = runner, default, on_presenter
        #: Compare mode: where the second world lies (m along the floor from the running one), framed with it.
        self.offset: tuple[float, float] | None = None
        self._views: dict[int, str] = {}
        self._legends: dict[int, Any] = {}
        picture = legend_picture()
        self._legend_aspect = picture.shape[0] / picture.shape[1]

    def of(self, client_id: int) -> str:
        return self._views.get(client_id, self.default)

    def choose(self, client: Any, view: str) -> None:
        """This viewer frames the floor as ``view`` from now on; its page is laid out for it."""
        if client is None or view not in VIEWS:
            return
        was = self.of(client.client_id)
        self._views[client.client_id] = view
        if view == PRESENTER and was != PRESENTER:
            client.gui.main_panel.minimize()
        elif view != PRESENTER and was == PRESENTER:
            client.gui.main_panel.expand()
        if (view == PRESENTER) != (was == PRESENTER):
            self.on_presenter(client, view == PRESENTER)
        self.apply(client)

    def toggle_presenter(self, client: Any) -> None:
        """The presenter layout, or back from it to the construction area (the P key)."""
        if client is not None:
            self.choose(client, CONSTRUCTION if self.of(client.client_id) == PRESENTER else PRESENTER)

    def apply(self, client: Any, lamp_in_view: bool = False) -> None:
        """Frame this viewer's camera for its view and window; the presenter's legend on its floor;
        ``lamp_in_view``: a lit lamp too (a phone whose drawer opened or closed over it).

        All of it in one event of the app's event thread, from reading the view to moving the camera:
        a View button chosen while a page's camera is fitted is framed after the fit, never overwritten
        by a view read before it (seen on a loaded machine when the fitting ran in a thread of its own:
        the whole arena chosen, the presenter's camera left)."""
        snap = self.runner.latest
        config = snap.world_config
        aspect = float(getattr(client.camera, "aspect", 0.0) or 1.4)
        view = self.of(client.client_id)
        presenter = view == PRESENTER and (aspect >= PHONE_ASPECT or self.offset is not None)
        self._show_legend(client, config, presenter)
        if self.offset is not None:
            aim_camera(client, *compare_camera(config, aspect, self.offset, whole=view == WHOLE_ARENA,
                                               legend_height_per_width=self._legend_aspect if presenter
                                               else None))
        elif presenter:
            aim_camera(client, *presenter_camera(config, aspect, self._legend_aspect,
                                                 also=lit_by_hand(snap) if lamp_in_view else None))
        elif lamp_in_view and lit_by_hand(snap) is not None:
            frame_arena(client, config, whole=view == WHOLE_ARENA, also=lit_by_hand(snap))
        else:
            frame_arena(client, config, whole=view == WHOLE_ARENA)

    def arrive(self, client: Any) -> None:
        """A page that connected: the default view's layout (its camera is framed as it reports its shape).
        The presenter's legend goes on its floor at once, with the rest of the first frame, not when the
        page first reports its window (seconds later on a loaded machine; a phone's report takes it away)."""
        if self.of(client.client_id) == PRESENTER:
            client.gui.main_panel.minimize()
            self.on_presenter(client, True)
            self._show_legend(client, self.runner.latest.world_config, True)

    def forget(self, client_id: int) -> None:
        self._views.pop(client_id, None)
        self._legends.pop(client_id, None)

    def _show_legend(self, client: Any, config: Any, shown: bool) -> None:
        """The legend on this viewer's floor (placed for the world's construction area, and in compare
        mode between the worlds), or none."""
        place = (config.centre, config.construction_size, self.offset)
        legend, placed_for = self._legends.get(client.client_id, (None, None))
        if legend is not None and (not shown or placed_for != place):
            legend.remove()
            del self._legends[client.client_id]
            legend = None
        if shown and legend is None:
            box = None if self.offset is None else compare_legend_box(config, self.offset, self._legend_aspect)
            self._legends[client.client_id] = (add_floor_legend(client.scene, config, presenter=True, box=box), place)
