"""The Inspector folder: follow one robot (clicked, or at random), read its
photocells, command and charge, and let the camera follow it."""

from __future__ import annotations

from typing import Any

import numpy as np
import viser

from sandbox.app import palette as pal
from sandbox.app.scene import frame_arena
from sandbox.app.snapshot import Snapshot
from sandbox.model.robots import PHOTOCELLS


class InspectorFolder:
    def __init__(self, gui: Any, runner: Any, server: Any):
        self.gui, self.runner, self.server = gui, runner, server
        #: Viewers whose camera follows the robot: each viewer decides for itself.
        self.followers: set[int] = set()

    def build(self, snap: Snapshot) -> None:
        gui, runner = self.gui, self.runner
        with gui.add_folder("Inspector"):
            self.help = gui.add_markdown("Click a robot on the floor to follow it.")
            self.text = gui.add_markdown("")
            self.charge_bar = gui.add_progress_bar(0.0, color="green", visible=False)
            self.camera_follow = gui.add_button("Camera follows (this viewer)", icon=viser.Icon.VIDEO,
                                                hint="Zoom your own view in on the followed robot and keep it "
                                                     "centred; press again to see the whole arena")
            self.follow_random = gui.add_button("Follow a random robot", icon=viser.Icon.TARGET)
            self.stop_follow = gui.add_button("Stop following", icon=viser.Icon.X, disabled=True)

        @self.follow_random.on_click
        def _(event: viser.GuiEvent) -> None:
            n = len(runner.latest.robot_positions)
            if n:
                self.follow(int(np.random.default_rng().integers(0, n)))

        @self.camera_follow.on_click
        def _(event: viser.GuiEvent) -> None:
            if event.client is None:
                return
            if event.client_id in self.followers:
                self.followers.discard(event.client_id)
                frame_arena(event.client, runner.latest.world_config)
            else:
                self.followers.add(event.client_id)

        @self.stop_follow.on_click
        def _(event: viser.GuiEvent) -> None:
            self.stop()

    def update(self, snap: Snapshot) -> None:
        if snap.robot is None:
            return
        self.text.content = self._text(snap)
        cap = snap.world_config.capacity
        self.charge_bar.value = float(100.0 * snap.robot.charge / cap) if cap > 0 else 0.0
        # The bar in the robot's own colour on the floor (viser's names for them).
        self.charge_bar.color = ("green", "orange", "red")[int(pal.charge_class([snap.robot.charge], cap)[0])]
        self.charge_bar.visible = True
        if self.followers:
            self._follow_with_cameras(snap)

    def click(self, point: tuple[float, float]) -> None:
        """A click on the floor: follow the nearest robot within a couple of body lengths."""
        snap = self.runner.latest
        if len(snap.robot_positions) == 0:
            return
        d = np.hypot(*(snap.robot_positions - np.asarray(point)).T)
        i = int(np.argmin(d))
        if d[i] <= max(1.5, 6 * snap.world_config.robot_radius):
            self.follow(i)

    def follow(self, index: int) -> None:
        self.runner.select(index)
        self.help.content = f"Following robot **{index}** (click another, or stop)."
        self.stop_follow.disabled = False

    def stop(self) -> None:
        self.runner.select(None)
        self.help.content = "Click a robot on the floor to follow it."
        self.text.content = ""
        self.charge_bar.visible = False
        self.stop_follow.disabled = True
        clients = self.server.get_clients()
        for client_id in list(self.followers):
            if client_id in clients:
                frame_arena(clients[client_id], self.runner.latest.world_config)
        self.followers.clear()

    def _follow_with_cameras(self, snap: Snapshot) -> None:
        x, y = (float(v) for v in snap.robot.position)
        height = 12.0
        clients = self.server.get_clients()
        for client_id in list(self.followers):
            client = clients.get(client_id)
            if client is None:  # left
                self.followers.discard(client_id)
                continue
            with client.atomic():
                client.camera.position = (x, y - 1e-3 * height, height)
                client.camera.look_at = (x, y, 0.0)

    @staticmethod
    def _text(snap: Snapshot) -> str:
        r = snap.robot
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
