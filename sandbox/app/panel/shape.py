"""The Goal shape folder: pick a built-in shape, draw one on the floor (its
Draw sub-folder is :mod:`.draw`), upload or download a polygon file. Every
shape goes through the model's loader and validation; a refused one leaves
the running simulation alone."""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any, Callable

import viser

from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.draw import DrawFolder
from sandbox.app.snapshot import Snapshot
from sandbox.shapes import (
    ShapeError,
    builtin_shape_names,
    polygon_to_text,
    shape_vertices,
)
from sandbox.shapes.formats import EXTENSIONS
from sandbox.shapes.isolated import read_polygon_isolated

CUSTOM_SHAPE = "(drawn or uploaded)"
#: The title of a refused upload: viser's own notice beside it says the file arrived, which it did.
UPLOAD_REFUSED = "File received, shape not used"
#: Longest file name shown and kept for an uploaded shape (its extension is kept whole).
NAME_LIMIT = 80
#: What a file name may not hold: control characters (a NUL among them) and halves of surrogate pairs.
_UNPRINTABLE = re.compile(r"[\x00-\x1f\x7f-\x9f\ud800-\udfff]")

log = logging.getLogger("sandbox.app.panel.shape")


class ShapeFolder:
    def __init__(self, gui: Any, runner: Any, scene: Any, on_change: Callable[[str], None] = lambda what: None):
        self.gui, self.runner = gui, runner
        self._on_change = on_change
        self.draw = DrawFolder(gui, runner, scene, use=self.use)
        #: What this panel last put in the dropdown: if it shows something else, a viewer picked it.
        self._shown: str | None = None

    def build(self, snap: Snapshot) -> None:
        gui = self.gui
        # A drawn or uploaded goal shows as CUSTOM_SHAPE, so picking a
        # built-in shape afterwards is always a change.
        names = [*builtin_shape_names(), CUSTOM_SHAPE]
        current = snap.shape_name if snap.shape_name in names else CUSTOM_SHAPE
        self._shown = current
        with gui.add_folder("Goal shape"):
            self.shape = gui.add_dropdown("Shape", tuple(names), initial_value=current,
                                          hint="circle, or a polygon file from shapes/")
            self.draw.build(snap)
            # The file chooser offers polygon files first; viser's own notice then says the bytes arrived,
            # and ours whether the shape is used.
            self.upload = gui.add_upload_button(
                "Upload polygon file", icon=viser.Icon.UPLOAD, mime_type=",".join(sorted(EXTENSIONS)),
                hint="Plain text x y per line, GeoJSON, WKT, JSON [[x, y], ...] or SVG; at most 1 MB")
            self.download_shape = gui.add_button("Download shape", icon=viser.Icon.DOWNLOAD,
                                                 hint="The current goal as a polygon file for --shape")

        @self.shape.on_update
        def _(event: viser.GuiEvent) -> None:
            name = self.shape.value
            if event.client is None:
                return  # this panel showing the running shape, not a pick
            if name == self.runner.latest.shape_name or name not in builtin_shape_names():
                return
            try:
                vertices = shape_vertices(name)
            except ShapeError as exc:
                notify_error(event.client, "Shape not used", str(exc))
                return
            self.use(vertices, name, event.client, announce=False)

        @self.upload.on_upload
        def _(event: viser.GuiEvent) -> None:
            uploaded = self.upload.value
            self.use_shape_file(uploaded.name or "upload.txt", uploaded.content, event.client)

        @self.download_shape.on_click
        def _(event: viser.GuiEvent) -> None:
            snap = self.runner.latest
            name = snap.shape_name or "shape"
            vertices = snap.goal_vertices if snap.goal_vertices is not None else snap.goal_outline
            comment = (f"phototaxis goal shape '{name}' in arena coordinates (metres)\n"
                       "use with: phototaxis --shape FILE")
            if snap.goal_vertices is None:
                comment += f"\nthe circle, as a {len(vertices)}-gon"
            text = polygon_to_text(vertices, comment)
            stem = Path(name).stem.replace(" ", "-") or "shape"
            event.client.send_file_download(f"{stem}.txt", text.encode("utf-8"), save_immediately=True)

    def update(self, snap: Snapshot) -> None:
        """Show the running shape, but never over a viewer's pick on its way to the simulation."""
        self.draw.update(snap)
        shown = snap.shape_name if snap.shape_name in self.shape.options else CUSTOM_SHAPE
        if self.shape.value == shown:
            self._shown = shown
        elif self.shape.value == self._shown:  # still what we showed: the goal changed elsewhere
            self._shown = shown
            self.shape.value = shown

    def use_shape_file(self, filename: Any, content: bytes, client: Any) -> bool:
        """Validate an uploaded polygon file with the model's loader, in a process of its own (a slow
        file must not stall anyone's scene); use it or say why not. Every refusal is told to the page."""
        name = upload_name(filename)
        try:
            vertices = read_polygon_isolated(bytes(content), name)
        except ShapeError as exc:
            notify_error(client, UPLOAD_REFUSED, str(exc))
            return False
        except Exception as exc:  # noqa: BLE001 - whatever happened, the page hears of it and the run goes on
            log.exception("upload %r could not be read", name)
            notify_error(client, UPLOAD_REFUSED, f"{name}: could not be read ({type(exc).__name__})")
            return False
        self.use(vertices, name, client)
        return True

    def use(self, vertices, name: str, client: Any, announce: bool = True, quiet: bool = False) -> None:
        """Hand the goal to the simulation; it may still refuse one that does not fit the arena.
        ``quiet``: part of another action (a paper case), which says what it did itself."""

        def used(notes: list[str]) -> None:
            if quiet:
                return
            self._on_change(f"shape {name}")
            # One notice for the action: what is used, then what to know about it.
            said = [f"Using {name}" + ("" if vertices is None else f" ({len(vertices)} vertices)")] if announce else []
            said += [note[0].upper() + note[1:] for note in notes]
            if said:
                notify(client, "Goal changed" if announce else "About this goal", ". ".join(said) + ".",
                       "green" if announce else "blue")

        def refused(exc: BaseException) -> None:
            notify_error(client, "Shape not used", str(exc))
            running = self.runner.latest.shape_name
            self._shown = running if running in self.shape.options else CUSTOM_SHAPE
            self.shape.value = self._shown  # the dropdown goes back to what runs

        self.runner.set_shape(vertices, name, on_done=used, on_error=refused)

    def click(self, point: tuple[float, float]) -> bool:
        """A click on the floor: a new point while drawing (returns whether it was taken)."""
        return self.draw.click(point)

    # What tests and the security checks reach for, from before the Draw folder had its own module.
    draw_points = property(lambda self: self.draw.points)
    drawing = property(lambda self: self.draw.drawing)
    draw_close = property(lambda self: self.draw.close)


def upload_name(filename: Any) -> str:
    """A page's name for its file, fit to show and to name the shape: the last part of a path only,
    no control characters, at most NAME_LIMIT characters with the extension (which gives the format)
    kept; "upload.txt" when nothing is left."""
    name = _UNPRINTABLE.sub("?", str(filename or "")).replace("\\", "/").rsplit("/", 1)[-1].strip()
    if len(name) > NAME_LIMIT:
        suffix = Path(name).suffix[:12]
        name = name[:NAME_LIMIT - len(suffix) - 3] + "..." + suffix
    return name if name not in ("", ".", "..") else "upload.txt"
