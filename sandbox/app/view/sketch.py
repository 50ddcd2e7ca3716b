"""The shape being drawn, on the floor: its outline, a numbered handle at each
vertex, the edges that cross in red, a rubber band from the last point to the
pointer, and a dashed preview of the goal at its final size with the smallest
and largest outlines of its light band. The nodes live under ``/draw``. Runs on the app's event thread.

viser reports no pointer movement, only clicks and drags of scene nodes, so
the tools are built from drags: each vertex handle is an instance of one
batched mesh (its drag moves that vertex), and while drawing an invisible pad
over the floor turns press-drag-release into "place the next point here",
the rubber band following the pointer meanwhile. A plain click still reaches
the scene's click callback, which adds a point.

Only the live page has these nodes: recordings do not show a drawing.

Runs on the app's event thread, as the Draw folder that drives it.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from sandbox.app.view import palette as pal
from sandbox.app.view.floor import floor_point

#: Heights (m) above the floor: over everything the simulation draws (scene.Z_TOP is 0.12), the handles
#: over the lines so that a press on a vertex grabs the vertex, not the pad under it.
Z_PAD, Z_PREVIEW, Z_LINE, Z_HANDLE = 0.3, 0.32, 0.34, 0.4
#: Handles not yet in use: a speck under the floor, where no press can reach them.
Z_SPARE, SPARE_SCALE = -5.0, 1e-4
#: The fewest handles the mesh has room for; it doubles when a drawing outgrows it.
HANDLE_ROOM = 16


def handle_room(n: int) -> int:
    """Room for ``n`` handles: HANDLE_ROOM, doubled as often as needed."""
    room = HANDLE_ROOM
    while room < n:
        room *= 2
    return room


#: The veil over the live scene while drawing (the drag surface): dark enough that the outline, its
#: numbers and the dashed preview read over lights, robots and boxes, light enough to see them move.
DIM_COLOUR, DIM_OPACITY = (12, 14, 24), 0.55
#: The drawn outline: bright and a fixed number of pixels thick at any zoom. Magenta, which nothing
#: else on the floor is, and which the page's tone mapping leaves vivid (a bright green turns pale).
LINE_COLOUR, LINE_PIXELS = (255, 0, 255), 7.0
CLOSING_COLOUR = (150, 0, 150)  # the edge back to the first point: the outline closes there when used
RUBBER_COLOUR, RUBBER_PIXELS = LINE_COLOUR, LINE_PIXELS  # the edge the release will add
CROSSING_COLOUR, CROSSING_PIXELS = (255, 0, 0), 10.0
HANDLE_COLOUR, FIRST_HANDLE_COLOUR, CROSSING_HANDLE_COLOUR = LINE_COLOUR, (255, 255, 255), (255, 0, 0)
#: The selected point (Delete removes it): yellow, which neither the outline nor the preview is (the lit
#: lights are, under the veil), and larger, so it is seen at a glance.
SELECTED_COLOUR, SELECTED_SCALE = (255, 220, 0), 1.8
#: The preview in the legend's colours for the goal and the lit outline, dashed: "not built yet".
PREVIEW_GOAL_COLOUR, PREVIEW_BAND_COLOUR, PREVIEW_PIXELS = pal.GOAL_LINE, pal.LIGHT_LINE, 4.0
DASH, GAP = 0.6, 0.4
#: A handle's radius as a fraction of the arena's side (0.38 m in the 64 m arena): about 10 pixels across
#: with the whole arena in view, easy to grab once zoomed in on the construction area.
HANDLE_FRACTION = 0.006
#: The pad reaches this far past the walls (fraction of the arena), so a drag just outside still lands.
PAD_MARGIN = 0.25

PadDrag = Callable[[str, tuple[float, float]], None]
VertexDrag = Callable[[int, str, tuple[float, float]], None]


def disc(segments: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A flat unit disc in the xy plane: (vertices, faces) of a triangle fan."""
    a = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    vertices = np.zeros((segments + 1, 3), np.float32)
    vertices[1:, 0], vertices[1:, 1] = np.cos(a), np.sin(a)
    faces = np.array([(0, 1 + k, 1 + (k + 1) % segments) for k in range(segments)], np.uint32)
    return vertices, faces


def dashed(outline: np.ndarray, z: float, dash: float = DASH, gap: float = GAP) -> np.ndarray:
    """(k, 2, 3) segments of a dashed closed outline: dashes of ``dash`` metres every ``dash + gap``."""
    v = np.asarray(outline, dtype=float).reshape(-1, 2)
    a, b = v, np.roll(v, -1, axis=0)
    lengths = np.hypot(*(b - a).T)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    starts = np.arange(0.0, cumulative[-1], dash + gap)
    ends = np.minimum(starts + dash, cumulative[-1])

    def at(s: np.ndarray) -> np.ndarray:
        edge = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(v) - 1)
        t = (s - cumulative[edge]) / np.maximum(lengths[edge], 1e-12)
        return a[edge] + t[:, None] * (b[edge] - a[edge])

    out = np.zeros((len(starts), 2, 3), np.float32)
    out[:, 0, :2], out[:, 1, :2], out[:, :, 2] = at(starts), at(ends), z
    return out


def _segments(pairs: list[tuple[np.ndarray, np.ndarray]], z: float) -> np.ndarray:
    out = np.zeros((max(len(pairs), 1), 2, 3), np.float32)
    for k, (a, b) in enumerate(pairs):
        out[k, 0, :2], out[k, 1, :2] = a, b
    out[:, :, 2] = z
    return out


class DrawView:
    """The ``/draw`` nodes of one scene. ``on_pad_drag(phase, point)`` and
    ``on_vertex_drag(index, phase, point)`` get floor points; the panel decides."""

    def __init__(self, scene: Any, arena_size: float, on_pad_drag: PadDrag, on_vertex_drag: VertexDrag):
        self.scene, self.arena_size = scene, float(arena_size)
        self._on_pad_drag, self._on_vertex_drag = on_pad_drag, on_vertex_drag
        self._handles: Any = None
        self.handles_shown = 0  # the handles in use: the mesh has room for more
        self._labels: list[Any] = []
        self._pad: Any = None
        self._disc = disc()
        line = dict(thickness_units="screen", visible=False)
        empty = np.zeros((1, 2, 3), np.float32)
        self.line = scene.add_line_segments("/draw/line", empty, LINE_COLOUR, thickness=LINE_PIXELS, **line)
        self.closing = scene.add_line_segments("/draw/closing", empty, CLOSING_COLOUR, thickness=LINE_PIXELS / 2,
                                               **line)
        self.crossing = scene.add_line_segments("/draw/crossing", empty, CROSSING_COLOUR, thickness=CROSSING_PIXELS,
                                                **line)
        self.rubber = scene.add_line_segments("/draw/rubber", empty, RUBBER_COLOUR, thickness=RUBBER_PIXELS, **line)
        self.preview_goal = scene.add_line_segments("/draw/preview/goal", empty, PREVIEW_GOAL_COLOUR,
                                                    thickness=PREVIEW_PIXELS, **line)
        self.preview_band = scene.add_line_segments("/draw/preview/band", empty, PREVIEW_BAND_COLOUR,
                                                    thickness=PREVIEW_PIXELS, **line)

    @property
    def handle_radius(self) -> float:
        return HANDLE_FRACTION * self.arena_size

    def set_arena(self, arena_size: float) -> None:
        """A new world of another size: the pad and the handles are sized from the arena."""
        if float(arena_size) == self.arena_size:
            return
        self.arena_size = float(arena_size)
        if self._pad is not None:
            self.set_pad(False)
            self.set_pad(True)
        if self._handles is not None:
            self._handles.remove()  # rebuilt at the next show, at the new size
            self._handles = None

    # ----------------------------------------------------------- outline
    def show(self, points: list, crossings: list[tuple[int, int]], selected: int | None = None) -> None:
        """The outline through ``points`` (closed back to the first in a dimmer line), its
        numbered handles (point ``selected`` larger and in cyan), and the edges of ``crossings``
        (pairs of edge indices) in red."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        n = len(pts)
        self._set(self.line, pal.open_segments(pts, Z_LINE) if n >= 2 else None)
        self._set(self.closing, pal.open_segments(pts[[-1, 0]], Z_LINE) if n >= 3 else None)
        red = sorted({e for pair in crossings for e in pair})
        self._set(self.crossing, _segments([(pts[e], pts[(e + 1) % n]) for e in red], Z_LINE + 0.01)
                  if red else None)
        self._show_handles(pts, red, selected)
        self._show_labels(pts)

    def show_rubber(self, start, end) -> None:
        """A line from ``start`` to ``end`` (the pointer during a drag); None hides it."""
        pairs = [(np.asarray(start, float), np.asarray(end, float))] if start is not None and end is not None \
            else []
        self._set(self.rubber, _segments(pairs, Z_LINE + 0.02) if pairs else None)

    def show_preview(self, goal: np.ndarray | None, smallest: np.ndarray | None = None,
                     largest: np.ndarray | None = None) -> None:
        """Dashed: the goal at its final size, and its smallest and largest light outlines. None hides them."""
        self._set(self.preview_goal, None if goal is None else dashed(goal, Z_PREVIEW))
        band = [dashed(o, Z_PREVIEW) for o in (smallest, largest) if o is not None]
        self._set(self.preview_band, np.concatenate(band) if band and goal is not None else None)

    @staticmethod
    def _set(handle: Any, segments: np.ndarray | None) -> None:
        if segments is None or len(segments) == 0:
            if handle.visible:
                handle.visible = False
            return
        handle.points = segments
        if not handle.visible:
            handle.visible = True

    def _show_handles(self, pts: np.ndarray, red: list[int], selected: int | None = None) -> None:
        """One batched mesh of discs, one per point, with room for more: a batched mesh keeps its
        instance count, and a new count was a new node, which the page builds afresh (its mesh and its
        drag handler) at every click; now a new point is new positions in the same node."""
        n = self.handles_shown = len(pts)
        if n == 0:
            if self._handles is not None:
                self._handles.visible = False
            return
        room = handle_room(n)
        colours = np.tile(np.array(HANDLE_COLOUR, np.uint8), (room, 1))
        scales = np.full(room, SPARE_SCALE, np.float32)
        scales[:n] = self.handle_radius
        colours[0] = FIRST_HANDLE_COLOUR
        for e in red:  # both ends of a crossing edge
            colours[[e, (e + 1) % n]] = CROSSING_HANDLE_COLOUR
        if selected is not None and 0 <= selected < n:
            colours[selected] = SELECTED_COLOUR
            scales[selected] *= SELECTED_SCALE
        positions = np.zeros((room, 3), np.float32)
        positions[:n, :2], positions[:n, 2] = pts, Z_HANDLE
        positions[n:, :2], positions[n:, 2] = pts[0], Z_SPARE
        if self._handles is not None and len(self._handles.batched_positions) != room:
            self._handles.remove()
            self._handles = None
        if self._handles is None:
            self._handles = self.scene.add_batched_meshes_simple(
                "/draw/handles", self._disc[0], self._disc[1], batched_wxyzs=np.tile([1.0, 0, 0, 0], (room, 1)),
                batched_positions=positions, batched_scales=scales, batched_colors=colours, lod="off",
                side="double", cast_shadow=False, receive_shadow=False)
            self._handles.on_drag(self._vertex_drag)
            return
        self._handles.batched_positions = positions
        if not np.array_equal(self._handles.batched_colors, colours):
            self._handles.batched_colors = colours
        if not np.array_equal(self._handles.batched_scales, scales):
            self._handles.batched_scales = scales
        if not self._handles.visible:
            self._handles.visible = True

    def _show_labels(self, pts: np.ndarray) -> None:
        """Vertex numbers beside the handles, up and right, where the line is least likely to run."""
        offset = np.array([0.9, 0.9]) * self.handle_radius
        while len(self._labels) > len(pts):
            self._labels.pop().remove()
        for k, p in enumerate(pts):
            position = (float(p[0] + offset[0]), float(p[1] + offset[1]), Z_HANDLE)
            if k < len(self._labels):
                if not np.allclose(self._labels[k].position, position):
                    self._labels[k].position = position
            else:
                self._labels.append(self.scene.add_label(f"/draw/labels/{k + 1}", str(k + 1), position=position,
                                                         anchor="bottom-left", font_screen_scale=1.3))

    # --------------------------------------------------------------- pad
    def set_pad(self, active: bool) -> None:
        """The drag surface over the floor, while drawing (else the camera orbits as usual): a dark veil
        over everything the simulation draws and under the drawing, so that the outline reads."""
        if active and self._pad is None:
            s = self.arena_size
            lo, hi = -PAD_MARGIN * s, (1 + PAD_MARGIN) * s
            corners = np.array([(lo, lo, Z_PAD), (hi, lo, Z_PAD), (hi, hi, Z_PAD), (lo, hi, Z_PAD)], np.float32)
            self._pad = self.scene.add_mesh_simple("/draw/pad", corners, np.array([(0, 1, 2), (0, 2, 3)],
                                                                                  np.uint32),
                                                   color=DIM_COLOUR, opacity=DIM_OPACITY, side="double",
                                                   cast_shadow=False, receive_shadow=False)
            self._pad.on_drag(self._pad_drag)
        elif not active and self._pad is not None:
            self._pad.remove()
            self._pad = None

    # ------------------------------------------------------------- drags
    # Plain functions: viser hands them to the app's event queue (sandbox.app.web.events), which runs
    # them in order, so an update never overtakes its start, and never beside another event.
    def _pad_drag(self, event: Any) -> None:
        point = self._floor(event)
        if point is not None or event.phase == "end":
            self._on_pad_drag(event.phase, point)

    def _vertex_drag(self, event: Any) -> None:
        point = self._floor(event)
        if event.instance_index is not None and (point is not None or event.phase == "end"):
            self._on_vertex_drag(int(event.instance_index), event.phase, point)

    @staticmethod
    def _floor(event: Any) -> tuple[float, float] | None:
        """Where the pointer is over the floor. viser gives the pointer on a plane facing the camera
        through the grabbed point; the line from the camera through it meets the floor under the
        pointer, whatever the camera's tilt."""
        end = np.asarray(event.end_position, dtype=float)
        try:
            camera = np.asarray(event.client.camera.position, dtype=float)
        except Exception:  # no camera yet: the plane is the floor's, near enough, from above
            return float(end[0]), float(end[1])
        return floor_point(tuple(camera), tuple(end - camera))
