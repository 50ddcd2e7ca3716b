"""The Inspector folder: each viewer follows a robot of its own (clicked, or
at random), reads its photocells, command and charge, and its camera follows
it unless the viewer unticks *Camera follows* (issue 41, item 4: the f key
said "Following robot 169" with the robot off-frame). Runs on the app's event thread.

The folder and its button are shared; what a viewer follows, whether its
camera follows, its read-outs and the ring, the robot's disc and photocell
dots on its floor are that viewer's own (viser's per-client GUI and scene),
like its camera: following a robot in one tab changes nothing in another.

The followed robot's disc is drawn again in the viewer's own scene, in the
same message as its ring: the shared scene reaches a page that draws slowly
in windows (:mod:`sandbox.app.web.pacing`), its own messages at once, so the
shared disc could lag a frame or two behind the ring and sit outside it.

Runs on the app's event thread, which owns every viewer's inspector."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import viser

from sandbox.app.view import palette as pal
from sandbox.app.view.scene import Z_TOP
from sandbox.app.world.orders import Follow
from sandbox.app.world.snapshot import RobotView, Snapshot
from sandbox.model.robots import PHOTOCELLS

HELP = "Click a robot on the floor to follow it (key f: any robot). Each viewer follows its own."
#: How high above the followed robot a following camera sits (m): the robot and its neighbours in view.
FOLLOW_HEIGHT = 12.0


@dataclass(eq=False, repr=False)  # viser's handles have no repr to lend
class Viewer:
    """One page's inspector: the robot it follows, its read-outs and its marks on the floor."""

    client: Any
    status: Any
    text: Any
    charge_bar: Any
    stop: Any
    follows: Any
    ring: Any
    disc: Any
    heading: Any
    sensors: Any
    robot: int | None = None


class InspectorFolder:
    def __init__(self, gui: Any, runner: Any, server: Any, reframe: Callable[[Any], None]):
        """``reframe(client)`` frames a page's camera as its View says (when its camera stops following)."""
        self.gui, self.runner, self.server, self._reframe = gui, runner, server, reframe
        #: Each connected page's inspector, by client id.
        self.viewers: dict[int, Viewer] = {}
        #: Viewers whose camera follows their robot: each viewer decides for itself.
        self.followers: set[int] = set()
        self.folder: Any = None

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Inspector") as self.folder:
            self.help = gui.add_markdown(HELP)
            self.follow_random = gui.add_button("Follow a random robot", icon=viser.Icon.TARGET)

        self.follow_random.on_click(lambda event: self.follow_any(event.client))
        gui.add_command("Follow a random robot", hotkey="F", description="key: f (this viewer)").on_trigger(
            lambda event: self.follow_any(event.client))

        for client in list(self.server.get_clients().values()):
            self.attach(client)

    # ------------------------------------------------------------ viewers
    def attach(self, client: Any) -> None:
        """Give a page that connected its own read-outs (in the shared folder) and floor marks."""
        if self.folder is None or client.client_id in self.viewers:
            return
        with self.folder:  # a client's elements inside the server's folder
            follows = client.gui.add_checkbox("Camera follows", True,
                                              hint="Your own view zoomed in on the robot you follow, kept "
                                                   "centred; untick to see the whole arena")
            status = client.gui.add_markdown("")
            text = client.gui.add_markdown("")
            charge_bar = client.gui.add_progress_bar(0.0, color="green", visible=False)
            stop = client.gui.add_button("Stop following", icon=viser.Icon.X, disabled=True)
        empty = np.zeros((1, 2, 3), np.float32)
        ring = client.scene.add_line_segments("/inspect/ring", empty, pal.SELECTED, thickness=0.08, visible=False)
        radius = self.runner.latest.world_config.robot_radius
        # Its disc and heading dot as the shared scene draws them (sizes are radii), over them.
        disc = client.scene.add_point_cloud("/inspect/robot", np.zeros((1, 3), np.float32), pal.SELECTED,
                                            point_size=radius, point_shape="circle", point_shading="flat",
                                            visible=False)
        heading = client.scene.add_point_cloud("/inspect/heading", np.zeros((1, 3), np.float32),
                                               pal.HEADING_MARK, point_size=0.3 * radius, point_shape="circle",
                                               point_shading="flat", visible=False)
        sensors = client.scene.add_point_cloud("/inspect/sensors", np.zeros((4, 3), np.float32),
                                               pal.SENSOR_COLOURS, point_size=0.09, point_shape="circle",
                                               visible=False)
        self.viewers[client.client_id] = Viewer(client, status, text, charge_bar, stop, follows, ring, disc,
                                                heading, sensors)

        @stop.on_click
        def _(event: viser.GuiEvent) -> None:
            self.stop_following(client.client_id)

        @follows.on_update
        def _(event: viser.GuiEvent) -> None:
            self.camera_follows(client.client_id, bool(follows.value))

    def detach(self, client_id: int) -> None:
        """A page left: forget what it followed (viser drops its elements)."""
        self.followers.discard(client_id)
        if self.viewers.pop(client_id, None) is not None:
            self._tell_runner()

    def follow(self, client: Any, index: int) -> None:
        """This viewer follows robot ``index``."""
        viewer = self.viewers.get(client.client_id)
        if viewer is None:
            self.attach(client)
            viewer = self.viewers.get(client.client_id)
            if viewer is None:
                return
        viewer.robot = int(index)
        viewer.status.content = f"Following robot **{index}** (click another, or stop)."
        viewer.stop.disabled = False
        self._tell_runner()
        if viewer.follows.value:  # into view now, not at the next read-out
            self.followers.add(client.client_id)
            positions = self.runner.latest.robot_positions
            if 0 <= viewer.robot < len(positions):
                self._move_camera(client, positions[viewer.robot])

    def camera_follows(self, client_id: int, on: bool) -> None:
        """This viewer's camera follows its robot (``on``), or sees the arena as its View says."""
        viewer = self.viewers.get(client_id)
        if viewer is None:
            return
        if not on:
            if client_id in self.followers:
                self.followers.discard(client_id)
                self._reframe(viewer.client)
        elif viewer.robot is not None:
            self.follow(viewer.client, viewer.robot)

    def follow_any(self, client: Any) -> None:
        """This viewer follows a robot drawn at random."""
        n = len(self.runner.latest.robot_positions)
        if n and client is not None:
            self.follow(client, int(np.random.default_rng().integers(0, n)))

    def click(self, point: tuple[float, float], client: Any) -> None:
        """A click on the floor: this viewer follows the nearest robot within a couple of body lengths."""
        snap = self.runner.latest
        if client is None or len(snap.robot_positions) == 0:
            return
        d = np.hypot(*(snap.robot_positions - np.asarray(point)).T)
        i = int(np.argmin(d))
        if d[i] <= max(1.5, 6 * snap.world_config.robot_radius):
            self.follow(client, i)

    def stop_following(self, client_id: int) -> None:
        """This viewer follows nothing; its camera, if it followed, sees the arena again."""
        viewer = self.viewers.get(client_id)
        if viewer is None:
            return
        viewer.robot = None
        viewer.status.content = ""
        viewer.text.content = ""
        viewer.charge_bar.visible = False
        viewer.stop.disabled = True
        viewer.ring.visible = viewer.disc.visible = viewer.heading.visible = viewer.sensors.visible = False
        if client_id in self.followers:
            self.followers.discard(client_id)
            self._reframe(viewer.client)
        self._tell_runner()

    def stop(self) -> None:
        """Every viewer stops following (a new world: its robots are not the ones followed)."""
        for client_id in list(self.viewers):
            self.stop_following(client_id)

    def _tell_runner(self) -> None:
        self.runner.submit(Follow(tuple(v.robot for v in self.viewers.values() if v.robot is not None)))

    # ------------------------------------------------------------ drawing
    def update(self, snap: Snapshot) -> None:
        """The read-outs, at the panel's refresh rate; cameras that follow move with them."""
        for client_id, viewer in list(self.viewers.items()):
            robot = snap.robot(viewer.robot)
            if robot is None:
                continue
            viewer.text.content = self._text(snap, robot)
            cap = snap.world_config.capacity
            viewer.charge_bar.value = float(100.0 * robot.charge / cap) if cap > 0 else 0.0
            # The bar in the robot's own colour on the floor (viser's names for them).
            viewer.charge_bar.color = ("green", "orange", "red")[int(pal.charge_class([robot.charge], cap)[0])]
            viewer.charge_bar.visible = True
            if client_id in self.followers:
                self._move_camera(viewer.client, robot.position)

    def draw(self, snap: Snapshot) -> None:
        """Each viewer's ring and photocell dots on its robot, at every frame (they ride with it)."""
        for viewer in list(self.viewers.values()):
            robot = snap.robot(viewer.robot)
            if robot is None:  # following nothing, or a robot this world does not have (yet)
                if viewer.ring.visible:
                    viewer.ring.visible = viewer.disc.visible = viewer.heading.visible = False
                    viewer.sensors.visible = False
                continue
            cfg = snap.world_config
            a = np.linspace(0, 2 * np.pi, 33)
            ring = robot.position + cfg.robot_radius * 1.9 * np.stack([np.cos(a), np.sin(a)], axis=1)
            pts = np.zeros((4, 3), np.float32)
            pts[:, :2], pts[:, 2] = robot.sensor_points, Z_TOP
            with viewer.client.atomic():
                viewer.ring.points = pal.closed_segments(ring[:-1], Z_TOP)
                disc, heading, colour = self._disc(robot, cfg)
                viewer.disc.points, viewer.disc.colors, viewer.heading.points = disc, colour, heading
                viewer.sensors.points = pts
                if not viewer.ring.visible:
                    viewer.ring.visible = viewer.disc.visible = viewer.heading.visible = True
                    viewer.sensors.visible = True

    @staticmethod
    def _disc(robot: RobotView, cfg: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The followed robot's disc and heading dot, as the shared scene draws them, just under the
        ring: the disc's point, the dot's, and the disc's colour (its charge's)."""
        ahead = 0.6 * cfg.robot_radius * np.array([np.cos(robot.heading), np.sin(robot.heading)])
        disc, heading = np.zeros((1, 3), np.float32), np.zeros((1, 3), np.float32)
        disc[0, :2], disc[0, 2] = robot.position, Z_TOP - 0.01
        heading[0, :2], heading[0, 2] = robot.position + ahead, Z_TOP - 0.005
        colour = pal.robot_colours(np.array([robot.charge]), cfg.capacity).astype(np.uint8)
        return disc, heading, colour

    @staticmethod
    def _move_camera(client: Any, position: np.ndarray) -> None:
        """The page's camera straight above ``position``, :data:`FOLLOW_HEIGHT` up, north up."""
        x, y = (float(v) for v in position[:2])
        with client.atomic():
            client.camera.position = (x, y - 1e-3 * FOLLOW_HEIGHT, FOLLOW_HEIGHT)
            client.camera.look_at = (x, y, 0.0)

    @staticmethod
    def _text(snap: Snapshot, r: RobotView) -> str:
        names = PHOTOCELLS[snap.world_config.photocells].names
        v, w = r.command
        av, aw = r.applied
        cap = snap.world_config.capacity
        state = "moving" if r.charge > 0 else "**out of charge: stopped**"
        cells = "".join(f"| {name} | {colour} | {reading:.3f} |\n"
                        for name, colour, reading in zip(names, pal.SENSOR_COLOUR_NAMES, r.sensors))
        return ("| photocell | its dot on the floor | light it reads |\n|---|---|---|\n" + cells + "\n"
                f"**Commanded** by its photocells: forward v = {v:+.3f} m/s, turn w = {w:+.3f} rad/s  \n"
                f"**Doing** v = {av:+.3f}, w = {aw:+.3f} ({state}): how it really moves, other than "
                f"commanded while it pushes or is pushed, and not at all when empty  \n"
                f"**Charge** {r.charge:.2f} / {cap:g} &nbsp; at ({r.position[0]:.1f}, {r.position[1]:.1f}) m")
