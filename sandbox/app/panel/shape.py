"""The Goal shape folder: pick a built-in shape, draw one on the floor (its
Draw sub-folder is :mod:`.draw`), upload or download a polygon file. Every
shape goes through the model's loader and validation; a refused one leaves
the running simulation alone. Runs on the app's event thread.

Runs on the app's event thread; an upload is read in a worker, which posts
what it read back."""

from __future__ import annotations

import logging
import re
import threading
from pathlib import Path
from typing import Any, Callable

import viser

from sandbox.app.web import viser_seam
from sandbox.app.panel.common import notify, notify_error
from sandbox.app.panel.draw import DrawFolder
from sandbox.app.world.orders import SetProgram, SetShape
from sandbox.app.world.snapshot import DESIGN_PROGRAM, Snapshot
from sandbox.model.design import MAX_NAME_CHARS
from sandbox.model.goal import fit_goal
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
#: Longest file name shown and kept for an uploaded shape (its extension is kept whole): the longest goal
#: name a design holds, so that the goal it names can be downloaded as a design and opened again.
NAME_LIMIT = MAX_NAME_CHARS
#: What a file name may not hold: control characters (a NUL among them) and halves of surrogate pairs.
_UNPRINTABLE = re.compile(r"[\x00-\x1f\x7f-\x9f\ud800-\udfff]")

log = logging.getLogger("sandbox.app.panel.shape")


class ShapeFolder:
    def __init__(self, gui: Any, runner: Any, scene: Any, *, events: Any,
                 on_change: Callable[..., None] = lambda what, *a: None, reset: Callable[..., None] | None = None,
                 back_to_defaults: Callable[[Any], None] = lambda client: None,
                 run_to_the_end: Callable[[Any], None] | None = None):
        """``events``: the app's event queue (:mod:`sandbox.app.web.events`; an upload is read aside, and
        its result comes back there). ``reset(client, on_done=..., on_error=...)``: a new world with the
        same seed (the Run folder's, which resets a compared world too); a goal used starts afresh with
        it. ``back_to_defaults(client)``: the outline and strategies back to their defaults, shown and
        applied (the Strategies folder's). ``run_to_the_end(client)``: the Draw folder's *Use and run to
        the end* (None: not offered)."""
        self.gui, self.runner = gui, runner
        self._events = events
        self._on_change = on_change
        self._reset = reset
        self.back_to_defaults = back_to_defaults
        self.draw = DrawFolder(gui, runner, scene, use=self.use, run_to_the_end=run_to_the_end)
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
            self.keep = gui.add_checkbox("Keep outline and strategies", False,
                                         hint="A new goal starts afresh at step 0 with the same seed; off, the "
                                              "outline goes back to auto and the strategies off")
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
        def _(event: viser_seam.UploadEvent) -> None:
            uploaded = event.file  # this page's file: the button's value is one for every page
            self.take_upload(uploaded.name or "upload.txt", uploaded.content, event.client)

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

    def take_upload(self, filename: Any, content: bytes, client: Any) -> None:
        """An uploaded polygon file: read aside (in a thread that waits for the reader's process, up to its
        time limit), then used or refused on the event thread; nothing waits for it meanwhile."""
        name = upload_name(filename)
        config = self.runner.latest.world_config  # the goal is fitted to the running world, as the simulation will

        def read() -> None:
            self._events.post(self._take_read, name, self._read(name, content, config), client)

        threading.Thread(target=read, name="upload-reader", daemon=True).start()

    def use_shape_file(self, filename: Any, content: bytes, client: Any) -> bool:
        """Validate an uploaded polygon file with the model's loader, in a process of its own (a slow
        file must not stall anyone's scene); use it or say why not, on the event thread. Every refusal is
        told to the page. Waits for the reader and the event: call it off the event thread (the tests do;
        a page's upload goes through :meth:`take_upload`)."""
        name = upload_name(filename)
        read = self._read(name, content, self.runner.latest.world_config)
        return self._events.call(self._take_read, name, read, client)

    @staticmethod
    def _read(name: str, content: bytes, config: Any = None) -> tuple[Any, str]:
        """(vertices, '') or (None, why not). With ``config``, the goal is also fitted as the simulation will
        fit it, here, before the simulation hears of it: a goal with more vertices than the outlines afford
        even simplified, or too costly for the memory budget, is refused by the server."""
        try:
            vertices = read_polygon_isolated(bytes(content), name)
        except ShapeError as exc:
            return None, str(exc)
        except Exception as exc:  # noqa: BLE001 - whatever happened, the page hears of it and the run goes on
            log.exception("upload %r could not be read", name)
            return None, f"{name}: could not be read ({type(exc).__name__})"
        try:
            if config is not None:
                fit_goal(config, vertices)
        except ShapeError as exc:
            return None, f"{name}: {exc}"
        return vertices, ""

    def _take_read(self, name: str, read: tuple[Any, str], client: Any) -> bool:
        vertices, problem = read
        if problem:
            notify_error(client, UPLOAD_REFUSED, problem)
            return False
        self.use(vertices, name, client)
        return True

    def use(self, vertices, name: str, client: Any, announce: bool = True, quiet: bool = False,
            then: Callable[[], None] | None = None) -> None:
        """Use a goal: a new world on it from step 0 with the same seed, the outline and strategies back
        to their defaults unless *Keep outline and strategies* is on. The simulation may still refuse a
        goal that does not fit the arena: then the running world goes on as it was. ``quiet``: part of
        another action (a paper case), which sets the strategies, starts the world and says what it did.
        ``then``: what to do once the new world has started (not if the goal was refused)."""

        def refused(exc: BaseException) -> None:
            notify_error(client, "Shape not used", str(exc))
            running = self.runner.latest.shape_name
            self._shown = running if running in self.shape.options else CUSTOM_SHAPE
            self.shape.value = self._shown  # the dropdown goes back to what runs

        if quiet:
            self.runner.ask(SetShape(vertices, name), on_done=lambda notes: self.draw.give_way(), on_error=refused)
            return
        keep = bool(self.keep.value)
        # A design's recorded lights were made for its own goal: a new goal hands the floor back to the paper.
        handed_back = self.runner.latest.program == DESIGN_PROGRAM

        def fitted(notes: list[str]) -> None:  # the goal fits: start it afresh
            if handed_back:
                self.runner.ask(SetProgram(None))
                notes = [*notes, "the design's recorded lights handed back to the paper's controller"]
            if not keep:
                self.back_to_defaults(client)
            if self._reset is None:
                started(notes)
            else:
                self._reset(client, on_done=lambda _: started(notes))

        def started(notes: list[str]) -> None:
            self._on_change(f"shape {name}", 0)  # the first step of the new world
            self.draw.give_way()  # the drawing leaves the goal built to be seen
            # One notice for the action: what is used, how it started, then what to know about it.
            what = f"Using {name}" + ("" if vertices is None else f" ({len(vertices)} vertices)")
            if self._reset is not None:
                what += f", from step 0 with seed {self.runner.latest.seed}"
            said = [what, "Outline and strategies kept" if keep else "Outline back to auto, strategies off"]
            said += [note[0].upper() + note[1:] for note in notes]
            notify(client, "Goal changed" if announce else "About this goal", ". ".join(said) + ".",
                   "green" if announce else "blue")
            if then is not None:
                then()

        self.runner.ask(SetShape(vertices, name), on_done=fitted, on_error=refused)

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
