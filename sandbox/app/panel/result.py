"""The Result folder: why the run stands where it does (issue 40, item 5). Runs on the app's event thread.

*Explain the result* says how many boxes are in the goal, where the others lie
(:mod:`sandbox.model.explain`: near the goal, heaped in a corner of the
construction area, against its wall, elsewhere), what 100 % would mean, and
which outline and strategies ran; and it rings the boxes outside the goal on
the floor, following them, until it is turned off or a new world starts.

After a run to the end the folder explains the result by itself and opens on
the page that asked, scrolled into view (:mod:`sandbox.app.web.page_open`): the
answer is not left below the fold in a closed folder (issue 56, item 4).

Runs on the app's event thread; a design file is packed in a worker, which
posts it back.
"""

from __future__ import annotations

import re
import threading
from typing import Any

import numpy as np
import viser

from sandbox.app.web import page_open
from sandbox.app.world.orders import Arrival, DesignOf
from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.world.snapshot import Snapshot, case_name
from sandbox.model.design import file_bytes
from sandbox.model.explain import PERFECT_PACKING, place_strays, strays_in_words

#: The rings around the boxes outside the goal: orange, under the boxes, wider than them.
RING_COLOUR = (255, 140, 0)
Z_RING = 0.015  # between the lit cells (0.01) and the boxes (0.02)
#: The folder's title, and the button that shows once it is open (the page script tells open from closed by it).
TITLE, EXPLAIN = "Result", "Explain the result"


def design_file_name(design: Any) -> str:
    """e.g. ``star-seed3-step100000-design.npz``."""
    shape = re.sub(r"[^A-Za-z0-9_-]+", "-", str(design.config.shape)).strip("-") or "goal"
    return f"{shape}-seed{design.seed}-step{design.steps_run}-design.npz"


def explanation(snap: Snapshot) -> str:
    """The result in a few lines of markdown (see the module's docstring)."""
    cfg = snap.world_config
    in_goal = np.asarray(snap.box_in_goal, bool)
    strays = place_strays(snap.box_positions, in_goal, snap.goal_outline, cfg.centre, cfg.construction_size,
                          2 * cfg.box_apothem)
    share = 100 * snap.sample.fraction_in_goal
    ran = plain(case_name(snap.shape_name, snap.strategies))
    outline = "the goal scaled" if snap.family == "scaled" else "the goal's edge at a distance (offset)"
    return (f"**{share:.1f} %** of the boxes are in the goal ({int(in_goal.sum())} of {len(in_goal)}) at step "
            f"{snap.step:,}. {strays_in_words(strays, 2 * cfg.box_apothem)} Ringed in orange on the floor.\n\n"
            f"{PERFECT_PACKING}\n\n**Ran:** {ran}; the band follows {outline}.")


class ResultFolder:
    def __init__(self, gui: Any, runner: Any, scene: Any, *, events: Any):
        """``events``: the app's event queue (:mod:`sandbox.app.web.events`; a design file is packed aside,
        and sent from there)."""
        self.gui, self.runner, self.scene, self._post = gui, runner, scene, events.post
        self.rings: Any = None
        self._world: int | None = None  # the world explained; a new one turns the rings off
        self._explain_at: tuple[int, int, Any] | None = None  # (world, step, page): explain the first frame there

    def build(self, snap: Snapshot) -> None:
        with self.gui.add_folder(TITLE, expand_by_default=False):
            self.text = self.gui.add_markdown("Where the boxes outside the goal lie, and what 100 % would mean.")
            self.explain_button = self.gui.add_button(EXPLAIN, icon=viser.Icon.HELP,
                                                      hint="Say where the boxes outside the goal lie and ring "
                                                           "them on the floor")
            self.highlight = self.gui.add_checkbox("Ring boxes outside the goal", False,
                                                   hint="Orange rings around the boxes outside the goal")
            self.download_design = self.gui.add_button(
                "Download design", icon=viser.Icon.DOWNLOAD,
                hint="One file: the goal, the settings, the seed and the light program that ran, every light "
                     "pattern with the step it started (phototaxis run --design FILE replays it; "
                     "docs/design-files.md)")
            # Its opener is sandbox.app.panel.opening, wired by the panel (issue 56, item 7).
            self.open_design = self.gui.add_upload_button(
                "Open design", icon=viser.Icon.UPLOAD, mime_type=".npz",
                hint="A design file (.npz, at most 1 MB): the world starts from its goal, settings and seed, lit "
                     "by its recorded light program, as serve --design starts it")
        self.explain_button.on_click(lambda event: self.explain())
        self.download_design.on_click(lambda event: self.send_design(event.client))
        self.highlight.on_update(lambda event: self._show_rings(self.runner.latest))

    def explain(self, snap: Snapshot | None = None) -> str:
        """Explain the running world's result now, and ring its stray boxes."""
        snap = snap or self.runner.latest
        self.text.content = text = explanation(snap)
        self._world = snap.world_key
        self.highlight.value = True
        self._show_rings(snap)
        return text

    def send_design(self, client: Any) -> None:
        """The running world's design, as a file for ``client`` (packed in a thread of its own: a long
        light program takes a while to compress)."""

        def pack(design: Any) -> None:
            def packed() -> None:
                data = file_bytes(design)
                self._post(lambda: client.send_file_download(design_file_name(design), data, save_immediately=True))

            threading.Thread(target=packed, name="design-packer", daemon=True).start()

        self.runner.ask(DesignOf(), on_done=pack, on_error=lambda exc: notify_error(client, "No design to download",
                                                                                    str(exc)))

    def explain_at(self, arrival: Arrival, client: Any = None) -> None:
        """Explain the world a run to the end arrived in once a frame at its step or later shows it (the
        answer comes before that frame; after a reset, before any frame of its world: its key is the
        arrival's, not the last frame's), and tell ``client`` the share."""
        self._explain_at = (arrival.world_key, int(arrival.step), client)

    def update(self, snap: Snapshot) -> None:
        if self._explain_at is not None:
            world, step, client = self._explain_at
            if snap.world_key > world:  # a newer world (keys only grow); an older one's frame may still come
                self._explain_at = None
            elif snap.world_key == world and snap.step >= step:
                self._explain_at = None
                self.explain(snap)
                notify(client, "Run to the end", f"Step {snap.step:,}: {100 * snap.sample.fraction_in_goal:.1f} % of "
                       "the boxes in the goal. The Result folder says where the others lie (ringed in orange).",
                       "green")
                page_open.open_folder(client, TITLE, EXPLAIN)  # the answer in view on the page that asked
                return
        if self.highlight.value and self._world is not None and snap.world_key != self._world:
            self.highlight.value = False  # a new world: the old explanation no longer holds
            self.text.content = "A new world started: press *Explain the result* again."
        self._show_rings(snap)

    def _show_rings(self, snap: Snapshot) -> None:
        outside = snap.box_positions[~np.asarray(snap.box_in_goal, bool)] if self.highlight.value else None
        if outside is None or len(outside) == 0:
            if self.rings is not None:
                self.rings.visible = False
            return
        points = np.zeros((len(outside), 3), np.float32)
        points[:, :2] = outside
        if self.rings is None:
            self.rings = self.scene.add_point_cloud(
                "/result/strays", points, RING_COLOUR, point_size=1.6 * snap.world_config.box_circumradius,
                point_shape="circle", point_shading="flat", position=(0.0, 0.0, Z_RING))
        else:
            self.rings.points = points
            self.rings.visible = True
