"""The teacher's wall: the Class folder of the teacher's panel, every student's world at once.
Built on the main thread with the panel; refreshed on the app's event thread, once a second.

The wall is one picture: a small picture of each student's floor (their construction area, drawn on
the server with numpy and Pillow, again only when their world moved) under
their label, step and share in the goal, three to a row, in the order the teacher chooses; sent as one
JPEG about once a second. Under it, a student picked by name goes *on the projector* (the teacher's floor
shows that world, live) or is sent the scene; the scene (the teacher's world or a paper case) goes to
everyone; the class challenge starts the same round for everyone, ranked here. The folder is in the
shared GUI, which a student's page is never sent (:mod:`sandbox.app.web.gate`).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import viser
from PIL import Image, ImageDraw, ImageFont

from sandbox.app.panel.plain import plain
from sandbox.app.view import palette as pal
from sandbox.app.view.scene import CONSTRUCTION_VIEW

#: Side of a student's picture (pixels), the band of text under it, the pictures to a row, and the JPEG
#: quality: the wall of 30 students is 400 x 1,720 pixels, about 60 KB a second to the teacher's page.
THUMBNAIL = 128
CAPTION = 34
COLUMNS = 3
GAP = 8
JPEG_QUALITY = 70
SORTS = ("arrival", "name", "share in the goal", "step")
NOBODY = "(no student yet)"


class Wall:
    """The Class folder (see the module docstring) for ``classroom``'s seats; ``scenes``: the names of
    the scenes the teacher may send."""

    def __init__(self, gui: Any, classroom: Any, scenes: tuple[str, ...]):
        self.gui, self.classroom = gui, classroom
        #: Each seat's picture, with the (world, step) it shows: drawn again only when its world moved.
        self._pictures: dict[str, tuple[tuple, Image.Image]] = {}
        #: The labels on the wall, in the order shown (what the teacher sees).
        self.shown: list[str] = []
        self._drawn_key: tuple | None = None
        self._captions = Captions()
        with gui.add_folder("Class", order=-1.0) as self.folder:
            self.link = gui.add_markdown(self._link_text(0))
            self.sort = gui.add_dropdown("Sort by", SORTS, initial_value=SORTS[0])
            self.picture = gui.add_image(np.zeros((THUMBNAIL // 2, _width(), 3), np.uint8), format="jpeg",
                                         jpeg_quality=JPEG_QUALITY)
            self.student = gui.add_dropdown("Student", (NOBODY,), initial_value=NOBODY)
            self.project = gui.add_button("Show on the projector", icon=viser.Icon.PRESENTATION, disabled=True,
                                          hint="Your floor shows this student's world, live")
            self.send_one = gui.add_button("Send the scene to this student", icon=viser.Icon.SEND, disabled=True)
            self.projector = gui.add_markdown("On the projector: **your world**")
            self.back = gui.add_button("Back to my world", icon=viser.Icon.ARROW_BACK, visible=False)
            self.scene = gui.add_dropdown("Scene to send", scenes, initial_value=scenes[0],
                                          hint="A paper case over your settings, or your world as it is now")
            self.send_all = gui.add_button("Send to everyone", icon=viser.Icon.USERS)
            self.challenge = gui.add_button("Start a class challenge", icon=viser.Icon.FLAG,
                                            hint="The same round for every student: the paper's seed, the "
                                                 "same steps; their scores ranked here")
            self.ranking = gui.add_markdown("")
        self.sort.on_update(lambda event: self.refresh())
        self.project.on_click(lambda event: classroom.project(self._picked()))
        self.send_one.on_click(lambda event: self._send([self._picked()], event.client))
        self.send_all.on_click(lambda event: self._send(None, event.client))
        self.challenge.on_click(lambda event: self._challenge(event.client))
        self.back.on_click(lambda event: classroom.project(None))

    # ------------------------------------------------------------ refresh
    def refresh(self) -> None:
        """The wall afresh (each student's picture only when their world moved), in the order chosen."""
        classroom = self.classroom
        seats = [seat for seat in classroom.seats.all() if seat.identity in classroom.worlds]
        snaps = {seat.identity: classroom.worlds[seat.identity].runner.latest for seat in seats}
        ordered = sort_seats(seats, snaps, self.sort.value)
        labels = [seat.label for seat in ordered]
        key = tuple((seat.identity, snaps[seat.identity].world_key, snaps[seat.identity].step,
                     seat.identity in classroom.page_of) for seat in ordered)
        if key != self._drawn_key and ordered:
            self._drawn_key = key
            self.picture.image = np.asarray(self._wall(ordered, snaps))
        self.shown = labels
        options = tuple(seat.label for seat in seats) or (NOBODY,)
        if tuple(self.student.options) != options:
            self.student.options = options
        self.project.disabled = self.send_one.disabled = not seats
        self.link.content = self._link_text(len(seats))
        projected = classroom.seats.get(classroom.projected) if classroom.projected else None
        self.projector.content = f"On the projector: **{plain(projected.label) if projected else 'your world'}**"
        self.back.visible = projected is not None
        if classroom.entrants:
            self.ranking.content = ranking_text(classroom.challenge_results())

    def _wall(self, ordered: list, snaps: dict) -> Image.Image:
        rows = (len(ordered) + COLUMNS - 1) // COLUMNS
        cell = THUMBNAIL + CAPTION
        wall = Image.new("RGB", (_width(), rows * (cell + GAP) - GAP), pal.BACKGROUND)
        for index, seat in enumerate(ordered):
            snap = snaps[seat.identity]
            x, y = (index % COLUMNS) * (THUMBNAIL + GAP), (index // COLUMNS) * (cell + GAP)
            wall.paste(self._picture_of(seat.identity, snap), (x, y))
            share = 100.0 * float(snap.sample.fraction_in_goal)
            away = "" if seat.identity in self.classroom.page_of else " (away)"
            self._captions.write(wall, (x + 2, y + THUMBNAIL + 3), f"{seat.label}{away}"[:22], (235, 235, 240))
            self._captions.write(wall, (x + 2, y + THUMBNAIL + 18),
                                 f"{share:.0f} % in goal, step {snap.step:,}"[:24], (170, 175, 185))
        return wall

    def _picture_of(self, identity: str, snap: Any) -> Image.Image:
        moved = (snap.world_key, snap.step)
        kept = self._pictures.get(identity)
        if kept is None or kept[0] != moved:
            kept = self._pictures[identity] = (moved, floor_picture(snap))
        return kept[1]

    def _link_text(self, count: int) -> str:
        link = self.classroom.students_link(self.classroom.app.url)
        noun = "student" if count == 1 else "students"
        return f"Students open **{plain(link)}**: each gets a world of their own. {count:,} {noun} so far."

    # ------------------------------------------------------------ actions
    def _picked(self) -> str | None:
        label = self.student.value
        return next((seat.identity for seat in self.classroom.seats.all() if seat.label == label), None)

    def _send(self, identities: list | None, client: Any) -> None:
        name = str(self.scene.value)
        scene = self.classroom.scene_named(name)
        sent = self.classroom.send(scene, None if identities is None else [i for i in identities if i])
        if client is not None:
            client.add_notification("Scene sent", f"{name} to {len(sent)} student"
                                    f"{'' if len(sent) == 1 else 's'}.", color="blue", auto_close_seconds=5.0)

    def _challenge(self, client: Any) -> None:
        entrants = self.classroom.start_challenge()
        self.ranking.content = ranking_text(self.classroom.challenge_results()) if entrants else \
            "No student has a page open: nobody to play."


class Captions:
    """The wall's lines of text, each written as ``ImageDraw.text`` writes it (the same pixels), but each
    line's shape rendered once: a student's name comes back every second, and the font is loaded once
    (it was loaded at each refresh; the caption lines were the largest part of the wall in py-spy's
    samples of the class server). A refresh of 30 students, every picture and read-out new: 35 ms of
    CPU before, 25 after."""

    #: Lines kept (a class's names, with and without "(away)", and the last second's read-outs).
    KEPT = 256

    def __init__(self, size: int = 12):
        self.size = size
        self._font: Any = None
        self._shapes: dict[str, tuple[Image.Image | None, tuple[int, int]]] = {}
        self.rendered = 0  # lines rendered (not found kept): for the tests

    def write(self, image: Image.Image, xy: tuple[int, int], text: str, fill: tuple[int, int, int]) -> None:
        """``text`` in ``fill`` with its origin at ``xy`` (whole pixels), as ``ImageDraw.text`` would."""
        shape, (dx, dy) = self._shape(text)
        if shape is not None:
            x, y = xy[0] + dx, xy[1] + dy
            image.paste(fill, (x, y, x + shape.size[0], y + shape.size[1]), shape)

    def _shape(self, text: str) -> tuple[Image.Image | None, tuple[int, int]]:
        kept = self._shapes.pop(text, None)  # (taken out and put back: the dict's order is the most recent)
        if kept is None:
            if self._font is None:
                self._font = ImageFont.load_default(size=self.size)
            mask, offset = self._font.getmask2(text, "L")
            shown = mask.size[0] > 0 and mask.size[1] > 0
            kept = (Image.frombytes("L", mask.size, bytes(mask)) if shown else None, offset)
            self.rendered += 1
            if len(self._shapes) >= self.KEPT:
                del self._shapes[next(iter(self._shapes))]  # the line least recently written
        self._shapes[text] = kept
        return kept


def sort_seats(seats: list, snaps: dict, how: str) -> list:
    """The seats in the order the teacher chose: arrival, name, share in the goal (most first), step."""
    if how == "name":
        return sorted(seats, key=lambda seat: seat.label.lower())
    if how == "share in the goal":
        return sorted(seats, key=lambda seat: (-float(snaps[seat.identity].sample.fraction_in_goal), seat.number))
    if how == "step":
        return sorted(seats, key=lambda seat: (-int(snaps[seat.identity].step), seat.number))
    return sorted(seats, key=lambda seat: seat.number)


def ranking_text(rows: list) -> str:
    """The class challenge's ranking, one line a student, best first."""
    lines = ["**Class challenge**"]
    for place, (label, score, doing) in enumerate(rows, 1):
        if score is None:
            lines.append(f"- {plain(label)}: {plain(doing)}")
        else:
            noun = "box" if abs(score.brought) == 1 else "boxes"
            lines.append(f"{place:d}. **{plain(label)}**: {score.brought:,} {noun} brought in "
                         f"({100 * score.share:.0f} %)")
    return "\n".join(lines)


def floor_picture(snap: Any, size: int = THUMBNAIL) -> Image.Image:
    """The construction area (where the boxes are built) and a margin, ``size`` pixels a side, in the
    page's colours: the lights as flat cells, each body a dot, the goal, the outline the lights follow
    and the wall that stops boxes as lines. Drawn with numpy (about 1 ms for the default world, where
    :func:`sandbox.app.view.frames.render` and a crop took 100 ms: 500 hexagons): a wall of 30 is
    drawn within the second it shows."""
    cfg = snap.world_config
    side = min(cfg.arena_size, cfg.construction_size * CONSTRUCTION_VIEW)
    x0 = y0 = float(np.clip(cfg.centre - side / 2, 0.0, cfg.arena_size - side))
    k = size / side  # pixels per metre
    ix, iy = _light_cells(cfg.arena_size, int(cfg.lights_per_side), x0, y0, side, size)
    peak = max(float(cfg.light_intensity), 1e-9)
    # Each light's colour once, then each pixel its light's (the same bytes as each pixel's colour worked
    # out from its light's level: the same arithmetic, done for 576 lights instead of 16,384 pixels).
    level = np.clip(np.asarray(snap.intensities, float) / peak, 0.0, 1.0)
    off, on = np.array(pal.LIGHT_OFF, float), np.array(pal.LIGHT_ON, float)
    colours = (off + level[..., None] * (on - off)).astype(np.uint8)
    img = colours[ix[None, :], iy[:, None]]
    in_goal = np.asarray(snap.box_in_goal, bool)
    box_colours = np.where(in_goal[:, None], np.array(pal.BOX_IN, np.uint8), np.array(pal.BOX_OUT, np.uint8))
    _dots(img, snap.box_positions, box_colours, x0, y0 + side, k, cfg.box_circumradius)
    _dots(img, snap.robot_positions, pal.robot_colours(snap.robot_charges, cfg.capacity), x0, y0 + side, k,
          cfg.robot_radius)
    picture = Image.fromarray(img)
    draw = ImageDraw.Draw(picture)

    def xy(points: Any) -> list[float]:
        p = np.asarray(points, float).reshape(-1, 2)
        return np.column_stack(((p[:, 0] - x0) * k, (y0 + side - p[:, 1]) * k)).ravel().tolist()

    draw.polygon(xy(pal.square(cfg.centre, cfg.construction_size / 2.0)), outline=pal.BOX_WALL)
    if len(snap.outline) >= 2:
        draw.polygon(xy(snap.outline), outline=pal.LIGHT_LINE)
    if len(snap.goal_outline) >= 2:
        draw.polygon(xy(snap.goal_outline), outline=pal.GOAL_LINE)
    return picture


@functools.lru_cache(maxsize=8)
def _light_cells(arena: float, lights: int, x0: float, y0: float, side: float, size: int) -> tuple:
    """Which light each column (``ix``) and each row (``iy``, row 0 at the top) of a picture lies in: the
    same for every picture of a class's worlds at one size of arena, worked out once."""
    k = size / side
    cell = arena / lights
    centres = (np.arange(size) + 0.5) / k
    ix = np.clip(((x0 + centres) / cell).astype(int), 0, lights - 1)
    iy = np.clip(((y0 + side - centres) / cell).astype(int), 0, lights - 1)
    return ix, iy


def _dots(img: np.ndarray, positions: Any, colours: Any, left: float, top: float, k: float, radius: float) -> None:
    """Each body a square dot of its colour, about its size (at least a pixel), where it lies in ``img``."""
    size = img.shape[0]
    p = np.asarray(positions, float).reshape(-1, 2)
    colours = np.broadcast_to(np.asarray(colours, np.uint8), (len(p), 3))
    u = ((p[:, 0] - left) * k).astype(int)
    v = ((top - p[:, 1]) * k).astype(int)
    reach = max(0, int(round(radius * k)) - 1)
    for du in range(-reach, reach + 1):
        for dv in range(-reach, reach + 1):
            uu, vv = u + du, v + dv
            inside = (uu >= 0) & (uu < size) & (vv >= 0) & (vv < size)
            img[vv[inside], uu[inside]] = colours[inside]


def _width() -> int:
    return COLUMNS * THUMBNAIL + (COLUMNS - 1) * GAP
