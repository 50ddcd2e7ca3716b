"""The Draw folder of Goal shape: a polygon designer's tools. Runs on the app's event thread.

The drawing is a list of points, numbered from 1 on the floor. Ways to change it:
click the floor (or press, drag and release: a rubber band follows the pointer)
while drawing, or click an edge to insert a point on it; drag a numbered handle;
click a handle to select its point and delete it (a button, or the Delete or
Backspace key); pick a template; type or paste points; undo; clear. Points snap
to a grid unless that is off. After every change the
floor shows the outline, its crossing edges in red, and (when it is a usable
polygon) a dashed preview of the goal at the size it will be built with the
smallest and largest outlines of its light band; a line of text says what
*Close and use* and the other buttons are waiting for.

Once a goal is in use the drawing gives way to the result (issue 56, item 3): its line, handles,
numbers and preview leave the floor, the points stay in the folder, and the next edit (*Edit this
goal*, *Start drawing*, a template, typed points, undo) brings them back.

Every callback runs on the app's event thread (:mod:`sandbox.app.web.events`), in order.
"""

from __future__ import annotations

import math
import threading
from typing import Any, Callable

import numpy as np
import viser

from sandbox.app.view.sketch import DrawView
from sandbox.app.panel.common import notify_error
from sandbox.app.panel.plain import plain
from sandbox.app.world.snapshot import Snapshot
from sandbox.model.family import make_goal
from sandbox.model.preview import GoalPreview, preview_goal
from sandbox.shapes import ShapeError, validate_polygon
from sandbox.shapes.drawing import (
    FORMATS_HINT,
    crossing_edges,
    edge_at,
    edge_name,
    format_coordinates,
    parse_coordinates,
    snap,
    vertex_at,
    without_repeats,
)
from sandbox.shapes.geometry import fit_to_area
from sandbox.shapes.templates import placed, template_names, template_vertices

SOURCE = "drawn shape"
PICK_TEMPLATE = "(pick one)"
DEFAULT_GRID = 0.5
#: How far from a point's handle (on screen) a click still selects it, and from an edge inserts a point
#: on it: a few pixels, whatever the zoom. Without the page's camera, the handle's own radius.
PICK_PIXELS, EDGE_PIXELS = 8.0, 6.0
#: The keys that delete the selected point (viser's names for them).
DELETE_KEYS = ("delete", "backspace")
Point = tuple[float, float]


def without_source(message: str) -> str:
    """A validation message without the leading "drawn shape: " (the status line says what it is about)."""
    return message.split(": ", 1)[1] if message.startswith(SOURCE) else message


def metres_per_pixel(client: Any, point: Point) -> float | None:
    """How many metres of the floor at ``point`` one pixel of ``client``'s view spans (None before
    the page has said its camera)."""
    try:
        camera = client.camera
        position, fov, height = np.asarray(camera.position, float), float(camera.fov), int(camera.image_height)
    except Exception:  # noqa: BLE001 - no page, or no camera yet: the caller falls back
        return None
    if height <= 0 or not 0 < fov < math.pi:
        return None
    distance = float(np.linalg.norm(position - (point[0], point[1], 0.0)))
    return 2.0 * distance * math.tan(fov / 2.0) / height


#: The status line's first words once the drawing has given way to the goal in use.
GIVEN_WAY = ("**In use**: the drawing is off the floor so that the goal built shows. **Edit this goal** brings "
             "the running goal back as points, **Start drawing** this drawing as it was.")


def status_text(n: int, drawing: bool, problem: str, preview: GoalPreview | None, typed_error: str = "",
                red: list[str] = (), selected: int | None = None, given_way: bool = False) -> str:
    """The line under the buttons: what the disabled ones wait for, or what Close and use will build."""
    place = f"Click the floor (or press, drag and release) to place point {n + 1}; click an edge to insert " \
        "one there." if drawing else \
        "Press **Start drawing** to click points on the floor, pick a **Template**, or type **Points**."
    if given_way and n:
        text = GIVEN_WAY
    elif n == 0:
        text = f"**No points yet**: Undo, Clear and Close and use need some. {place}"
    elif n < 3:
        text = f"**Close and use needs at least 3 points**: {n} so far. {place}"
    elif problem:
        text = f"**Close and use is off**: {plain(problem)}."
        if red:
            names = plain(", ".join(red[:-1]) + " and " + red[-1] if len(red) > 1 else red[0])
            text += f" In red on the floor: edge{'s' if len(red) > 1 else ''} {names}; drag a numbered point " \
                    "to untangle them."
    else:
        text = f"**Ready**: {n} points. "
        if preview is not None:
            text += (f"Dashed on the floor: the goal at its final size ({preview.area:.0f} m², centred) in blue, "
                     "the smallest and largest outlines of its light band in orange. ")
            text += "".join(f"Note: {plain(note)}. " for note in preview.notes)
        text += "**Close and use** builds it; **Use and run to the end** builds it and gives the answer."
    if selected is not None and 0 <= selected < n:
        text += f"\n\n**Point {selected + 1} selected**: drag it, or **Delete point** (the Delete key) removes it."
    if typed_error:
        text += f"\n\n**Points not applied**: {plain(typed_error)}"
    return text


def _warm_up(config: Any) -> None:
    try:
        preview_goal(config, template_vertices("L"), 0.0)
    except ShapeError:
        pass  # an arena too small for it: compiled all the same


class DrawFolder:
    """The drawing state and its controls. ``use(vertices, name, client)`` hands a finished goal on."""

    def __init__(self, gui: Any, runner: Any, scene: Any, use: Callable[..., None],
                 run_to_the_end: Callable[[Any], None] | None = None):
        """``run_to_the_end(client)``: *Run to the end* of the Run folder, for a page (None: the button is
        not offered)."""
        self.gui, self.runner, self._use = gui, runner, use
        self.run_to_the_end = run_to_the_end
        self.points: list[Point] = []
        #: The index of the selected point (its handle clicked or dragged; Delete removes it), or None.
        self.selected: int | None = None
        self.drawing = False
        #: The drawing has given way to the goal in use: kept, but not on the floor (issue 56, item 3).
        self.given_way = False
        self._problem = ""
        self._red: list[str] = []  # the crossing edges, by vertex numbers
        self._typed_error = ""
        self._preview: GoalPreview | None = None
        self._preview_config: Any = None
        config = runner.latest.world_config
        self.view = DrawView(scene, config.arena_size, self.pad_drag, self.vertex_drag)
        self._centre = (config.centre, config.centre)
        self._warmed = False

    def warm_up(self) -> None:
        """Load the preview's compiled geometry (numba), aside, once: its first call takes most of a
        second. The first viewer's arrival starts it, long before that page has loaded and a point is
        dragged; a server that nobody watches never pays for it."""
        if self._warmed:
            return
        self._warmed = True
        config = self.runner.latest.world_config
        threading.Thread(target=_warm_up, args=(config,), daemon=True, name="draw-preview-warm-up").start()

    # ------------------------------------------------------------ build
    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        with gui.add_folder("Draw", expand_by_default=False):
            gui.add_markdown("Click points on the floor, drag a numbered point to move it. The goal is centred "
                             "and scaled to the boxes' area when used.")
            self.status = gui.add_markdown("")
            self.toggle = gui.add_button("Start drawing", icon=viser.Icon.PENCIL)
            self.undo = gui.add_button("Undo last point", icon=viser.Icon.ARROW_BACK_UP, disabled=True)
            self.delete = gui.add_button("Delete point", icon=viser.Icon.BACKSPACE, disabled=True,
                                         hint="Remove the selected point (click its handle to select it); "
                                              "keys: Delete, Backspace")
            self.close = gui.add_button("Close and use", icon=viser.Icon.CHECK, disabled=True,
                                        hint="Start a new world on this goal (step 0, the same seed); the points "
                                             "stay here to tweak")
            self.close_and_run = gui.add_button("Use and run to the end", icon=viser.Icon.PLAYER_SKIP_FORWARD,
                                                disabled=True,
                                                hint="Close and use, then Run to the end (to Run to step, in Run): "
                                                     "the answer without watching")
            self.edit = gui.add_button("Edit this goal", icon=viser.Icon.EDIT,
                                       hint="Bring the running goal back here as numbered points")
            self.clear = gui.add_button("Clear", icon=viser.Icon.TRASH, disabled=True)
            self.template = gui.add_dropdown("Template", (PICK_TEMPLATE, *template_names()),
                                             initial_value=PICK_TEMPLATE,
                                             hint="Start from a letter or a figure; its points stay editable")
            self.snap_on = gui.add_checkbox("Snap to grid", True, hint="New and moved points go to the nearest "
                                            "grid node")
            self.grid = gui.add_number("Grid (m)", DEFAULT_GRID, min=0.1, max=5.0, step=0.1,
                                       hint="Spacing of the snapping grid (turn Snap to grid on to use it)")
            self.typed = gui.add_text("Points", "", multiline=True, hint=FORMATS_HINT)
            self.apply = gui.add_button("Apply points", icon=viser.Icon.ARROW_RIGHT,
                                        hint="Replace the drawing with the points typed above")
            self.show_preview = gui.add_checkbox("Preview final size", True,
                                                 hint="Dashed: the goal as it will be built and its light band")
        # The Delete and Backspace keys (and viser's command palette, Ctrl+K): off while nothing is
        # selected, so the page does not take those keys then (and the server refuses them).
        self.delete_keys = [gui.add_command("Delete the selected point", hotkey=key, disabled=True,
                                            description=f"key: {key} (Goal shape, Draw)") for key in DELETE_KEYS]
        self.toggle.on_click(lambda event: self._set_drawing(not self.drawing))
        self.undo.on_click(lambda event: self._change(self.points[:-1]))
        self.delete.on_click(lambda event: self.delete_selected())
        for command in self.delete_keys:
            command.on_trigger(lambda event: self.delete_selected())
        self.clear.on_click(lambda event: self._change([]))
        self.close.on_click(self._close_and_use)
        self.close_and_run.on_click(lambda event: self._close_and_use(event, to_the_end=True))
        self.edit.on_click(lambda event: self.edit_running_goal())
        self.template.on_update(self._pick_template)
        self.apply.on_click(self._apply_typed)
        self.snap_on.on_update(lambda event: self._sync_controls())
        self.show_preview.on_update(lambda event: self._refresh())
        self._refresh()

    def update(self, snap: Snapshot) -> None:
        """A new world or new strategies change the preview's size: recompute it."""
        config = snap.world_config
        if config == self._preview_config:
            return
        self._centre = (config.centre, config.centre)
        self.view.set_arena(config.arena_size)
        self._refresh()

    # ------------------------------------------------------------ input
    @property
    def step(self) -> float:
        return float(self.grid.value) if self.snap_on.value else 0.0

    def click(self, point: Point, client: Any = None) -> bool:
        """A click on the floor by ``client``'s page (returns whether the drawing took it). On a point's
        handle: selects that point, drawing or not. While drawing, elsewhere: on an edge, inserts a
        point there between its two ends; anywhere else, adds the next point."""
        if self.given_way:
            return False  # the points are not on the floor: a click there is the inspector's
        scale = metres_per_pixel(client, point) if client is not None else None
        radius = self.view.handle_radius
        vertex = vertex_at(self.points, point, max(radius, PICK_PIXELS * scale) if scale else radius)
        if vertex is not None:
            self._select(vertex)
            return True
        if not self.drawing:
            return False
        edge = edge_at(self.points, point, EDGE_PIXELS * scale if scale else radius)
        if edge is not None and edge + 1 < len(self.points):
            self._insert(edge + 1, point)
        else:  # on the closing edge, the new point goes last all the same
            self._add(point)
        return True

    def delete_selected(self) -> None:
        """Remove the selected point (the Delete point button, the Delete and Backspace keys)."""
        if self.selected is None or not 0 <= self.selected < len(self.points):
            return
        self._change([p for k, p in enumerate(self.points) if k != self.selected])

    def pad_drag(self, phase: str, point: Point | None) -> None:
        """Press, drag and release on the floor while drawing: the next point where released."""
        if not self.drawing:
            return
        last = self.points[-1] if self.points else None
        if phase == "end":
            self.view.show_rubber(None, None)
            if point is not None:
                self._add(point)
        elif last is not None and point is not None:
            self.view.show_rubber(last, snap(point, self.step))

    def vertex_drag(self, index: int, phase: str, point: Point | None) -> None:
        """A numbered handle dragged: its vertex follows, snapped; the preview returns on release."""
        if not 0 <= index < len(self.points) or self.given_way:
            return
        if point is not None:
            moved = snap(point, self.step)
            if moved != self.points[index]:
                self.points[index] = moved
                self.view.show(self.points, crossing_edges(self.points), self.selected)
        if phase == "start":
            self.selected = index  # the dragged point is the selected one: Delete removes it
            self.view.show_preview(None)
            self.view.show(self.points, crossing_edges(self.points), self.selected)
            self._sync_controls()
        elif phase == "end":
            kept = without_repeats(self.points)
            self._change(kept, selected=index if len(kept) == len(self.points) else None)

    # ---------------------------------------------------------- actions
    def _add(self, point: Point) -> None:
        self._insert(len(self.points), point, select=False)

    def _insert(self, index: int, point: Point, select: bool = True) -> None:
        """A new point at ``index`` (snapped), selected unless it is the last one added by a click;
        nothing where a point already is."""
        p = snap(point, self.step)
        if self._on_a_vertex(p) or self._on_a_vertex(point):
            return
        self._change([*self.points[:index], p, *self.points[index:]], selected=index if select else None)

    def _select(self, index: int) -> None:
        self.selected = index
        self.view.show(self.points, crossing_edges(self.points), self.selected)
        self._sync_controls()

    def _on_a_vertex(self, p: Point) -> bool:
        r = self.view.handle_radius
        return any((p[0] - x) ** 2 + (p[1] - y) ** 2 < r * r for x, y in self.points)

    def _set_drawing(self, on: bool) -> None:
        self.drawing = on
        if on:
            self.given_way = False  # drawing again: the points come back to the floor
        self.view.set_pad(on)
        self._refresh()

    def give_way(self) -> None:
        """A goal is in use (this drawing's, or any other): the drawing leaves the floor so that the
        goal built, its edge and its boxes show; the points stay here for the next edit."""
        self.given_way, self.drawing, self.selected = True, False, None
        self.view.set_pad(False)
        self._refresh()

    def _close_and_use(self, event: viser.GuiEvent, to_the_end: bool = False) -> None:
        """*Close and use* (``to_the_end``: and then *Run to the end*)."""
        try:
            vertices = validate_polygon(self.points, SOURCE)
        except ShapeError as exc:
            notify_error(event.client, "Shape not used", str(exc))
            return
        run, client = self.run_to_the_end, event.client
        then = (lambda: run(client)) if to_the_end and run is not None else None
        self._use(vertices, "drawn", client, then=then)  # the drawing gives way once the goal is in use
        self.drawing = False  # the points stay: the goal can be tweaked and used again
        self.view.set_pad(False)
        self._refresh()

    def edit_running_goal(self) -> None:
        """The running goal as the drawing's points (the circle as its polygon), to tweak and use again."""
        snap = self.runner.latest
        vertices = snap.goal_vertices if snap.goal_vertices is not None else snap.goal_outline
        self._change(without_repeats([(round(float(x), 3), round(float(y), 3)) for x, y in vertices]))

    def _pick_template(self, event: viser.GuiEvent) -> None:
        name = self.template.value
        if event.client is None or name == PICK_TEMPLATE:
            return  # this panel putting the dropdown back, not a pick
        self._change([tuple(p) for p in placed(template_vertices(name), self._centre, self.step).tolist()])
        self.template.value = PICK_TEMPLATE  # so that the same template can be picked again

    def _apply_typed(self, event: viser.GuiEvent) -> None:
        try:
            points = parse_coordinates(self.typed.value)
        except ShapeError as exc:
            self._typed_error = str(exc)
            notify_error(event.client, "Points not applied", str(exc))
            self._sync_controls()
            return
        # Typed points are a shape in their own coordinates: shown where the goal will be built, at its
        # size (not snapped: they are what was asked).
        self._change(self._where_built(without_repeats(points)))

    def _where_built(self, points: list[Point]) -> list[Point]:
        """``points`` where the goal they make will be built: scaled to the goal's area (the boxes' total
        area), centred in the arena, and moved as the model moves a goal to lie inside the construction
        wall (issue 56, item 2: they were drawn 1.25 m off the goal built). Only centred while they are
        not yet a polygon; not moved when the goal cannot be built (the status line says why)."""
        if not points:
            return points
        try:
            validate_polygon(points, SOURCE)
        except ShapeError:
            return [tuple(p) for p in placed(np.asarray(points, float), self._centre).tolist()]
        config = self.runner.latest.world_config
        area = max(config.boxes, 1) * config.box_area  # the goal's area, as the model fits it (fit_goal)
        fitted = fit_to_area(np.asarray(points, float), area, np.asarray(self._centre, float))
        try:
            fitted = fitted + np.asarray(make_goal(config, fitted).moved, float)
        except ShapeError:
            pass  # refused when used: shown centred, with the reason under the buttons
        return [(round(float(x), 3), round(float(y), 3)) for x, y in fitted]

    def _change(self, points: list[Point], selected: int | None = None) -> None:
        """The drawing is now ``points``, with point ``selected`` selected (None: none): redraw,
        re-check, re-preview, and show them as text."""
        self.points = list(points)
        self.given_way = False  # an edit: the drawing is back on the floor
        self.selected = selected if selected is not None and 0 <= selected < len(self.points) else None
        self._typed_error = ""
        self._refresh()
        self.typed.value = format_coordinates(self.points)

    # ---------------------------------------------------------- display
    def _refresh(self) -> None:
        crossings = crossing_edges(self.points)
        n = len(self.points)
        self._red = [edge_name(e, n) for e in sorted({e for pair in crossings for e in pair})]
        self._problem, self._preview = self._check()
        if self.given_way:
            self.view.show([], [])
        else:
            self.view.show(self.points, crossings, self.selected)
        if self._preview is not None and self.show_preview.value and not self.given_way:
            self.view.show_preview(self._preview.goal, self._preview.smallest, self._preview.largest)
        else:
            self.view.show_preview(None)
        self._sync_controls()

    def _check(self) -> tuple[str, GoalPreview | None]:
        """Why the drawing cannot be used ('' if it can), and its preview when it can."""
        self._preview_config = config = self.runner.latest.world_config
        if len(self.points) < 3:
            return "", None
        try:
            vertices = validate_polygon(self.points, SOURCE)
            return "", preview_goal(config, vertices, config.flare)
        except ShapeError as exc:
            return without_source(str(exc)), None

    def _sync_controls(self) -> None:
        n = len(self.points)
        self.toggle.label = "Stop drawing" if self.drawing else "Start drawing"
        self.undo.disabled = self.clear.disabled = n == 0
        nothing_selected = self.selected is None
        if self.delete.disabled != nothing_selected:
            self.delete.disabled = nothing_selected
            for command in self.delete_keys:
                command.disabled = nothing_selected
        self.close.disabled = n < 3 or bool(self._problem)
        self.close_and_run.disabled = self.close.disabled or self.run_to_the_end is None
        self.grid.disabled = not self.snap_on.value
        self.status.content = status_text(n, self.drawing, self._problem, self._preview, self._typed_error,
                                          self._red, self.selected, self.given_way)
