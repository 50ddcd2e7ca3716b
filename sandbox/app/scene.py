"""The top-down scene: one viser node per kind of thing, updated from snapshots.

Layout (z up, arena on z = 0, camera above looking down):

- ``/arena/lights``   the 64 x 64 light grid as one crisp texture
- ``/arena/field``    the sensed luminosity as a heat map (toggle)
- ``/arena/walls``, ``/arena/box_wall``   outer wall and the box-only wall
- ``/goal``, ``/light_outline``   goal outline and current light outline
- ``/swarm/robots``, ``/swarm/headings``, ``/swarm/boxes``   batched meshes
- ``/inspect/*``, ``/draw/*``   the followed robot and the shape being drawn

Works on any viser scene API (the live server, or a headless server that is
only being recorded).
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from sandbox.app import palette as pal
from sandbox.app.snapshot import Snapshot
from sandbox.model.config import Config

Z_FIELD, Z_LIGHTS, Z_BOXES, Z_ROBOTS, Z_MARKS, Z_LINES, Z_TOP = -0.01, 0.0, 0.02, 0.04, 0.05, 0.08, 0.12


def top_down_camera(config: Config, aspect: float = 1.4, fov_deg: float = 50.0) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera position, look-at point and vertical field of view (radians) that
    frame the whole arena from straight above (tilted a hair so orbiting works),
    in a view ``aspect`` (width / height) wide: high enough for the arena's
    height and, in a narrow view, for its width."""
    c = config.arena_size / 2.0
    fov = np.radians(fov_deg)
    half = config.arena_size * 0.56  # arena plus a margin
    height = half / np.tan(fov / 2.0) / min(1.0, max(aspect, 0.1))
    return np.array([c, c - 1e-3 * height, height]), np.array([c, c, 0.0]), float(fov)


def frame_arena(client: Any, config: Config) -> None:
    """Point one viewer's camera at the whole arena, for its own window's shape."""
    aspect = float(getattr(client.camera, "aspect", 0.0) or 1.4)
    position, look_at, fov = top_down_camera(config, aspect)
    with client.atomic():
        client.camera.fov = fov
        client.camera.position = tuple(position)
        client.camera.look_at = tuple(look_at)


def _geometry_key(cfg: Config, n: int, m: int) -> tuple:
    """What the static scene depends on: a change rebuilds the nodes (a gain does not)."""
    return (cfg.arena_size, cfg.construction_size, cfg.centre, cfg.light_pitch, cfg.robot_radius, cfg.box_circumradius,
            n, m)


def configure_scene(server: Any, config: Config) -> None:
    """z up, flat true colours (no shading lights, an even ambient light) and a
    top-down initial camera framing the arena. Also recorded into replays."""
    server.scene.set_up_direction("+z")
    server.scene.world_axes.visible = False
    server.scene.configure_default_lights(False)
    server.scene.configure_environment_map(None)
    server.scene.add_light_ambient("/ambient", intensity=3.14159)
    position, look_at, fov = top_down_camera(config)
    server.initial_camera.position = tuple(position)
    server.initial_camera.look_at = tuple(look_at)
    server.initial_camera.fov = fov
    server.initial_camera.far = float(position[2] * 4)


class SceneView:
    """Draws snapshots into a viser scene."""

    def __init__(self, scene: Any, snapshot: Snapshot, *, show_field: bool = False):
        self.scene = scene
        self.show_field = show_field
        self._lock = threading.RLock()
        self._built_for: tuple | None = None
        self._lights_key: tuple | None = None
        self._field_key: tuple | None = None
        self._goal_key: int | None = None
        self._outline_shape: tuple | None = None
        self._outline_bytes: bytes | None = None
        self._n: tuple[int, int] | None = None
        self._draw_points: list[tuple[float, float]] = []
        self.handles: dict[str, Any] = {}
        self.update(snapshot)

    # ------------------------------------------------------------ static
    def _build(self, snap: Snapshot) -> None:
        cfg = snap.world_config
        s, c = cfg.arena_size, cfg.arena_size / 2.0
        sc = self.scene
        for h in self.handles.values():
            try:
                h.remove()
            except Exception:
                pass
        self.handles = {}
        placeholder = np.zeros((8, 8, 3), np.uint8)
        # The light grid: one flat square per light, crisp by construction, on a
        # dark floor that shows as thin seams between cells.
        self.handles["floor"] = sc.add_mesh_simple(
            "/arena/floor", *pal.square_mesh(c), color=pal.CELL_EDGE, position=(c, c, Z_LIGHTS - 0.005),
            cast_shadow=False, receive_shadow=False)
        n_side, pitch = cfg.lights_per_side, cfg.light_pitch
        centres = (np.arange(n_side) + 0.5) * pitch
        gx, gy = np.meshgrid(centres, centres, indexing="ij")  # row-major [ix, iy] like the intensities
        cells = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, Z_LIGHTS)], axis=1).astype(np.float32)
        self.handles["lights"] = sc.add_batched_meshes_simple(
            "/arena/lights", *pal.square_mesh(0.44 * pitch),
            np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (len(cells), 1)), cells,
            batched_colors=pal.linear(pal.light_colours(np.zeros(len(cells)))), lod="off", cast_shadow=False,
            receive_shadow=False)
        self.handles["field"] = sc.add_image(
            "/arena/field", placeholder, s, s, format="png", position=(c, c, Z_FIELD),
            cast_shadow=False, receive_shadow=False, visible=self.show_field)
        self.handles["walls"] = sc.add_line_segments(
            "/arena/walls", pal.closed_segments(pal.square(c, c), Z_LINES), pal.ARENA_WALL, thickness=0.25)
        self.handles["box_wall"] = sc.add_line_segments(
            "/arena/box_wall", pal.closed_segments(pal.square(cfg.centre, cfg.construction_size / 2.0), Z_LINES),
            pal.BOX_WALL, thickness=0.1)
        n, m = len(snap.robot_positions), len(snap.box_positions)
        identity = np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (max(n, 1), 1))
        pos = np.zeros((max(n, 1), 3), np.float32)
        dv, df = pal.disc_mesh(cfg.robot_radius, 20)
        self.handles["robots"] = sc.add_batched_meshes_simple(
            "/swarm/robots", dv, df, identity, pos, batched_colors=np.zeros((max(n, 1), 3), np.uint8),
            lod="off", cast_shadow=False, receive_shadow=False, visible=n > 0)
        hv, hf = pal.heading_mark_mesh(cfg.robot_radius, 0.005)
        self.handles["headings"] = sc.add_batched_meshes_simple(
            "/swarm/headings", hv, hf, identity, pos, batched_colors=pal.linear(pal.HEADING_MARK),
            lod="off", cast_shadow=False, receive_shadow=False, visible=n > 0)
        bv, bf = pal.hexagon_mesh(cfg.box_circumradius)
        identity_b = np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (max(m, 1), 1))
        self.handles["boxes"] = sc.add_batched_meshes_simple(
            "/swarm/boxes", bv, bf, identity_b, np.zeros((max(m, 1), 3), np.float32),
            batched_colors=np.zeros((max(m, 1), 3), np.uint8), lod="off", cast_shadow=False,
            receive_shadow=False, visible=m > 0)
        empty = np.zeros((1, 2, 3), np.float32)
        self.handles["goal"] = sc.add_line_segments("/goal", empty, pal.GOAL_LINE, thickness=0.18)
        self.handles["light_outline"] = sc.add_line_segments("/light_outline", empty, pal.LIGHT_LINE, thickness=0.08)
        self.handles["selected"] = sc.add_line_segments("/inspect/ring", empty, pal.SELECTED, thickness=0.08,
                                                        visible=False)
        self.handles["sensors"] = sc.add_point_cloud(
            "/inspect/sensors", np.zeros((4, 3), np.float32), pal.SENSOR_COLOURS, point_size=0.09,
            point_shape="circle", visible=False)
        self.handles["draw_line"] = sc.add_line_segments("/draw/line", empty, pal.DRAW_LINE, thickness=0.15,
                                                         visible=False)
        self.handles["draw_points"] = sc.add_point_cloud(
            "/draw/points", np.zeros((1, 3), np.float32), pal.DRAW_LINE, point_size=0.6, point_shape="circle",
            visible=False)
        self._built_for = _geometry_key(cfg, n, m)
        self._lights_key = self._field_key = self._goal_key = None
        self._outline_bytes = None
        self._n = (n, m)
        self._redraw_preview()

    # ----------------------------------------------------------- dynamic
    def update(self, snap: Snapshot) -> None:
        with self._lock:
            cfg = snap.world_config
            n, m = len(snap.robot_positions), len(snap.box_positions)
            if self._built_for != _geometry_key(cfg, n, m):
                self._build(snap)
            h = self.handles
            if snap.lights_key != self._lights_key:
                h["lights"].batched_colors = pal.linear(pal.light_colours(snap.intensities, peak=max(cfg.light_intensity, 1e-9)))
                self._lights_key = snap.lights_key
            if self.show_field and snap.field is not None and snap.lights_key != self._field_key:
                h["field"].image = pal.field_image(snap.field, top_first=False)
                self._field_key = snap.lights_key
            if snap.goal_key != self._goal_key:
                h["goal"].points = pal.closed_segments(snap.goal_outline, Z_LINES + 0.01)
                self._goal_key = snap.goal_key
            outline_bytes = snap.outline.tobytes()
            if outline_bytes != self._outline_bytes:
                h["light_outline"].points = pal.closed_segments(snap.outline, Z_LINES)
                self._outline_bytes = outline_bytes
            if n:
                pos = np.empty((n, 3), np.float32)
                pos[:, :2], pos[:, 2] = snap.robot_positions, Z_ROBOTS
                quat = pal.heading_quaternions(snap.robot_headings)
                h["robots"].batched_positions = pos
                h["robots"].batched_wxyzs = quat
                h["robots"].batched_colors = pal.linear(pal.robot_colours(snap.robot_charges, cfg.capacity))
                pos_marks = pos.copy()
                pos_marks[:, 2] = Z_MARKS
                h["headings"].batched_positions = pos_marks
                h["headings"].batched_wxyzs = quat
            if m:
                bpos = np.empty((m, 3), np.float32)
                bpos[:, :2], bpos[:, 2] = snap.box_positions, Z_BOXES
                h["boxes"].batched_positions = bpos
                h["boxes"].batched_wxyzs = pal.heading_quaternions(snap.box_angles)
                h["boxes"].batched_colors = pal.linear(pal.box_colours(snap.box_in_goal))
            robot = snap.robot
            if robot is not None:
                a = np.linspace(0, 2 * np.pi, 33)
                r = cfg.robot_radius * 1.9
                ring = robot.position + r * np.stack([np.cos(a), np.sin(a)], axis=1)
                h["selected"].points = pal.closed_segments(ring[:-1], Z_TOP)
                pts = np.zeros((4, 3), np.float32)
                pts[:, :2], pts[:, 2] = robot.sensor_points, Z_TOP
                h["sensors"].points = pts
            if h["selected"].visible != (robot is not None):
                h["selected"].visible = robot is not None
                h["sensors"].visible = robot is not None

    def set_show_field(self, show: bool, snap: Snapshot) -> None:
        with self._lock:
            self.show_field = bool(show)
            if not show:
                self._field_key = None
            elif snap.field is not None and snap.lights_key != self._field_key:
                self.handles["field"].image = pal.field_image(snap.field, top_first=False)
                self._field_key = snap.lights_key
            self.handles["field"].visible = self.show_field
            self.handles["lights"].visible = not self.show_field
            self.handles["floor"].visible = not self.show_field

    # ------------------------------------------------------------ drawing
    def set_draw_points(self, points: list[tuple[float, float]]) -> None:
        with self._lock:
            self._draw_points = list(points)
            self._redraw_preview()

    def _redraw_preview(self) -> None:
        h = self.handles
        pts = np.array(self._draw_points, dtype=np.float32).reshape(-1, 2)
        if len(pts) == 0:
            h["draw_line"].visible = False
            h["draw_points"].visible = False
            return
        p3 = np.zeros((len(pts), 3), np.float32)
        p3[:, :2], p3[:, 2] = pts, Z_TOP
        h["draw_points"].points = p3
        h["draw_points"].colors = np.tile(np.array(pal.DRAW_LINE, np.uint8), (len(pts), 1))
        h["draw_points"].visible = True
        if len(pts) >= 2:
            segs = pal.open_segments(pts, Z_TOP)
            if len(pts) >= 3:  # dashed-looking closing edge: drawn thinner via a second pass is overkill; show it
                segs = np.concatenate([segs, pal.open_segments(np.stack([pts[-1], pts[0]]), Z_TOP)])
            h["draw_line"].points = segs
            h["draw_line"].visible = True
        else:
            h["draw_line"].visible = False
