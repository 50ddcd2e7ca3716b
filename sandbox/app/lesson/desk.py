"""A student's desk: the panel and the floor everybody knows, on their page alone, for their world.
Built and drawn on the app's event thread.

The same :class:`~sandbox.app.panel.Panel` and :class:`~sandbox.app.view.scene.SceneView` as the
single world's, built on the page's own GUI and scene (:class:`~sandbox.app.lesson.pages.OnePage`),
with light programs refused (they run Python on the server). A page that reloads gets a new desk for
the same world; a desk ends with its page.
"""

from __future__ import annotations

from typing import Any

from sandbox.app.lesson.pages import OnePage
from sandbox.app.panel import Panel
from sandbox.app.panel.plain import plain
from sandbox.app.panel.framing import WHOLE_ARENA
from sandbox.app.view.partner import Comparison
from sandbox.app.view.scene import SceneView, aim_camera, top_down_camera
from sandbox.app.world.snapshot import Snapshot



def configure_page(page: Any, config: Any) -> None:
    """What the shared page gets once, sent to this page: the theme, the docked panel, the floor's lights
    and camera."""
    page.gui.configure_theme(dark_mode=True, control_width="large", show_logo=False, show_share_button=False,
                             brand_color=(255, 190, 40))
    page.gui.main_panel.dock_right()
    page.gui.main_panel.set_width(420)
    # As configure_scene (sandbox.app.view.scene) sets the shared scene, but for one page: its world axes
    # are the shared scene's node (never sent to a student's page), its camera is its own.
    scene = page.scene
    scene.set_up_direction("+z")
    scene.configure_default_lights(False)
    scene.configure_environment_map(None)
    scene.add_light_ambient("/ambient", intensity=3.14159)
    position, look_at, fov = top_down_camera(config)
    camera = page.client.camera
    camera.far = float(top_down_camera(config)[0][2] * 8)
    aim_camera(page.client, position, look_at, fov)


class Desk:
    """One page's panel and floor for one student's world (``world``: its runner, lockstep and the
    compared world's maker)."""

    def __init__(self, client: Any, world: Any, label: str, *, events: Any):
        self.client, self.world = client, world
        page = self.page = OnePage(client)
        first = world.runner.latest
        with client.atomic():
            configure_page(page, first.world_config)
            self.title = page.gui.add_markdown(f"**{plain(label)}**: your own world. Your teacher sees it on the wall.")
        self.view = SceneView(page.scene, first)
        self.comparison = Comparison(page, world.lockstep, world.make_runner, on_layout=self._reframe, events=events)
        self.panel = Panel(page, world.runner, self.view, self.comparison, events=events, allow_programs=False,
                           may_load_programs=lambda client: False, default_view=WHOLE_ARENA)
        # A recording is the shared scene's (viser serializes the server's scene only): the teacher's.
        self.panel.record.button.disabled = True
        self.panel.record.status.content = "Recording is on your teacher's page."
        self.panel.welcome(client, controls=True)
        self._fitted: float | None = None  # the window's shape (width / height) the camera was framed for
        client.camera.on_update(lambda camera: self._fit())
        self._fit()

    def draw(self, snap: Snapshot) -> None:
        """A frame of this desk's world: floor and read-outs in one batch, to this page."""
        with self.client.atomic():
            self.view.update(snap)
            self.comparison.draw()
            self.panel.update(snap)
        self.panel.inspector.draw(snap)
        self.panel.on_frame_drawn()

    def close(self) -> list:
        """The page left (or the world was replaced): the desk's workers stop (returned, still ending),
        the compared world ends."""
        workers = self.panel.stop()
        self.comparison.end()
        self.panel.farewell(self.client.client_id)
        return workers

    def clear(self) -> None:
        """Take the desk off its page, which stays (a new world is coming): every control and node of it."""
        self.client.gui.reset()
        self.client.scene.reset()

    def _fit(self) -> None:
        """Frame the arena for the page's window whenever its shape changes, not only while it lays itself
        out (as a presenter's page is reframed, sandbox.commands.serve): the desk's docked panel comes in
        the page's own messages, after its first layout, and a page whose canvas narrowed for it after the
        first 30 s kept a camera framed for the whole width, the arena's right side and the caption's end
        under the panel ("... 33 % in" cut off at 1024 x 768). A camera the student moved stays until then."""
        aspect = self.client.camera.aspect
        if aspect and aspect != self._fitted and self.client.client_id not in self.panel.inspector.followers:
            self.panel.framing.apply(self.client)
            self._fitted = aspect

    def _reframe(self, offset: tuple[float, float] | None) -> None:
        """Compare mode began or ended on this desk: its page frames both worlds, or the one."""
        self.panel.framing.offset = offset
        with self.client.atomic():
            self.view.set_compared(offset, self.world.runner.latest)
        if self.client.client_id not in self.panel.inspector.followers:
            self.panel.framing.apply(self.client)
